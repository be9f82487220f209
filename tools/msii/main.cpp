/// @file main.cpp
/// @brief The `msii` program: Multi-Scale Integral Invariants for 3D scans.
/// Every failure ends in one line "msii: error: ..." on stderr and a non-zero exit:
/// 2 for wrong usage, 1 for anything else.
#include "commands.h"

#include <msii/core/errors.h>
#include <msii/core/version.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#ifdef __GLIBC__
#include <malloc.h>
#endif

int main(int argc, char** argv)
{
#ifdef __GLIBC__
    // glibc raises its threshold for mapping a block of its own with each large block freed,
    // so that later blocks of a few megabytes come from the threads' heaps, which keep what
    // is freed: the same run's peak memory varied by a tenth (the benchmark's 1.1M tablet:
    // 1,681 to 1,871 MiB in 14 runs). A fixed threshold of 1 MiB returns every such block
    // when it is freed: 1,634 to 1,662 MiB in 8 runs, for about 2 % more time.
    mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
    CLI::App app{"msii: Multi-Scale Integral Invariants (volume, sphere area, patch area, line "
                 "length) per vertex of triangle meshes: 3D scans of tablets, seals, inscriptions "
                 "and terrain; metrics of the feature vectors, 1-ring smoothing, EXR feature maps, pictures, components and outlines."};
    app.set_version_flag("--version", std::string("msii ") + msii::versionString());
    app.require_subcommand(1);
    auto runCompute = msii::tools::addComputeCommand(app);
    auto runMetric = msii::tools::addMetricCommand(app);
    auto runSmooth = msii::tools::addSmoothCommand(app);
    auto runMap = msii::tools::addMapCommand(app);
    auto runRender = msii::tools::addRenderCommand(app);
    auto runSegment = msii::tools::addSegmentCommand(app);
    auto runOutline = msii::tools::addOutlineCommand(app);
    auto runMerge = msii::tools::addMergeCommand(app);
    auto runView = msii::tools::addViewCommand(app);
    auto runAxis = msii::tools::addAxisCommand(app);
    auto runProfile = msii::tools::addProfileCommand(app);
    auto runUnroll = msii::tools::addUnrollCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --help-all, --version
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "msii: error: " << msii::printableLine(e.what()) << " (see msii --help)\n";
        return 2;
    }
    try {
        int status = 2;
        if (app.got_subcommand("compute")) status = runCompute();
        else if (app.got_subcommand("metric")) status = runMetric();
        else if (app.got_subcommand("smooth")) status = runSmooth();
        else if (app.got_subcommand("map")) status = runMap();
        else if (app.got_subcommand("render")) status = runRender();
        else if (app.got_subcommand("segment")) status = runSegment();
        else if (app.got_subcommand("outline")) status = runOutline();
        else if (app.got_subcommand("merge")) status = runMerge();
        else if (app.got_subcommand("view")) status = runView();
        else if (app.got_subcommand("axis")) status = runAxis();
        else if (app.got_subcommand("profile")) status = runProfile();
        else if (app.got_subcommand("unroll")) status = runUnroll();
        // The command's files are written, closed and renamed. What is left at exit is the
        // libraries' teardown (PROJ closing its database, GDAL its drivers, TBB its threads):
        // about 5 ms of a 0.3 s run on a 1000 x 1000 DEM, which the system reclaims anyway.
        std::cout.flush();
        std::cerr.flush();
        std::fflush(nullptr);
        std::_Exit(status);
    } catch (const std::bad_alloc&) {
        std::cerr << "msii: error: out of memory (try a larger --voxel-size)\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "msii: error: " << msii::printableLine(e.what()) << '\n';
        return 1;
    }
}
