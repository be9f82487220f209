#include <msii/io/feature_table.h>

#include <msii/core/errors.h>
#include <msii/io/feature_properties.h>
#include <msii/io/gigamesh_files.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>

namespace msii {

FeatureTable featureTableOf(const std::vector<VertexProperty>& properties, std::size_t numVertices,
                            const std::vector<Invariant>& invariants)
{
    std::map<std::string, const VertexProperty*> byName;
    for (const VertexProperty& p : properties) byName[p.name] = &p;
    FeatureTable table;
    table.numVertices = numVertices;
    std::vector<const VertexProperty*> columns;
    for (Invariant inv : invariants) {
        const char letter = invariantLetter(inv);
        int count = 0;
        while (byName.count(featureName(letter, std::size_t(count)))) ++count;
        if (count == 0) {
            // Some radii only, e.g. a DEM's default bands (V at R/4, R/2, 3R/4 and R).
            std::string some;
            for (const VertexProperty& p : properties)
                if (p.name.size() > 2 && p.name[0] == letter && p.name[1] == '_' &&
                    std::isdigit(static_cast<unsigned char>(p.name[2])))
                    some += (some.empty() ? "" : ", ") + p.name;
            if (!some.empty())
                throw InvalidInputError(std::string("the input has ") + letter + " at some radii only (" + some +
                                        "); the metrics need it at every radius, from " + featureName(letter, 0));
            std::string present;
            for (const char c : std::string("VSPL")) {
                int n = 0;
                while (byName.count(featureName(c, std::size_t(n)))) ++n;
                if (n > 0) present += (present.empty() ? "" : ", ") + featureName(c, 0) + "…" + featureName(c, std::size_t(n - 1));
            }
            throw InvalidInputError(std::string("the input has no ") + letter + " features (" +
                                    featureName(letter, 0) + " …); it has " +
                                    (present.empty() ? std::string("none") : present) +
                                    " (compute them first, or read them from a GigaMesh .mat file)");
        }
        for (int j = 0; j < count; ++j) {
            const VertexProperty* p = byName[featureName(letter, std::size_t(j))];
            if (p->values.size() != numVertices)
                throw InvalidInputError("property " + p->name + " has " + std::to_string(p->values.size()) +
                                        " values for " + std::to_string(numVertices) + " vertices");
            columns.push_back(p);
        }
        table.blocks.push_back({inv, count});
    }
    const std::size_t dim = columns.size();
    table.values.resize(numVertices * dim);
    for (std::size_t e = 0; e < dim; ++e)
        for (std::size_t i = 0; i < numVertices; ++i) table.values[i * dim + e] = columns[e]->values[i];
    return table;
}

std::vector<VertexProperty> featurePropertiesFromMat(const std::string& path, std::size_t numVertices)
{
    const auto invariant = gigaMeshInvariantOfFileName(path);
    if (!invariant)
        throw InvalidInputError("'" + std::filesystem::path(path).filename().string() +
                                "' is not named like a GigaMesh feature file (*.volume.mat for V, "
                                "*.surface.mat for P)");
    const GigaMeshRows rows = readGigaMeshMat(path, numVertices);
    const auto columns = fromGigaMeshRows(rows, *invariant);
    const char letter = *invariant == GigaMeshInvariant::Volume ? 'V' : 'P';
    std::vector<VertexProperty> props;
    for (std::size_t j = 0; j < columns.size(); ++j) props.push_back({featureName(letter, j), columns[j]});
    return props;
}

void mergeProperties(std::vector<VertexProperty>& properties, std::vector<VertexProperty> add)
{
    for (VertexProperty& p : add) {
        const auto it = std::find_if(properties.begin(), properties.end(),
                                     [&](const VertexProperty& q) { return q.name == p.name; });
        if (it != properties.end()) *it = std::move(p);
        else properties.push_back(std::move(p));
    }
}

} // namespace msii
