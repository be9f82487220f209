#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_table.h>
#include <msii/mesh/read_mesh.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {

bool isFeatureName(const std::string& name, char letter)
{
    if (name.size() < 4 || name[1] != '_') return false;
    const bool letterOk = letter != 0 ? name[0] == letter : std::string("VSPL").find(name[0]) != std::string::npos;
    return letterOk &&
           std::all_of(name.begin() + 2, name.end(), [](unsigned char c) { return std::isdigit(c); });
}

FeatureMesh readFeatureMesh(const std::string& input, const std::vector<std::string>& matFiles)
{
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    ReadMeshResult read = readMesh(input, options);
    FeatureMesh out;
    out.mesh = std::move(read.mesh);
    out.properties = std::move(read.vertexProperties);
    out.comments = std::move(read.comments);
    for (const std::string& mat : matFiles) {
        std::vector<VertexProperty> add = featurePropertiesFromMat(mat, out.mesh.numVertices());
        const char letter = add.front().name[0];
        // A .mat replaces the whole feature vector of its invariant, whatever its length.
        out.properties.erase(std::remove_if(out.properties.begin(), out.properties.end(),
                                            [&](const VertexProperty& p) { return isFeatureName(p.name, letter); }),
                             out.properties.end());
        mergeProperties(out.properties, std::move(add));
    }
    return out;
}

void qualityWithoutNaN(std::vector<VertexProperty>& properties)
{
    for (VertexProperty& p : properties)
        if (p.name == "quality")
            for (float& v : p.values)
                if (std::isnan(v)) v = 0.0f;
}

std::size_t findProperty(const FeatureMesh& in, const std::string& name)
{
    for (std::size_t k = 0; k < in.properties.size(); ++k)
        if (in.properties[k].name == name) return k;
    std::string present;
    for (const auto& p : in.properties) present += (present.empty() ? "" : " ") + p.name;
    throw InvalidInputError("the input has no vertex property '" + name + "' (it has: " +
                            (present.empty() ? std::string("none") : present) + ")");
}

std::vector<std::size_t> findProperties(const FeatureMesh& in, const std::string& commaList)
{
    std::vector<std::size_t> out;
    std::stringstream list(commaList);
    std::string name;
    while (std::getline(list, name, ','))
        if (!name.empty()) out.push_back(findProperty(in, name));
    if (out.empty()) throw InvalidInputError("--properties names no property");
    return out;
}

std::vector<double> parseNumberList(const std::string& text, const std::string& option)
{
    std::vector<double> out;
    std::stringstream list(text);
    std::string item;
    while (std::getline(list, item, ',')) {
        std::size_t used = 0;
        double v = 0;
        try {
            v = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || !std::isfinite(v))
            throw InvalidInputError(option + ": '" + item + "' is not a number");
        out.push_back(v);
    }
    return out;
}

std::string outputPath(const std::string& input, const std::string& output, const std::string& suffix,
                       bool overwrite, const std::string& extension)
{
    std::string path = output;
    if (path.empty()) {
        const fs::path in(input);
        path = (in.parent_path() / (in.stem().string() + "." + suffix + extension)).string();
    }
    if (fs::path(path).extension() != extension)
        throw InvalidInputError("the output '" + path + "' must be a " + extension + " file");
    if (!overwrite && fs::exists(path))
        throw IOError("'" + path + "' exists already (use --overwrite to replace it)");
    checkWritable(path);
    return path;
}

} // namespace msii::tools
