// Reads a mesh, computes V̂ at 16 radii for every vertex and writes them as CSV, one row per
// vertex: the smallest program on msii's library (docs/library.md).
//   volume_csv MESH RADIUS OUT.csv
#include <msii/msii.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

int main(int argc, char** argv)
{
    if (argc != 4) {
        std::fprintf(stderr, "usage: volume_csv MESH RADIUS OUT.csv\n");
        return 2;
    }
    try {
        const msii::TriMesh mesh = msii::readMesh(argv[1]).mesh;
        msii::InvariantsOptions options;
        options.radius = std::atof(argv[2]);
        options.scales = 16;
        options.computeSphere = options.computePatch = options.computeLine = false;  // V only
        const msii::InvariantsResult result = msii::computeInvariants(mesh, options);

        std::ofstream csv(argv[3]);
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
