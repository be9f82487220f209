# SPDX-License-Identifier: GPL-3.0-or-later
"""Makes the seed files of the fuzzing harness (tests/fuzz/seeds/): one or two small inputs
per format msii reads, each computing successfully in a fraction of a second with the radius
SEEDS gives it and -n 4. fuzz.py mutates them; test_fuzz.py checks that they compute.

The meshes come from msii-samples (ASCII PLY) and are converted here to OFF, OBJ and STL; the
rasters come from msii-samples --geotiff and GDAL. The seeds are committed; run this again
only to change them:

    /usr/bin/python3 tests/fuzz/make_seeds.py --samples build/samples/msii-samples
"""
import argparse
import os
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SEED_DIR = os.path.join(HERE, "seeds")

# Seed file -> the radius fuzz.py computes it with (-n 4). Sized so that the smallest radius
# is about a median edge (meshes) or a cell (rasters): the same work as a real run, in small.
SEEDS = {
    "sphere_ascii.ply": 2.6,
    "terrain_binary.ply": 1.5,
    "sphere.off": 2.6,
    "tablet.obj": 1.4,
    "sphere_ascii.stl": 5.0,
    "terrain_binary.stl": 1.4,
    "terrain_cog.tif": 4.0,
    "terrain_plain.tif": 4.0,
    "terrain.asc": 4.0,
}

# Files that belong to a seed and travel with it (a raster's coordinate system).
COMPANIONS = {"terrain.asc": ["terrain.prj"]}


def seed_format(name):
    """The format a seed stands for: its extension."""
    return name.rsplit(".", 1)[1]


def run_samples(samples, *args):
    subprocess.run([samples, *args, "-q"], check=True)


def read_ascii_ply(path):
    """Vertices [(x, y, z)] and triangles [(a, b, c)] of msii-samples' ASCII PLY."""
    with open(path) as f:
        lines = f.read().splitlines()
    end = lines.index("end_header")
    counts = {}
    for line in lines[:end]:
        words = line.split()
        if words[0] == "element":
            counts[words[1]] = int(words[2])
    body = lines[end + 1:]
    vertices = [tuple(float(w) for w in line.split()[:3]) for line in body[:counts["vertex"]]]
    faces = []
    for line in body[counts["vertex"]:counts["vertex"] + counts["face"]]:
        words = [int(w) for w in line.split()]
        faces.append(tuple(words[1:1 + words[0]]))
    return vertices, faces


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def unit(v):
    length = (v[0] ** 2 + v[1] ** 2 + v[2] ** 2) ** 0.5
    return (0.0, 0.0, 1.0) if length == 0 else (v[0] / length, v[1] / length, v[2] / length)


def face_normal(vertices, face):
    a, b, c = (vertices[i] for i in face)
    return unit(cross(sub(b, a), sub(c, a)))


def vertex_normals(vertices, faces):
    """Area-weighted vertex normals (the unnormalised cross product weighs by area)."""
    sums = [[0.0, 0.0, 0.0] for _ in vertices]
    for face in faces:
        a, b, c = (vertices[i] for i in face)
        n = cross(sub(b, a), sub(c, a))
        for i in face:
            for k in range(3):
                sums[i][k] += n[k]
    return [unit(s) for s in sums]


def g(x):
    """A coordinate as short text: seeds stay small, and 6 digits are plenty for fuzzing."""
    return "%.6g" % x


def write_off(path, vertices, faces):
    with open(path, "w") as f:
        f.write("OFF\n# sphere from msii-samples, for the fuzzing harness\n")
        f.write("%d %d 0\n" % (len(vertices), len(faces)))
        for v in vertices:
            f.write(" ".join(g(x) for x in v) + "\n")
        for face in faces:
            f.write("%d %s\n" % (len(face), " ".join(str(i) for i in face)))


def write_obj(path, vertices, faces):
    """OBJ with positions, texture coordinates (x, y scaled to [0, 1]) and normals, faces in
    the form `f v/vt/vn`, the one most scanners write."""
    normals = vertex_normals(vertices, faces)
    xs = [v[0] for v in vertices]
    ys = [v[1] for v in vertices]
    span = max(max(xs) - min(xs), max(ys) - min(ys)) or 1.0
    with open(path, "w") as f:
        f.write("# tablet from msii-samples, for the fuzzing harness\no tablet\n")
        for v in vertices:
            f.write("v %s\n" % " ".join(g(x) for x in v))
        for v in vertices:
            f.write("vt %s %s\n" % (g((v[0] - min(xs)) / span), g((v[1] - min(ys)) / span)))
        for n in normals:
            f.write("vn %s\n" % " ".join(g(x) for x in n))
        for face in faces:
            f.write("f %s\n" % " ".join("%d/%d/%d" % (i + 1, i + 1, i + 1) for i in face))


def write_stl_ascii(path, vertices, faces):
    with open(path, "w") as f:
        f.write("solid sphere\n")
        for face in faces:
            f.write(" facet normal %s\n  outer loop\n" % " ".join(g(x) for x in face_normal(vertices, face)))
            for i in face:
                f.write("   vertex %s\n" % " ".join(g(x) for x in vertices[i]))
            f.write("  endloop\n endfacet\n")
        f.write("endsolid sphere\n")


def write_stl_binary(path, vertices, faces):
    with open(path, "wb") as f:
        # A header that does not start with "solid", which readers take for ASCII STL.
        f.write(b"binary STL from msii-samples, fuzzing seed".ljust(80, b" "))
        f.write(struct.pack("<I", len(faces)))
        for face in faces:
            values = list(face_normal(vertices, face))
            for i in face:
                values.extend(vertices[i])
            f.write(struct.pack("<12fH", *values, 0))


def make_meshes(samples, tmp):
    sphere = os.path.join(tmp, "sphere.ply")
    small_sphere = os.path.join(tmp, "small_sphere.ply")
    tablet = os.path.join(tmp, "tablet.ply")
    terrain = os.path.join(tmp, "terrain.ply")
    run_samples(samples, "sphere", "--radius", "2", "--spacing", "0.5", "--ascii",
                "-o", os.path.join(SEED_DIR, "sphere_ascii.ply"))
    run_samples(samples, "sphere", "--radius", "2", "--spacing", "0.5", "--ascii", "-o", sphere)
    run_samples(samples, "sphere", "--radius", "2", "--spacing", "0.9", "--ascii", "-o", small_sphere)
    run_samples(samples, "terrain", "--width", "4", "--height", "3", "--spacing", "0.3",
                "--relief", "0.4", "--hill-width", "1", "-o", os.path.join(SEED_DIR, "terrain_binary.ply"))
    run_samples(samples, "tablet", "--width", "3", "--height", "2", "--spacing", "0.3",
                "--wedge-size", "0.8", "--ascii", "-o", tablet)
    run_samples(samples, "terrain", "--width", "3", "--height", "2", "--spacing", "0.3",
                "--relief", "0.4", "--hill-width", "1", "--ascii", "-o", terrain)
    write_off(os.path.join(SEED_DIR, "sphere.off"), *read_ascii_ply(sphere))
    write_obj(os.path.join(SEED_DIR, "tablet.obj"), *read_ascii_ply(tablet))
    write_stl_ascii(os.path.join(SEED_DIR, "sphere_ascii.stl"), *read_ascii_ply(small_sphere))
    write_stl_binary(os.path.join(SEED_DIR, "terrain_binary.stl"), *read_ascii_ply(terrain))


def make_rasters(samples, tmp):
    from osgeo import gdal
    gdal.UseExceptions()
    # msii-samples' GeoTIFF: 40 x 30 cells of 1 m, EPSG:25832, float32, nodata -9999 with
    # a few nodata cells, DEFLATE-compressed as a Cloud-Optimized GeoTIFF.
    cog = os.path.join(SEED_DIR, "terrain_cog.tif")
    run_samples(samples, "terrain", "--geotiff", "--width", "40", "--height", "30", "--spacing", "1",
                "--relief", "3", "--hill-width", "6", "--holes", "2", "--hole-size", "1.5", "-o", cog)
    # The same heights uncompressed in strips, so that mutations of the pixel data change
    # heights instead of breaking the compressed stream; a different nodata value.
    source = gdal.Open(cog)
    heights = source.GetRasterBand(1).ReadAsArray()
    heights[heights == -9999] = -32768
    heights[12, 20:23] = -32768
    plain = gdal.GetDriverByName("GTiff").Create(os.path.join(SEED_DIR, "terrain_plain.tif"), 40, 30, 1,
                                                 gdal.GDT_Float32, ["COMPRESS=NONE", "TILED=NO"])
    plain.SetGeoTransform(source.GetGeoTransform())
    plain.SetProjection(source.GetProjection())
    band = plain.GetRasterBand(1)
    band.SetNoDataValue(-32768)
    band.WriteArray(heights)
    plain = None
    # ESRI ASCII grid with its .prj, heights to the centimetre.
    asc = os.path.join(SEED_DIR, "terrain.asc")
    gdal.Translate(asc, source, format="AAIGrid", creationOptions=["DECIMAL_PRECISION=2"])
    source = None
    for leftover in (asc + ".aux.xml", cog + ".aux.xml"):
        if os.path.exists(leftover):
            os.remove(leftover)


def check(msii):
    """Every seed computes (status 0), and quickly."""
    import time
    ok = True
    for name, radius in SEEDS.items():
        with tempfile.TemporaryDirectory() as tmp:
            raster = seed_format(name) in ("tif", "asc")
            out = ["--raster-output", os.path.join(tmp, "out.tif")] if raster else ["-o", os.path.join(tmp, "out.ply")]
            start = time.monotonic()
            run = subprocess.run([msii, "compute", os.path.join(SEED_DIR, name), "-r", str(radius), "-n", "4", *out],
                                 capture_output=True, text=True)
            seconds = time.monotonic() - start
            size = os.path.getsize(os.path.join(SEED_DIR, name))
            print("%-20s %6d bytes  status %d  %.2f s" % (name, size, run.returncode, seconds))
            if run.returncode != 0:
                print(run.stderr, end="")
                ok = False
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", default=os.environ.get("MSII_SAMPLES_EXE"), help="msii-samples program")
    parser.add_argument("--msii", default=os.environ.get("MSII_EXE"), help="msii program, to check the seeds")
    args = parser.parse_args()
    if not args.samples:
        parser.error("give --samples or set MSII_SAMPLES_EXE")
    os.makedirs(SEED_DIR, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        make_meshes(args.samples, tmp)
        make_rasters(args.samples, tmp)
    if args.msii and not check(args.msii):
        sys.exit(1)


if __name__ == "__main__":
    main()
