"""Tests of the Python module `msii` (python/msii_module.cpp), run by the README's test
command through ctest: msii.compute on arrays equals `msii compute` on the same mesh's PLY
bit for bit, and msii.metric and msii.smooth equal `msii metric` and `msii smooth`; any C-contiguous or strided float32/float64 and integer arrays give the same
values; bad arrays raise ValueError with one sentence; progress is reported and an exception
from it stops the work; Ctrl-C cancels with KeyboardInterrupt."""
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import msii

MSII = os.environ["MSII_EXE"]
SAMPLES = os.environ["MSII_SAMPLES_EXE"]
VOLUME_CSV = os.environ.get("VOLUME_CSV_EXE")  # examples/volume_csv, the library's first program


def read_ply(path):
    """The vertex records of a binary little-endian PLY as a numpy structured array."""
    types = {"float": "<f4", "double": "<f8", "int": "<i4", "uchar": "u1"}
    with open(path, "rb") as f:
        fields, in_vertex, count = [], False, 0
        while True:
            line = f.readline().decode().strip()
            if line == "end_header":
                break
            words = line.split()
            if words[0] == "element":
                in_vertex = words[1] == "vertex"
                if in_vertex:
                    count = int(words[2])
            elif words[0] == "property" and in_vertex:
                fields.append((words[2], types[words[1]]))
        return np.frombuffer(f.read(count * np.dtype(fields).itemsize), dtype=np.dtype(fields), count=count)


@pytest.fixture(scope="module")
def tablet(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tablet")
    scan = folder / "scan.ply"
    subprocess.run([SAMPLES, "tablet", "--width", "6", "--height", "5", "--spacing", "0.08", "-q", "-o", str(scan)],
                   check=True)
    return scan


def test_compute_equals_the_cli_bit_for_bit(tablet, tmp_path):
    out = tmp_path / "scan.msii.ply"
    subprocess.run([MSII, "compute", str(tablet), "-r", "0.8", "-q", "-o", str(out)], check=True)
    cli = read_ply(out)
    vertices, faces = msii.read_mesh(str(tablet))
    assert vertices.dtype == np.float64 and vertices.shape == (len(cli), 3)
    assert faces.dtype == np.int32 and faces.shape[1] == 3
    r = msii.compute(vertices, faces, 0.8)
    assert r.radii.shape == (16,)
    assert np.allclose(r.radii, 0.8 * np.arange(1, 17) / 16)
    compared = 0
    for letter in "VSPL":
        values = getattr(r, letter)
        assert values.dtype == np.float32 and values.shape == (len(cli), 16)
        for j in range(16):
            column = cli["%s_%02d" % (letter, j + 1)]
            same = (values[:, j] == column) | (np.isnan(values[:, j]) & np.isnan(column))
            assert same.all(), "%s_%02d differs at %d vertices" % (letter, j + 1, (~same).sum())
            compared += np.count_nonzero(~np.isnan(column))
    assert compared > 100000
    assert not np.isnan(r.V).any()  # the open border is continued: values everywhere
    assert r.border == "continue" and r.filled_share.shape == (len(cli),)
    assert (r.filled_share > 0).any() and (r.filled_share == 0).any()
    column = cli["filled_share"]
    assert np.array_equal(r.filled_share, column)
    masked = msii.compute(vertices, faces, 0.8, border="mask")
    assert np.isnan(masked.V).any() and not np.isnan(masked.V).all()  # NaN where a ball reaches the border
    whole = ~np.isnan(masked.V).any(axis=1)
    assert np.array_equal(masked.V[whole], r.V[whole])  # balls clear of the border: the same, bit for bit
    with pytest.raises(msii.InvalidInputError, match="continue"):
        msii.compute(vertices, faces, 0.8, border="clip")
    assert r.voxel_size > 0 and len(r.levels) == 16


def test_pl_check_is_the_cli_option(tablet, tmp_path):
    # pl_check=False is msii compute --pl-check off, bit for bit; the default evaluates some
    # values exactly (the tablet's wedges), which it says.
    out = tmp_path / "scan.msii.ply"
    subprocess.run([MSII, "compute", str(tablet), "-r", "0.8", "-q", "--pl-check", "off", "-o", str(out)], check=True)
    cli = read_ply(out)
    vertices, faces = msii.read_mesh(str(tablet))
    off = msii.compute(vertices, faces, 0.8, invariants="PL", pl_check=False)
    on = msii.compute(vertices, faces, 0.8, invariants="PL")
    assert not off.pl_check and off.pl_exact_share == 0
    assert on.pl_check and 0 < on.pl_exact_share < 1
    for letter in "PL":
        for j in range(16):
            column = cli["%s_%02d" % (letter, j + 1)]
            assert np.array_equal(getattr(off, letter)[:, j], column, equal_nan=True), "%s_%02d" % (letter, j + 1)
    assert (on.P != off.P).any() and (on.L != off.L).any()


def test_every_door_gives_the_same_values_on_a_scan_that_needs_repair(tablet, tmp_path):
    # A scan as real ones come: duplicate faces, degenerate faces, a flipped face, small
    # holes and a vertex in no face. `msii compute`, msii.compute and the C++ library's
    # example (examples/volume_csv) all run the engine's pipeline (pipeline/compute.h), so
    # they repair it alike and give the same V at every vertex.
    assert VOLUME_CSV, "VOLUME_CSV_EXE is not set"
    vertices, faces = msii.read_mesh(str(tablet))
    rng = np.random.default_rng(7)
    kept = np.ones(len(faces), bool)
    for centre in rng.choice(len(vertices), 3, replace=False):  # small holes: faces near 3 vertices removed
        near = np.linalg.norm(vertices - vertices[centre], axis=1) < 0.15
        kept &= ~near[faces].any(axis=1)
    broken = faces[kept].copy()
    broken[5] = broken[5][::-1]                                       # flipped
    broken = np.vstack([broken, broken[:4], [[broken[9][0], broken[9][0], broken[9][1]]]])  # duplicates, degenerate
    broken_vertices = np.vstack([vertices, [[50.0, 50.0, 50.0]]])     # in no face
    scan = tmp_path / "broken.ply"
    msii.write_ply(str(scan), broken_vertices, broken)

    python = msii.compute(broken_vertices, broken, 0.8, invariants="V")
    kinds = {w.kind for w in python.warnings}
    assert {"duplicate_faces_removed", "degenerate_faces_removed", "holes_filled"} <= kinds, kinds
    out = tmp_path / "broken.msii.ply"
    subprocess.run([MSII, "compute", str(scan), "-r", "0.8", "--invariants", "V", "-q", "-o", str(out)], check=True)
    cli = np.stack([read_ply(out)["V_%02d" % (j + 1)] for j in range(16)], axis=1)
    csv = tmp_path / "broken.csv"
    subprocess.run([VOLUME_CSV, str(scan), "0.8", str(csv)], check=True, stderr=subprocess.DEVNULL)
    library = np.genfromtxt(csv, delimiter=",", skip_header=1, dtype=np.float64)[:, 1:].astype(np.float32)
    for name, values in [("msii.compute", python.V), ("volume_csv", library)]:
        assert values.shape == cli.shape, name
        assert np.array_equal(values, cli, equal_nan=True), name
    assert np.count_nonzero(~np.isnan(cli)) > 5 * len(vertices)  # values compared, not only NaN
    assert np.isnan(cli[-1]).all()  # the vertex in no face


def test_array_types_and_layouts_give_the_same_values(tablet):
    vertices, faces = msii.read_mesh(str(tablet))
    ref = msii.compute(vertices, faces, 0.8, scales=4, invariants="VS")
    assert ref.P is None and ref.L is None
    variants = [
        (vertices.astype(np.float32), faces.astype(np.int64)),     # the PLY's floats are float32
        (np.asfortranarray(vertices), np.asfortranarray(faces)),  # not C-contiguous
        (np.hstack([vertices, np.zeros_like(vertices)])[:, :3], faces.astype(np.uint32)),  # a strided view
    ]
    for v, f in variants:
        r = msii.compute(v, f, 0.8, scales=4, invariants="V,S", threads=1)
        assert np.array_equal(r.V, ref.V, equal_nan=True)
        assert np.array_equal(r.S, ref.S, equal_nan=True)


@pytest.mark.parametrize("vertices, faces, message", [
    (np.zeros((4, 2)), np.zeros((1, 3), np.int32), "vertices must be an array of shape (n, 3), not (4, 2)."),
    (np.zeros((4, 3)), np.zeros((3,), np.int32), "faces must be an array of shape (m, 3), not (3,)."),
    (np.zeros((4, 3)), np.array([[0, 1, 4]], np.int32), "face 0 refers to vertex 4, but there are 4 vertices."),
    (np.zeros((4, 3)), np.array([[0, -1, 2]], np.int64), "face 0 refers to vertex -1, but there are 4 vertices."),
    (np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], float), np.array([[0, 1, 2]], np.int32),
     "vertex 2 has a coordinate that is not a finite number."),
    (np.zeros((4, 3), np.int32), np.zeros((1, 3), np.int32), "vertices must be float32 or float64, not int32."),
    (np.zeros((4, 3)), np.zeros((1, 3), np.float64), "faces must be int32, int64, uint32 or uint64, not float64."),
])
def test_bad_arrays_raise_value_error(vertices, faces, message):
    with pytest.raises(ValueError) as error:
        msii.compute(vertices, faces, 1.0)
    assert str(error.value) == message


def test_bad_arguments_raise_value_error(tablet):
    vertices, faces = msii.read_mesh(str(tablet))
    for kwargs, text in [({"radius": -1.0}, "radius"), ({"radius": 0.8, "invariants": "VX"}, "invariants"),
                         ({"radius": 0.8, "threads": -2}, "threads"), ({"radius": 0.8, "progress": 3}, "progress")]:
        with pytest.raises(ValueError, match=text):
            msii.compute(vertices, faces, **kwargs)
    with pytest.raises(OSError, match="cannot open"):
        msii.read_mesh(str(tablet) + ".missing.ply")
    with pytest.raises(ValueError, match="unknown file extension"):
        msii.read_mesh(str(tablet) + ".xyz")


def test_progress_is_reported_and_can_stop_the_work(tablet):
    vertices, faces = msii.read_mesh(str(tablet))
    calls = []
    msii.compute(vertices, faces, 0.8, scales=4, progress=lambda stage, done, total: calls.append((stage, done, total)))
    assert len(calls) >= 4
    assert all(isinstance(s, str) and 0 <= d <= t for s, d, t in calls if t > 0)

    class Stop(Exception):
        pass

    def stop(stage, done, total):
        raise Stop(stage)

    with pytest.raises(Stop):
        msii.compute(vertices, faces, 0.8, progress=stop)


def test_ctrl_c_cancels_with_keyboard_interrupt(tmp_path):
    script = textwrap.dedent("""
        import os, signal, sys, threading, time
        import msii
        vertices, faces = msii.read_mesh(sys.argv[1])
        threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        start = time.time()
        try:
            msii.compute(vertices, faces, 1.0, exact=True)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted after %.1f s" % (time.time() - start))
    """)
    scan = tmp_path / "big.ply"
    subprocess.run([SAMPLES, "tablet", "--width", "12", "--height", "10", "--spacing", "0.05", "-q", "-o", str(scan)],
                   check=True)
    run = subprocess.run([sys.executable, "-c", script, str(scan)], capture_output=True, text=True, timeout=120,
                         env=dict(os.environ))
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("interrupted after"), run.stdout + run.stderr
    assert float(run.stdout.split()[2]) < 10.0


def test_write_ply_round_trip(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], np.int32)
    path = tmp_path / "t.ply"
    msii.write_ply(str(path), vertices, faces, {"quality": np.array([0.5, 1, 2, 3], np.float32)})
    v, f = msii.read_mesh(str(path))
    assert np.array_equal(v, vertices) and np.array_equal(f, faces)
    assert np.array_equal(read_ply(path)["quality"], np.array([0.5, 1, 2, 3], np.float32))
    # A column of a 2-D array (strided, as result.V[:, j]) is written as its values.
    table = np.arange(12, dtype=np.float32).reshape(4, 3)
    msii.write_ply(str(path), vertices, faces, {"column": table[:, 2]})
    assert np.array_equal(read_ply(path)["column"], table[:, 2])
    with pytest.raises(ValueError, match="one value per vertex"):
        msii.write_ply(str(path), vertices, faces, {"q": np.zeros(3)})


def test_metric_and_smooth_equal_the_cli(tablet, tmp_path):
    out = tmp_path / "scan.msii.ply"
    subprocess.run([MSII, "compute", str(tablet), "-r", "0.8", "-n", "8", "-q", "-o", str(out)], check=True)
    vertices, faces = msii.read_mesh(str(tablet))
    r = msii.compute(vertices, faces, 0.8, scales=8)
    for name, invariants, reference in [("l2", "V", "flat"), ("mahalanobis", "V,P", "flat"),
                                        ("l1w", "V,S,P,L", "flat"), ("cosine", "S", 2000)]:
        m = tmp_path / ("metric-%s.ply" % name)
        subprocess.run([MSII, "metric", str(out), "--invariants", invariants, "--metric", name, "-q", "-o", str(m),
                        "--reference", reference if reference == "flat" else "vertex:%d" % reference], check=True)
        cli = read_ply(m)["f_" + name]
        mine = msii.metric(r, name, reference=reference, invariants=invariants.replace(",", ""))
        assert mine.dtype == np.float32 and mine.shape == (len(vertices),)
        assert np.array_equal(mine, cli, equal_nan=True), name
        assert np.count_nonzero(~np.isnan(cli)) > 1000
    # A vertex as the reference: 0 at that vertex.
    assert msii.metric(r, "l2", reference=2000, invariants="V")[2000] == 0
    with pytest.raises(ValueError, match="unknown metric"):
        msii.metric(r, "l3")
    with pytest.raises(ValueError, match="reference vertex"):
        msii.metric(r, "l2", reference=10**9)

    s = tmp_path / "smooth.ply"
    subprocess.run([MSII, "smooth", str(out), "--properties", "V_08", "-q", "-o", str(s)], check=True)
    cli = read_ply(s)["V_08"]
    mine = msii.smooth(vertices, faces, r.V[:, 7])
    assert np.array_equal(mine, cli, equal_nan=True)
    both = msii.smooth(vertices, faces, r.V[:, 6:8], iterations=30)
    assert both.shape == (len(vertices), 2) and np.array_equal(both[:, 1], cli, equal_nan=True)
    assert np.array_equal(msii.smooth(vertices, faces, r.V[:, 7], iterations=0), r.V[:, 7], equal_nan=True)
    with pytest.raises(ValueError, match="filter"):
        msii.smooth(vertices, faces, r.V[:, 7], filter="gauss")


def test_tiles_give_the_same_values(tablet):
    vertices, faces = msii.read_mesh(str(tablet))
    whole = msii.compute(vertices, faces, 0.8, scales=4)
    for kwargs in [{"tiles": 2}, {"tiles": 3}, {"memory_budget": 1e9}]:
        part = msii.compute(vertices, faces, 0.8, scales=4, **kwargs)
        for letter in "VSPL":
            assert np.array_equal(getattr(part, letter), getattr(whole, letter), equal_nan=True), (kwargs, letter)
    with pytest.raises(ValueError, match="not tiled"):
        msii.compute(vertices, faces, 0.8, exact=True, tiles=2)
    with pytest.raises(ValueError, match="0 or more"):
        msii.compute(vertices, faces, 0.8, tiles=-1)


def test_warnings_are_objects_with_kind_count_and_message(tablet):
    vertices, faces = msii.read_mesh(str(tablet))
    doubled = np.vstack([faces, faces[:10]])  # 10 duplicate faces: removed, and said so
    r = msii.compute(vertices, doubled, 0.8, scales=4, invariants="V")
    kinds = {w.kind: w for w in r.warnings}
    duplicates = [w for w in r.warnings if "duplicate" in w.kind]
    assert len(duplicates) == 1 and duplicates[0].count == 10, kinds
    assert all(isinstance(w.message, str) and w.message for w in r.warnings)
    clean = msii.compute(vertices, faces, 0.8, scales=4, invariants="V")
    assert not any("duplicate" in w.kind for w in clean.warnings)
    assert np.array_equal(clean.V, r.V, equal_nan=True)  # the repaired mesh gives the same values


def test_warnings_carry_codes_and_figures(tmp_path):
    # A small open patch with a large radius: most vertices masked, coded "mostly_masked"
    # with its figures, in a sentence that names no command-line flag.
    scan = tmp_path / "plate.ply"
    subprocess.run([SAMPLES, "tablet", "--width", "3", "--height", "2", "--spacing", "0.1", "-q", "-o", str(scan)],
                   check=True)
    vertices, faces = msii.read_mesh(str(scan))
    r = msii.compute(vertices, faces, 1.5, scales=4, invariants="V", border="mask")
    masked = [w for w in r.warnings if w.kind == "mostly_masked"]
    assert len(masked) == 1, [w.kind for w in r.warnings]
    w = masked[0]
    assert w.figures["largest_radius"] == pytest.approx(1.5)
    share = float(np.mean(np.isnan(r.V[:, -1])))
    assert w.figures["masked_share"] == pytest.approx(share, abs=0.02)  # of the prepared mesh's vertices
    assert w.count > len(vertices) / 2
    assert "--" not in w.message


def test_feature_map_equals_the_exr_of_msii_map(tablet, tmp_path):
    vertices, faces = msii.read_mesh(str(tablet))
    r = msii.compute(vertices, faces, 0.8, scales=4, invariants="V")
    features = tmp_path / "scan.msii.ply"
    subprocess.run([MSII, "compute", str(tablet), "-r", "0.8", "-n", "4", "--invariants", "V", "-q",
                    "-o", str(features)], check=True)
    exr = tmp_path / "scan.map.exr"
    subprocess.run([MSII, "map", str(features), "--view", "+z", "--pixels", "300", "-q", "-o", str(exr)], check=True)
    m = msii.feature_map(vertices, faces, {"V_04": r.V[:, 3]}, view="+z", longer_side=300)
    got = msii.read_feature_map(str(exr))
    assert m.height.shape == got.channels["height"].shape and max(m.height.shape) == 300
    assert m.pixel_size == pytest.approx(got.pixel_size, rel=1e-12)
    assert np.array_equal(m.height, got.channels["height"], equal_nan=True)
    assert np.array_equal(m.mask, got.channels["mask"] == 1)
    for c, axis in enumerate("xyz"):
        assert np.array_equal(m.normal[:, :, c], got.channels["normal." + axis], equal_nan=True)
    assert np.array_equal(m.values["V_04"], got.channels["V_04"], equal_nan=True)
    assert m.mask.sum() > 0.5 * m.mask.size and np.isfinite(m.values["V_04"][m.mask]).any()
    with pytest.raises(ValueError, match="one value per vertex"):
        msii.feature_map(vertices, faces, {"q": r.V[:10, 0]})
    with pytest.raises(ValueError, match="not both"):
        msii.feature_map(vertices, faces, pixel_size=0.1, longer_side=100)
