// Reads a mesh, computes V̂ at 16 radii for every vertex and writes them as CSV, one row per
// vertex: the smallest program on msii's library (docs/library.md). It runs the pipeline of
// `msii compute` (msii::compute: mesh preparation, the invariants, the values mapped back
// to the file's vertices), so a scan with duplicate faces or holes gets the same values here
// as from the command line and Python.
//   volume_csv MESH RADIUS OUT.csv
#include <msii/msii.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>

int main(int argc, char** argv)
{
    if (argc != 4) {
        std::fprintf(stderr, "usage: volume_csv MESH RADIUS OUT.csv\n");
        return 2;
    }
    try {
        const msii::TriMesh mesh = msii::readMesh(argv[1]).mesh;
        msii::ComputeOptions options;
        options.invariants.radius = std::atof(argv[2]);
        options.invariants.scales = 16;
        options.invariants.select(msii::parseInvariantList("V"));
        const msii::ComputeResult result = msii::compute(mesh, options);
        for (const msii::Diagnostic& d : result.diagnostics)  // what was repaired or filled
            std::fprintf(stderr, "volume_csv: warning: %s\n", d.message.c_str());

        std::ofstream csv(argv[3]);
        csv << std::setprecision(9);  // enough digits that each float reads back as itself
        csv << "vertex";
        for (double r : result.plan.radii) csv << ",V_r" << r;
        csv << '\n';
        for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
            csv << i;
            for (const auto& column : result.features[msii::Invariant::Volume]) csv << ',' << column[i];  // NaN: masked
            csv << '\n';
        }
        std::fprintf(stderr, "%zu vertices, %zu radii -> %s\n", mesh.numVertices(), result.plan.radii.size(), argv[3]);
        return csv ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "volume_csv: error: %s\n", e.what());
        return 1;
    }
}
