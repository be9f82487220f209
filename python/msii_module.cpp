/// @file msii_module.cpp
/// @brief `import msii`: the engine for Python. Meshes come in and results go out as numpy
/// arrays; msii.compute runs the engine's pipeline, as `msii compute` does (pipeline/
/// compute.h: mesh preparation, then the invariants, mapped back to the input's vertices),
/// so its values equal the CLI's bit for bit. The computation runs without the GIL; Ctrl-C cancels it (KeyboardInterrupt) through
/// the engine's progress listener (core/run_context.h), which also feeds `progress`.
#include <msii/core/errors.h>
#include <msii/core/run_context.h>
#include <msii/core/version.h>
#include <msii/pipeline/compute.h>
#include <msii/io/write_ply.h>
#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/map_frame.h>
#include <msii/featuremap/rasterize.h>
#include <msii/io/read_mesh.h>
#include <msii/metrics/feature_metrics.h>
#include <msii/smoothing/ring_smoothing.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace msii;

namespace {

/// When Python wants to stop (a signal such as Ctrl-C, or an exception raised by the
/// progress callable), the RunContext's listener throws msii::Cancelled to unwind the
/// engine. The Python error itself travels in `PendingError`, fetched in the thread that saw
/// it and restored in the calling thread.

struct PendingError {
    PyObject *type = nullptr, *value = nullptr, *traceback = nullptr;
    void fetch() { PyErr_Fetch(&type, &value, &traceback); }   // with the GIL
    void restore() { PyErr_Restore(type, value, traceback); }  // with the GIL; gives the references away
};

std::string shapeText(const py::array& a)
{
    std::string s = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

template <class T>
void readPoints(const py::array& a, std::vector<Vec3>& points)
{
    const auto r = a.unchecked<T, 2>();  // any strides: no copy of the array
    points.resize(std::size_t(r.shape(0)));
    for (py::ssize_t i = 0; i < r.shape(0); ++i) {
        const Vec3 p(double(r(i, 0)), double(r(i, 1)), double(r(i, 2)));
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw py::value_error("vertex " + std::to_string(i) + " has a coordinate that is not a finite number.");
        points[std::size_t(i)] = p;
    }
}

template <class T>
void readFaces(const py::array& a, std::size_t numVertices, std::vector<Triangle>& triangles)
{
    const auto r = a.unchecked<T, 2>();
    triangles.resize(std::size_t(r.shape(0)));
    for (py::ssize_t f = 0; f < r.shape(0); ++f)
        for (int k = 0; k < 3; ++k) {
            const T v = r(f, k);
            if (v < 0 || std::uint64_t(v) >= numVertices)
                throw py::value_error("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                                      ", but there are " + std::to_string(numVertices) + " vertices.");
            triangles[std::size_t(f)][k] = std::uint32_t(v);
        }
}

/// The mesh of (n, 3) float32/float64 vertices and (m, 3) integer faces, read in place.
TriMesh meshOf(const py::array& vertices, const py::array& faces)
{
    if (vertices.ndim() != 2 || vertices.shape(1) != 3)
        throw py::value_error("vertices must be an array of shape (n, 3), not " + shapeText(vertices) + ".");
    if (faces.ndim() != 2 || faces.shape(1) != 3)
        throw py::value_error("faces must be an array of shape (m, 3), not " + shapeText(faces) + ".");
    TriMesh mesh;
    const py::dtype vt = vertices.dtype(), ft = faces.dtype();
    if (vt.is(py::dtype::of<double>())) readPoints<double>(vertices, mesh.points);
    else if (vt.is(py::dtype::of<float>())) readPoints<float>(vertices, mesh.points);
    else throw py::value_error("vertices must be float32 or float64, not " + py::str(py::handle(vt)).cast<std::string>() + ".");
    const std::size_t n = mesh.points.size();
    if (ft.is(py::dtype::of<std::int32_t>())) readFaces<std::int32_t>(faces, n, mesh.triangles);
    else if (ft.is(py::dtype::of<std::int64_t>())) readFaces<std::int64_t>(faces, n, mesh.triangles);
    else if (ft.is(py::dtype::of<std::uint32_t>())) readFaces<std::uint32_t>(faces, n, mesh.triangles);
    else if (ft.is(py::dtype::of<std::uint64_t>())) readFaces<std::uint64_t>(faces, n, mesh.triangles);
    else throw py::value_error("faces must be int32, int64, uint32 or uint64, not " + py::str(py::handle(ft)).cast<std::string>() + ".");
    return mesh;
}

/// A column per radius ([j][vertex]) as one (n_vertices, N) float32 array; frees each
/// column once copied, so the result is held once, not twice.
py::object featureArray(std::vector<std::vector<float>>& columns)
{
    if (columns.empty()) return py::none();
    const std::size_t nr = columns.size(), nv = columns.front().size();
    py::array_t<float> out({nv, nr});
    auto w = out.mutable_unchecked<2>();
    for (std::size_t j = 0; j < nr; ++j) {
        for (std::size_t i = 0; i < nv; ++i) w(py::ssize_t(i), py::ssize_t(j)) = columns[j][i];
        std::vector<float>().swap(columns[j]);
    }
    return std::move(out);
}

py::object computeArrays(const py::array& vertices, const py::array& faces, double radius, int scales,
                 const std::string& invariants, bool exact, int threads, const py::object& progress,
                 double memoryBudget, int tiles, const std::string& border, bool plCheck)
{
    const TriMesh mesh = meshOf(vertices, faces);
    if (!(radius > 0) || !std::isfinite(radius)) throw py::value_error("radius must be a positive number.");
    if (threads < 0) throw py::value_error("threads must be 0 (all cores) or more.");
    if (!(memoryBudget >= 0) || tiles < 0) throw py::value_error("memory_budget and tiles must be 0 or more.");
    ComputeOptions o;
    o.invariants.radius = radius;
    o.invariants.scales = scales;
    o.invariants.select(parseInvariantList(invariants));
    o.invariants.exact = exact;
    o.tiling.memoryBudget = memoryBudget;
    o.tiling.tilesPerAxis = tiles;
    o.border = parseBorderHandling(border);
    o.invariants.patchLineExactWhereBlurred = plCheck;
    const bool follow = !progress.is_none();
    if (follow && !PyCallable_Check(progress.ptr()))
        throw py::value_error("progress must be a callable (stage, done, total) or None.");

    PendingError pending;
    ComputeResult result;
    {
        py::gil_scoped_release free;
        std::unique_ptr<tbb::global_control> limit;
        if (threads > 0)
            limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
        RunContext watch([&](const ProgressUpdate& update) {
            py::gil_scoped_acquire hold;
            if (PyErr_CheckSignals() != 0) {  // Ctrl-C (in the main thread): KeyboardInterrupt
                pending.fetch();
                throw Cancelled{};
            }
            if (!follow) return;
            try {
                progress(update.stage, update.done, update.total);
            } catch (py::error_already_set& e) {
                e.restore();
                pending.fetch();
                throw Cancelled{};
            }
        });
        try {
            result = msii::compute(mesh, o, &watch);
        } catch (const Cancelled&) {
            py::gil_scoped_acquire hold;
            pending.restore();
            throw py::error_already_set();
        }
    }
    py::dict out;
    for (Invariant i : kAllInvariants)
        out[std::string(1, invariantLetter(i)).c_str()] = featureArray(result.features[i]);
    const ScalePlan& plan = result.plan;
    out["radii"] = py::array_t<double>(py::ssize_t(plan.radii.size()), plan.radii.data());
    out["voxel_size"] = plan.voxelSize;
    out["levels"] = plan.volumeSphereLevels;
    out["sample_levels"] = plan.patchLineLevels;
    out["reach"] = plan.reach;
    out["exact"] = exact;
    out["border"] = border;
    out["pl_check"] = plCheck;
    // P and L: the share of values evaluated exactly where the kernels blur (docs/method.md).
    out["pl_exact_share"] = double(result.cost.patchLinePairsExact) / double(std::max<std::size_t>(1, result.cost.patchLinePairs));
    out["filled_share"] = py::array_t<float>(py::ssize_t(result.filledShare.size()), result.filledShare.data());
    // Diagnostics as objects (core/diagnostics.h): kind (e.g. "duplicate_faces_removed",
    // "holes_filled", "mostly_masked"), count (of faces, holes, vertices ...; 0 if nothing),
    // figures (a dict of further numbers) and message.
    const py::object record = py::module_::import("types").attr("SimpleNamespace");
    py::list warnings;
    for (const Diagnostic& d : result.diagnostics) {
        py::dict figures;
        for (const auto& [name, value] : d.figures) figures[name.c_str()] = value;
        warnings.append(record(py::arg("kind") = d.kind, py::arg("count") = d.count, py::arg("figures") = figures,
                               py::arg("message") = d.message));
    }
    out["warnings"] = warnings;
    return record(**out);
}

py::tuple readMeshArrays(const std::string& path)
{
    ReadMeshResult read;
    {
        py::gil_scoped_release free;
        read = readMesh(path);
    }
    const std::size_t nv = read.mesh.numVertices(), nf = read.mesh.numTriangles();
    py::array_t<double> v({nv, std::size_t(3)});
    py::array_t<std::int32_t> f({nf, std::size_t(3)});
    auto vw = v.mutable_unchecked<2>();
    auto fw = f.mutable_unchecked<2>();
    for (std::size_t i = 0; i < nv; ++i)
        for (int k = 0; k < 3; ++k) vw(py::ssize_t(i), k) = read.mesh.points[i][k];
    for (std::size_t t = 0; t < nf; ++t)
        for (int k = 0; k < 3; ++k) fw(py::ssize_t(t), k) = std::int32_t(read.mesh.triangles[t][k]);
    return py::make_tuple(v, f);
}

/// {name: array of n values} (any dtype, layout or stride) as vertex properties.
std::vector<VertexProperty> vertexProperties(const py::dict& properties, std::size_t numVertices)
{
    std::vector<VertexProperty> props;
    for (const auto& [key, value] : properties) {
        const std::string name = py::str(key);
        const py::array_t<float, py::array::c_style | py::array::forcecast> a =
            py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
        if (!a || a.ndim() != 1 || std::size_t(a.shape(0)) != numVertices)
            throw py::value_error("property '" + name + "' must be an array of one value per vertex (" +
                                  std::to_string(numVertices) + ").");
        props.push_back({name, std::vector<float>(a.data(), a.data() + a.shape(0))});
    }
    return props;
}

void writePlyArrays(const std::string& path, const py::array& vertices, const py::array& faces,
                    const py::dict& properties)
{
    const TriMesh mesh = meshOf(vertices, faces);
    std::vector<VertexProperty> props = vertexProperties(properties, mesh.numVertices());
    py::gil_scoped_release free;
    writePly(path, mesh, props);
}

/// One value per vertex from the feature vectors of a compute result (paper §3.1).
py::array_t<float> metric(const py::object& result, const std::string& name, const py::object& reference, double p,
                          const std::string& invariants)
{
    const MetricOptions options = metricOptionsByName(name, p);
    FeatureTable table;
    std::vector<py::array_t<float>> blocks;
    for (const Invariant inv : parseInvariantList(invariants.empty() ? "VSPL" : invariants)) {
        const py::object a = py::getattr(result, std::string(1, invariantLetter(inv)).c_str(), py::none());
        if (a.is_none()) {
            if (invariants.empty()) continue;  // the result's own invariants
            throw py::value_error(std::string("the result has no ") + invariantLetter(inv) + " features.");
        }
        py::array_t<float> block = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
        if (!block || block.ndim() != 2 || block.shape(1) < 1)
            throw py::value_error(std::string(1, invariantLetter(inv)) + " must be an array of shape (n_vertices, N).");
        if (!blocks.empty() && block.shape(0) != blocks.front().shape(0))
            throw py::value_error("the invariants' arrays have different numbers of vertices.");
        table.blocks.push_back({inv, int(block.shape(1))});
        blocks.push_back(block);
    }
    if (blocks.empty()) throw py::value_error("the result has no features (V, S, P or L).");
    table.numVertices = std::size_t(blocks.front().shape(0));
    const std::size_t dim = table.dimension();
    table.values.resize(table.numVertices * dim);
    std::size_t first = 0;
    for (const auto& block : blocks) {
        const auto r = block.unchecked<2>();
        for (py::ssize_t i = 0; i < r.shape(0); ++i)
            for (py::ssize_t e = 0; e < r.shape(1); ++e) table.values[std::size_t(i) * dim + first + std::size_t(e)] = r(i, e);
        first += std::size_t(r.shape(1));
    }
    std::vector<double> ref;
    if (py::isinstance<py::str>(reference)) {
        if (reference.cast<std::string>() != "flat")
            throw py::value_error("reference must be \"flat\", a vertex index or a feature vector.");
        ref = flatReference(table);
    } else if (py::isinstance<py::int_>(reference)) {
        const long long v = reference.cast<long long>();
        if (v < 0 || std::size_t(v) >= table.numVertices)
            throw py::value_error("reference vertex " + std::to_string(v) + " is not one of the " +
                                  std::to_string(table.numVertices) + " vertices.");
        ref = vertexReference(table, std::size_t(v));
    } else {
        const auto vec = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(reference);
        if (!vec || vec.ndim() != 1 || std::size_t(vec.shape(0)) != dim)
            throw py::value_error("a reference vector must have " + std::to_string(dim) + " values.");
        ref.assign(vec.data(), vec.data() + dim);
    }
    MetricResult r;
    {
        py::gil_scoped_release free;
        r = computeMetric(table, ref, options);
    }
    return py::array_t<float>(py::ssize_t(r.values.size()), r.values.data());
}

/// 1-ring smoothing (paper §3.2) of one value per vertex, or of each column of (n, k).
py::array_t<float> smooth(const py::array& vertices, const py::array& faces, const py::array& values, int iterations,
                          const std::string& filter)
{
    const TriMesh mesh = meshOf(vertices, faces);
    if (iterations < 0) throw py::value_error("iterations must be 0 or more.");
    SmoothingOptions options;
    options.iterations = iterations;
    if (filter == "mean") options.filter = SmoothingFilter::Mean;
    else if (filter == "median") options.filter = SmoothingFilter::Median;
    else throw py::value_error("filter must be \"mean\" or \"median\", not \"" + filter + "\".");
    py::array_t<float> in = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
    if (!in || (in.ndim() != 1 && in.ndim() != 2) || std::size_t(in.shape(0)) != mesh.numVertices())
        throw py::value_error("values must have one row per vertex (" + std::to_string(mesh.numVertices()) +
                              "), as shape (n,) or (n, k).");
    const std::size_t n = mesh.numVertices(), k = in.ndim() == 2 ? std::size_t(in.shape(1)) : 1;
    py::array_t<float> out(in.request().shape);
    const float* src = in.data();
    float* dst = out.mutable_data();
    {
        py::gil_scoped_release free;
        const RingSmoother smoother(mesh, options);
        std::vector<float> column(n);
        for (std::size_t c = 0; c < k; ++c) {
            for (std::size_t i = 0; i < n; ++i) column[i] = src[i * k + c];
            smoother.smooth(column);
            for (std::size_t i = 0; i < n; ++i) dst[i * k + c] = column[i];
        }
    }
    return out;
}

/// The map of msii map, in memory: the mesh projected orthographically onto a frame, with
/// height, normal, mask and each given per-vertex property per pixel (map/feature_map.h),
/// the values an EXR written by msii map holds.
py::object featureMap(const py::array& vertices, const py::array& faces, const py::dict& properties,
                      const std::string& view, double pixelSize, int longerSide)
{
    const TriMesh mesh = meshOf(vertices, faces);
    std::vector<VertexProperty> props = vertexProperties(properties, mesh.numVertices());
    MapFrameOptions fo;
    parseMapView(view, fo);
    if (pixelSize > 0 && longerSide > 0) throw py::value_error("give pixel_size or longer_side, not both.");
    if (pixelSize < 0 || longerSide < 0) throw py::value_error("pixel_size and longer_side must be positive.");
    if (pixelSize > 0) fo.pixelSize = pixelSize;
    else fo.longerSidePixels = longerSide > 0 ? longerSide : 2048;  // msii map's default

    MapFrame frame;
    PixelHits hits;
    std::array<std::vector<float>, 3> normal;
    std::vector<std::vector<float>> channels(props.size());
    {
        py::gil_scoped_release free;
        frame = makeMapFrame(mesh, fo);
        hits = rasterize(mesh, frame);
        const std::array<std::vector<float>, 3> vn = vertexNormalsInFrame(mesh, frame);
        for (int c = 0; c < 3; ++c) normal[std::size_t(c)] = interpolateToPixels(mesh, hits, vn[std::size_t(c)]);
        // Unit length per pixel, as in the EXR (NaN where the interpolated normal vanishes).
        const float nan = std::numeric_limits<float>::quiet_NaN();
        for (std::size_t k = 0; k < hits.triangle.size(); ++k) {
            const float x = normal[0][k], y = normal[1][k], z = normal[2][k], len = std::sqrt(x * x + y * y + z * z);
            for (auto& n : normal) n[k] = len > 0 ? n[k] / len : nan;
        }
        for (std::size_t q = 0; q < props.size(); ++q) channels[q] = interpolateToPixels(mesh, hits, props[q].values);
    }
    const py::ssize_t h = frame.height, w = frame.width;
    const auto image = [&](const std::vector<float>& values) {
        py::array_t<float> a({h, w});
        std::copy(values.begin(), values.end(), a.mutable_data());
        return a;
    };
    py::array_t<float> normals({h, w, py::ssize_t(3)});
    float* dst = normals.mutable_data();
    for (std::size_t k = 0; k < hits.triangle.size(); ++k)
        for (std::size_t c = 0; c < 3; ++c) dst[3 * k + c] = normal[c][k];
    py::array_t<bool> mask({h, w});
    for (std::size_t k = 0; k < hits.triangle.size(); ++k) mask.mutable_data()[k] = hits.triangle[k] != PixelHits::kNone;
    py::dict values;
    for (std::size_t q = 0; q < props.size(); ++q) values[props[q].name.c_str()] = image(channels[q]);
    const auto vec = [](const Vec3& v) { return py::make_tuple(v.x, v.y, v.z); };
    const py::object record = py::module_::import("types").attr("SimpleNamespace");
    return record(py::arg("height") = image(hits.depth), py::arg("normal") = normals, py::arg("mask") = mask,
                  py::arg("values") = values, py::arg("pixel_size") = frame.pixelSize,
                  py::arg("origin") = vec(frame.origin), py::arg("axis_u") = vec(frame.axisU),
                  py::arg("axis_v") = vec(frame.axisV), py::arg("axis_normal") = vec(frame.normal),
                  py::arg("min_u") = frame.minU, py::arg("max_v") = frame.maxV, py::arg("view") = mapViewName(frame));
}

/// An EXR feature map (msii map) read back: every channel as (h, w) float32, and the frame.
py::object readFeatureMapArrays(const std::string& path)
{
    FeatureMapImage map;
    {
        py::gil_scoped_release free;
        map = readFeatureMap(path);
    }
    py::dict channels;
    for (const auto& [name, values] : map.channels) {
        py::array_t<float> a({py::ssize_t(map.height), py::ssize_t(map.width)});
        std::copy(values.begin(), values.end(), a.mutable_data());
        channels[name.c_str()] = a;
    }
    const auto vec = [](const Vec3& v) { return py::make_tuple(v.x, v.y, v.z); };
    const py::object record = py::module_::import("types").attr("SimpleNamespace");
    return record(py::arg("channels") = channels, py::arg("pixel_size") = map.frame.pixelSize,
                  py::arg("origin") = vec(map.frame.origin), py::arg("axis_u") = vec(map.frame.axisU),
                  py::arg("axis_v") = vec(map.frame.axisV), py::arg("axis_normal") = vec(map.frame.normal),
                  py::arg("min_u") = map.frame.minU, py::arg("max_v") = map.frame.maxV, py::arg("units") = map.units,
                  py::arg("radii") = map.radii);
}

} // namespace

PYBIND11_MODULE(msii, m)
{
    m.doc() = "Multi-Scale Integral Invariants (V, S, P, L) per vertex of triangle meshes: 3D scans of tablets, "
              "seals, inscriptions and terrain. See docs/python.md.";
    m.attr("__version__") = versionString();
    // The engine's two errors as Python's: input that cannot be computed, and files.
    py::register_exception<InvalidInputError>(m, "InvalidInputError", PyExc_ValueError);
    py::register_exception<IOError>(m, "IOError", PyExc_OSError);

    m.def("read_mesh", &readMeshArrays, py::arg("path"),
          "Reads a PLY, OBJ, OFF or STL mesh: (vertices float64 (n, 3), faces int32 (m, 3)).");
    m.def("compute", &computeArrays, py::arg("vertices"), py::arg("faces"), py::arg("radius"), py::arg("scales") = 16,
          py::arg("invariants") = "VSPL", py::arg("exact") = false, py::arg("threads") = 0,
          py::arg("progress") = py::none(), py::arg("memory_budget") = 0.0, py::arg("tiles") = 0,
          py::arg("border") = "continue", py::arg("pl_check") = true,
          "The integral invariants at N = scales radii r_j = j*radius/N for every vertex, as msii compute "
          "computes them (mesh preparation included; the same values bit for bit). Returns an object with V, S, P, L "
          "(float32 (n_vertices, N), None if not asked), filled_share (float32 (n_vertices,): how much of each "
          "vertex's largest ball rests on surface not in the input, filled holes and the continuation past borders, "
          "as a share of pi R^2), radii, "
          "voxel_size, levels (grid level per radius), exact, warnings (what preparation repaired or filled and the "
          "computation's remarks, each with kind, count and message). progress(stage, done, total) is called about 10 times per second; Ctrl-C cancels "
          "(KeyboardInterrupt). memory_budget (bytes) or tiles (per axis) compute in tiles, with the same values. "
          "border='continue' (default) continues an open surface past its borders so that every vertex gets values; "
          "border='mask' gives NaN where a ball reaches a border instead. "
          "pl_check=True (default) evaluates P and L exactly where kernels of two widths disagree (pl_exact_share: the "
          "share of values so evaluated); False: the kernel sums alone, as msii compute --pl-check off. "
          "The GIL is released while computing.");
    m.def("metric", &metric, py::arg("result"), py::arg("metric") = "mahalanobis", py::arg("reference") = "flat",
          py::arg("p") = 2.0, py::arg("invariants") = "",
          "One value per vertex from the feature vectors of a compute result (paper Sec. 3.1), as msii metric: "
          "metric l1, l2, linf, lp (with p), l1w, l2w, linfw, lpw, mahalanobis, cosine, correlation, "
          "autocorrelation, tanimoto or neuclid; reference \"flat\" (a plane's values), a vertex index or a "
          "feature vector; invariants e.g. \"VP\" (default: all the result has). float32 (n,), NaN where undefined.");
    m.def("smooth", &smooth, py::arg("vertices"), py::arg("faces"), py::arg("values"), py::arg("iterations") = 30,
          py::arg("filter") = "mean",
          "Fast 1-ring smoothing (paper Sec. 3.2) of values (n,) or each column of (n, k), as msii smooth: "
          "filter \"mean\" or \"median\", iterations passes. float32, same shape.");
    m.def("feature_map", &featureMap, py::arg("vertices"), py::arg("faces"), py::arg("values") = py::dict(),
          py::arg("view") = "best", py::arg("pixel_size") = 0.0, py::arg("longer_side") = 0,
          "The mesh projected orthographically, as msii map writes it to EXR: height (h, w) over the plane "
          "towards the viewer, normal (h, w, 3) in the map frame, mask (h, w) bool, values {name: (h, w)} "
          "interpolated from {name: array of n values}, NaN off the mesh; and the frame (pixel_size, origin, "
          "axis_u, axis_v, axis_normal, min_u, max_v: pixel (x, y) is at u = min_u + (x + 0.5) pixel_size, "
          "v = max_v - (y + 0.5) pixel_size). view: best, +x, -x, +y, -y, +z, -z or \"X,Y,Z\"; resolution: "
          "pixel_size (mesh units) or longer_side (pixels, default 2048).");
    m.def("read_feature_map", &readFeatureMapArrays, py::arg("path"),
          "Reads an EXR feature map (msii map): channels {name: (h, w) float32} and the frame, units and radii "
          "from its header.");
    m.def("write_ply", &writePlyArrays, py::arg("path"), py::arg("vertices"), py::arg("faces"),
          py::arg("properties") = py::dict(),
          "Writes a binary PLY with per-vertex float properties {name: array of n values}, atomically.");
}
