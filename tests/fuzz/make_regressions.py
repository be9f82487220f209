# SPDX-License-Identifier: GPL-3.0-or-later
"""Makes the regression inputs of issue 38 (tests/fuzz/regressions/), the inputs that once
broke msii; test_fuzz.py runs each with the outcome msii owes it. The files are committed;
run this again only to change them:

    /usr/bin/python3 tests/fuzz/make_regressions.py --samples build/samples/msii-samples

Mutants that fuzz.py found failing are saved next to these by hand (fuzz.py --keep), with
their expected outcome in test_fuzz.py's FOUND_BY_FUZZING.
"""
import argparse
import math
import os
import random
import shutil
import struct
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REGRESSION_DIR = os.path.join(HERE, "regressions")

FLOAT32_LOWEST = -3.4028234663852886e38   # -3.4028235e38 as float32 stores it
PATCH = (slice(90, 100), slice(120, 130))  # rows, columns of the undeclared-nodata patch: 100 cells


def hills(width, height, relief):
    """Smooth heights from a formula, rounded to 1/64 m so that the files compress well."""
    rows = []
    for row in range(height):
        y = float(row)
        rows.append([round((300 + relief * (math.sin(x / 23.0) * math.cos(y / 31.0)
                                          + 0.6 * math.sin((x + 2 * y) / 17.0))) * 64) / 64
                     for x in (float(c) for c in range(width))])
    return rows


def write_dem(path, rows, nodata=None):
    """A float32 GeoTIFF of 1 m cells in EPSG:25832 (UTM 32N), DEFLATE-compressed."""
    import numpy as np
    from osgeo import gdal, osr
    gdal.UseExceptions()
    heights = np.array(rows, dtype=np.float32)
    dataset = gdal.GetDriverByName("GTiff").Create(path, heights.shape[1], heights.shape[0], 1, gdal.GDT_Float32,
                                                   ["COMPRESS=DEFLATE", "PREDICTOR=3", "ZLEVEL=9"])
    dataset.SetGeoTransform((512000.0, 1.0, 0.0, 5498000.0, 0.0, -1.0))
    crs = osr.SpatialReference()
    crs.ImportFromEPSG(25832)
    dataset.SetProjection(crs.ExportToWkt())
    band = dataset.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.WriteArray(heights)
    dataset = None
    if os.path.exists(path + ".aux.xml"):
        os.remove(path + ".aux.xml")


def undeclared_nodata_dems():
    """200 x 200 hills with a 10 x 10 patch of float32's lowest value, and one of -9999, as
    DEMs come from tools that mark gaps so without declaring it as nodata."""
    for name, value in (("dem_float_min_patch.tif", FLOAT32_LOWEST), ("dem_minus9999_patch.tif", -9999.0)):
        rows = hills(200, 200, 12.0)
        for r in range(PATCH[0].start, PATCH[0].stop):
            for c in range(PATCH[1].start, PATCH[1].stop):
                rows[r][c] = value
        write_dem(os.path.join(REGRESSION_DIR, name), rows)


def spikes_dem():
    """60 x 60 cells of 1 m relief with 20 single-cell spikes of 1 to 4.8 km, as a lidar
    tile with outliers (birds, clouds) holds: heights from 0 to 4,800 m."""
    rng = random.Random(38)
    rows = [[round((0.5 + 0.5 * math.sin(c / 7.0) * math.cos(r / 9.0)) * 64) / 64 for c in range(60)]
            for r in range(60)]
    cells = rng.sample([(r, c) for r in range(60) for c in range(60)], 20)
    for i, (r, c) in enumerate(cells):
        rows[r][c] = 4800.0 if i == 0 else round(rng.uniform(1000, 4800), 1)
    rows[0][0] = 0.0
    write_dem(os.path.join(REGRESSION_DIR, "dem_spikes.tif"), rows)


def closed_spikes(samples, tmp):
    """A closed sphere (radius 2) with one vertex moved 10^6 units outwards: the long, thin
    faces around it would span a voxel grid of 10^6 units. And the same with the vertex moved
    3000 units, which msii once computed for 75 s in 7 GB: far enough to cost that much, not
    far enough for the check of the grid's extent. And a small mesh with a spike."""
    sphere = os.path.join(tmp, "sphere.ply")
    subprocess.run([samples, "sphere", "--radius", "2", "--spacing", "0.5", "--ascii", "-q", "-o", sphere], check=True)
    with open(sphere) as f:
        lines = f.read().split("\n")
    first = lines.index("end_header") + 1
    moved = first + 7
    x, y, z = (float(w) for w in lines[moved].split())
    length = math.sqrt(x * x + y * y + z * z)
    for name, distance in (("closed_spike.ply", 1e6), ("closed_spike_3000.ply", 3000.0)):
        spiked = list(lines)
        spiked[moved] = " ".join("%.9g" % (v + distance * v / length) for v in (x, y, z))
        with open(os.path.join(REGRESSION_DIR, name), "w") as f:
            f.write("\n".join(spiked))
    # A coarser sphere, 42 vertices, with a vertex 20,000 units away: the spike rule, which
    # measures the mesh by its central 98 %, missed it on so few vertices (32 s, 4.2 GB, then
    # "out of memory").
    small = os.path.join(tmp, "small_sphere.ply")
    subprocess.run([samples, "sphere", "--radius", "2", "--spacing", "0.9", "--ascii", "-q", "-o", small], check=True)
    with open(small) as f:
        lines = f.read().split("\n")
    moved = lines.index("end_header") + 1 + 7
    x, y, z = (float(w) for w in lines[moved].split())
    length = math.sqrt(x * x + y * y + z * z)
    lines[moved] = " ".join("%.9g" % (v + 20000.0 * v / length) for v in (x, y, z))
    with open(os.path.join(REGRESSION_DIR, "closed_spike_small_mesh.ply"), "w") as f:
        f.write("\n".join(lines))


def obj_bad_vertices(samples, tmp):
    """A small closed OBJ with one vertex `v nan 0 0`, and one with `v 1e308 0 0`, on line 12;
    and one with a face whose first corner has no vertex index."""
    sphere = os.path.join(tmp, "small_sphere.ply")
    subprocess.run([samples, "sphere", "--radius", "2", "--spacing", "0.9", "--ascii", "-q", "-o", sphere],
                   check=True)
    with open(sphere) as f:
        lines = f.read().split("\n")
    first = lines.index("end_header") + 1
    counts = {w[1]: int(w[2]) for w in (line.split() for line in lines[:first]) if w and w[0] == "element"}
    vertices = [line.split() for line in lines[first:first + counts["vertex"]]]
    faces = [line.split()[1:] for line in lines[first + counts["vertex"]:first + counts["vertex"] + counts["face"]]]
    for name, bad in (("obj_nan_vertex.obj", "v nan 0 0"), ("obj_huge_vertex.obj", "v 1e308 0 0")):
        out = ["# a sphere with one vertex that is not a finite number, on line 12", "o sphere"]
        out += ["v %s" % " ".join(v) for v in vertices]
        out[11] = bad
        out += ["f %s" % " ".join(str(int(i) + 1) for i in face) for face in faces]
        with open(os.path.join(REGRESSION_DIR, name), "w") as f:
            f.write("\n".join(out) + "\n")
    # A face whose first corner has no vertex index ("/2/2"): OpenMesh's OBJ reader asserts
    # that a face has vertices, and the assertion aborts the program (fuzzing found it).
    out = ["# a sphere with a face whose first corner has no vertex index, on the last line", "o sphere"]
    out += ["v %s" % " ".join(v) for v in vertices]
    out += ["f %s" % " ".join(str(int(i) + 1) for i in face) for face in faces]
    out.append("f /2/2 3/3/3 4/4/4")
    with open(os.path.join(REGRESSION_DIR, "obj_face_without_vertex.obj"), "w") as f:
        f.write("\n".join(out) + "\n")


def ply_control_bytes():
    """An ASCII PLY whose header has a bogus property line with control characters (\\x01,
    a carriage return, an escape sequence that would clear a terminal's line) and bytes that
    are not UTF-8: an error quoting it verbatim would span lines or corrupt the terminal."""
    with open(os.path.join(HERE, "seeds", "sphere_ascii.ply"), "rb") as f:
        data = f.read()
    at = data.index(b"property float z\n") + len(b"property float z\n")
    bogus = b"property flo\x01at\rq\x1b[2K\xff\xfe\n"
    with open(os.path.join(REGRESSION_DIR, "ply_control_bytes.ply"), "wb") as f:
        f.write(data[:at] + bogus + data[at:])


def off_unicode_controls():
    """An OFF whose vertex line holds characters that are valid UTF-8 but not printable: a
    next-line control (U+0085), a line separator (U+2028), a right-to-left override (U+202E,
    which reorders the rest of a terminal line) and an Arabic number sign (U+0603, a format
    character, as fuzzing found one)."""
    with open(os.path.join(HERE, "seeds", "sphere.off"), encoding="utf-8") as f:
        lines = f.read().split("\n")
    vertex = next(i for i, line in enumerate(lines) if len(line.split()) == 3 and "." in line) + 10
    lines[vertex] = "0.5 \u0085x\u2028y\u202ez\u0603 1.0"
    with open(os.path.join(REGRESSION_DIR, "off_unicode_controls.off"), "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def off_binary_huge_count():
    """A binary OFF ("OFF BINARY", big-endian numbers) of 75 bytes that declares 200 million
    vertices and holds one triangle: read through OpenMesh, it once took 17 s and 4.3 GB of
    memory before an error (2.1 GB and "out of memory (try a larger --voxel-size)" under a
    4 GB address-space limit). Fuzzing found it, with the text seed's keyword changed."""
    data = b"OFF BINARY\n" + struct.pack(">iii", 200000000, 1, 0) + struct.pack(">9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    data += struct.pack(">iiii", 3, 0, 1, 2)
    with open(os.path.join(REGRESSION_DIR, "off_binary_huge_count.off"), "wb") as f:
        f.write(data)


def asc_far_corner():
    """The ESRI ASCII grid seed with its corner at x = 1e308: msii's error was OpenVDB's
    "ValueError: can't construct a dense grid with an empty bounding box", without the file."""
    with open(os.path.join(HERE, "seeds", "terrain.asc")) as f:
        lines = f.read().split("\n")
    lines = ["xllcorner    1e308" if line.startswith("xllcorner") else line for line in lines]
    with open(os.path.join(REGRESSION_DIR, "asc_far_corner.asc"), "w") as f:
        f.write("\n".join(lines))
    shutil.copy(os.path.join(HERE, "seeds", "terrain.prj"), os.path.join(REGRESSION_DIR, "asc_far_corner.prj"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", default=os.environ.get("MSII_SAMPLES_EXE"), help="msii-samples program")
    args = parser.parse_args()
    if not args.samples:
        parser.error("give --samples or set MSII_SAMPLES_EXE")
    os.makedirs(REGRESSION_DIR, exist_ok=True)
    undeclared_nodata_dems()
    spikes_dem()
    with tempfile.TemporaryDirectory() as tmp:
        closed_spikes(args.samples, tmp)
        obj_bad_vertices(args.samples, tmp)
    ply_control_bytes()
    off_unicode_controls()
    off_binary_huge_count()
    asc_far_corner()


if __name__ == "__main__":
    main()
