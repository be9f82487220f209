# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of the QGIS Processing provider msii (qgis/msii_processing), headless, through
Processing as QGIS runs it: each algorithm writes the very file the msii command writes with
the same options, byte for byte; msii's progress, warnings and errors reach the feedback;
Cancel stops msii at once and leaves no file; the compute output loads styled on its quality
band; the provider has exactly its four algorithms; the program is found where it is set.

Run by ctest (qgis/CMakeLists.txt), or:
    QT_QPA_PLATFORM=offscreen MSII_EXE=build/tools/msii MSII_SAMPLES_EXE=build/samples/msii-samples \
        /usr/bin/python3 -m pytest -q -p no:cacheprovider qgis/tests/test_provider.py
"""

import filecmp
import glob
import os
import shutil
import subprocess
import sys
import tempfile
import time

import pytest
from osgeo import gdal
from qgis.core import (QgsApplication, QgsProcessingException, QgsProcessingFeedback,
                       QgsProject, QgsRasterLayer, QgsRasterMinMaxOrigin)

MSII = os.environ["MSII_EXE"]
SAMPLES = os.environ["MSII_SAMPLES_EXE"]
PLUGINS = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir)

# The DEMs: 1 m cells, hills of 4 m; with HOLES, nodata patches that msii fills (and warns
# about).
TERRAIN = ["terrain", "--geotiff", "--spacing", "1", "--relief", "4", "--hill-width", "25", "-q"]
HOLES = ["--holes", "5", "--hole-size", "2"]

# A profile of its own: the user's Processing settings (such as "msii program") stay out.
os.environ["QGIS_CUSTOM_CONFIG_PATH"] = tempfile.mkdtemp(prefix="msii-qgis-test-")
_app = QgsApplication([], False)  # kept for the whole run: QGIS needs one application


@pytest.fixture(scope="session")
def processing():
    """Processing initialised with the plugin's provider, as qgis_process loads it (iface None)."""
    _app.initQgis()
    sys.path.append(os.path.join(QgsApplication.pkgDataPath(), "python", "plugins"))
    sys.path.insert(0, os.path.abspath(PLUGINS))
    sys.dont_write_bytecode = True  # no __pycache__ in the source tree
    from processing.core.Processing import Processing
    Processing.initialize()
    import msii_processing
    plugin = msii_processing.classFactory(None)
    plugin.initProcessing()
    import processing as module
    yield module
    plugin.unload()
    shutil.rmtree(os.environ["QGIS_CUSTOM_CONFIG_PATH"], ignore_errors=True)


def generate(path, width, height, *extra):
    subprocess.run([SAMPLES, *TERRAIN, "--width", str(width), "--height", str(height), *extra,
                    "-o", str(path)], check=True)
    return str(path)


@pytest.fixture(scope="session")
def data(tmp_path_factory):
    """The DEMs, and a feature GeoTIFF with V at every radius (for render, metric, smooth),
    in one folder; each test writes into a subfolder of its own."""
    folder = tmp_path_factory.mktemp("qgis")
    generate(folder / "dem.tif", 120, 90, *HOLES)
    msii(folder, "compute", "dem.tif", "-r", "10", "--bands", "quality,V", "--raster-output", "features.tif")
    return folder


def msii(folder, *arguments):
    """Runs the msii command in @p folder, as a user would."""
    subprocess.run([MSII, *arguments], cwd=folder, check=True, stderr=subprocess.DEVNULL)


def subfolder(data, name):
    folder = data / name
    folder.mkdir()
    return folder


def assert_same_file(ours, theirs):
    """The two files exist, are not empty, and are equal byte for byte."""
    for path in (ours, theirs):
        assert os.path.isfile(path), path
        assert os.path.getsize(path) > 0, path
    assert filecmp.cmp(ours, theirs, shallow=False), f"{ours} differs from {theirs}"


def leftovers(folder):
    """Files msii writes while it works: temporary names (engine/src/io/atomic_file.cpp) and
    the GeoTIFF's intermediate."""
    return glob.glob(os.path.join(folder, ".*.tmp-*")) + glob.glob(os.path.join(folder, "*.part*"))


class Recorder(QgsProcessingFeedback):
    """Records what the algorithm reports; cancels at the first progress report if asked to."""

    def __init__(self, cancel_on_progress=False):
        super().__init__()
        self.progress, self.texts, self.warnings, self.cancelled_at = [], [], [], None
        self.cancel_on_progress = cancel_on_progress
        self.progressChanged.connect(self.on_progress)

    def on_progress(self, value):
        self.progress.append(value)
        if self.cancel_on_progress and self.cancelled_at is None:
            self.cancelled_at = time.monotonic()
            self.cancel()

    def setProgressText(self, text):
        self.texts.append(text)
        super().setProgressText(text)

    def pushWarning(self, text):
        self.warnings.append(text)
        super().pushWarning(text)


def test_compute_equals_the_command(processing, data):
    """1. msii:compute with the defaults writes the command's GeoTIFF, byte for byte, and its
    JSON record; the input given by another path (absolute here, relative there) changes nothing."""
    folder = subfolder(data, "compute")
    msii(folder, "compute", "../dem.tif", "-r", "10", "--raster-output", "cli.tif")
    out = str(folder / "out.tif")
    result = processing.run("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 10, "OUTPUT": out})
    assert result["OUTPUT"] == out
    assert result["RECORD"] == str(folder / "out.json") and os.path.getsize(result["RECORD"]) > 0
    assert_same_file(out, str(folder / "cli.tif"))


def test_compute_options_equal_the_command(processing, data):
    """2. The same with every option other than its default: -n, --bands, --border mask,
    --fill-holes, --float32."""
    folder = subfolder(data, "compute_options")
    msii(folder, "compute", "../dem.tif", "-r", "10", "-n", "6", "--bands", "quality,V", "--border", "mask",
         "--fill-holes", "5", "--float32", "--raster-output", "cli.tif")
    out = str(folder / "out.tif")
    processing.run("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 10, "SCALES": 6,
                                    "BANDS": "quality,V", "BORDER": "mask", "FILL_HOLES": 5,
                                    "FLOAT32": True, "OUTPUT": out})
    assert_same_file(out, str(folder / "cli.tif"))
    # The options reached msii: float32, 7 bands (quality and V at 6 radii).
    dataset = gdal.Open(out)
    assert dataset.RasterCount == 7 and dataset.GetRasterBand(1).DataType == gdal.GDT_Float32


def test_render_equals_the_command(processing, data):
    """3. msii:render writes the command's PNG, with options other than the defaults."""
    folder = subfolder(data, "render")
    msii(folder, "render", "../features.tif", "--show", "V_05", "--colormap", "cividis", "--shade",
         "--pixels", "600", "-o", "cli.png")
    out = str(folder / "out.png")
    processing.run("msii:render", {"INPUT": str(data / "features.tif"), "SHOW": "V_05", "COLORMAP": "cividis",
                                   "SHADE": True, "PIXELS": 600, "OUTPUT": out})
    assert_same_file(out, str(folder / "cli.png"))


@pytest.mark.parametrize("options, parameters", [
    ([], {}),
    (["-m", "l2w", "--reference", "vector:" + ",".join(["0.45"] * 10)],
     {"METRIC": "l2w", "REFERENCE": "vector:" + ",".join(["0.45"] * 10)}),
], ids=["defaults", "options"])
def test_metric_equals_the_command(processing, data, options, parameters):
    """4a. msii:metric writes the command's GeoTIFF on the input's grid."""
    folder = subfolder(data, "metric_" + ("options" if options else "defaults"))
    msii(folder, "metric", "../features.tif", *options, "-o", "cli.tif")
    out = str(folder / "out.tif")
    processing.run("msii:metric", {"INPUT": str(data / "features.tif"), "OUTPUT": out, **parameters})
    assert_same_file(out, str(folder / "cli.tif"))


@pytest.mark.parametrize("options, parameters", [
    ([], {}),
    (["--filter", "median", "-k", "5", "--properties", "quality,V_05"],
     {"FILTER": "median", "ITERATIONS": 5, "PROPERTIES": "quality,V_05"}),
], ids=["defaults", "options"])
def test_smooth_equals_the_command(processing, data, options, parameters):
    """4b. msii:smooth writes the command's GeoTIFF on the input's grid."""
    folder = subfolder(data, "smooth_" + ("options" if options else "defaults"))
    msii(folder, "smooth", "../features.tif", *options, "-o", "cli.tif")
    out = str(folder / "out.tif")
    processing.run("msii:smooth", {"INPUT": str(data / "features.tif"), "OUTPUT": out, **parameters})
    assert_same_file(out, str(folder / "cli.tif"))


def test_progress_and_warnings_reach_the_feedback(processing, data):
    """5. msii's progress lines become progress (values inside the range, 100 at the end) and
    stage texts; 6. its warnings (the DEM's holes were filled) become warnings."""
    folder = subfolder(data, "progress")
    dem = generate(folder / "dem.tif", 400, 300, *HOLES)
    feedback = Recorder()
    processing.run("msii:compute", {"INPUT": dem, "RADIUS": 10, "OUTPUT": str(folder / "out.tif")},
                   feedback=feedback)
    assert any(0 < p < 100 for p in feedback.progress), feedback.progress
    assert feedback.progress[-1] >= 99.9
    assert any(text.startswith("V and S") for text in feedback.texts), feedback.texts
    assert any(w.startswith("msii: warning: ") and "filled 5 holes" in w for w in feedback.warnings), feedback.warnings


def test_error_is_msii_s_line_and_leaves_no_output(processing, data):
    """7. A DEM without a coordinate system: the exception holds msii's one error line (the
    command's own), and nothing is written."""
    folder = subfolder(data, "error")
    source = gdal.Open(str(data / "dem.tif"))
    nocrs = str(folder / "nocrs.tif")
    copy = gdal.GetDriverByName("GTiff").Create(nocrs, source.RasterXSize, source.RasterYSize, 1, gdal.GDT_Float32)
    copy.SetGeoTransform(source.GetGeoTransform())
    copy.GetRasterBand(1).WriteArray(source.GetRasterBand(1).ReadAsArray())
    copy = None
    assert gdal.Open(nocrs).GetSpatialRef() is None

    command = subprocess.run([MSII, "compute", nocrs, "-r", "10", "--raster-output", str(folder / "cli.tif")],
                             capture_output=True, text=True)
    assert command.returncode == 1
    line = [l for l in command.stderr.splitlines() if l.startswith("msii: error: ")]
    assert len(line) == 1 and "coordinate system" in line[0], command.stderr

    out = folder / "out.tif"
    with pytest.raises(QgsProcessingException) as raised:
        processing.run("msii:compute", {"INPUT": nocrs, "RADIUS": 10, "OUTPUT": str(out)})
    assert line[0] in str(raised.value)
    assert not out.exists() and not (folder / "out.json").exists()
    assert not leftovers(str(folder))


def test_a_layer_that_is_no_file_is_refused(processing, data):
    """msii reads files: a raster held in GDAL's memory is refused, with what to do."""
    folder = subfolder(data, "not_a_file")
    with open(data / "dem.tif", "rb") as f:
        gdal.FileFromMemBuffer("/vsimem/dem.tif", f.read())
    layer = QgsRasterLayer("/vsimem/dem.tif", "in memory", "gdal")
    assert layer.isValid()
    with pytest.raises(QgsProcessingException) as raised:
        processing.run("msii:compute", {"INPUT": layer, "RADIUS": 10, "OUTPUT": str(folder / "out.tif")})
    gdal.Unlink("/vsimem/dem.tif")
    assert "is not a raster file" in str(raised.value) and "Save it as a GeoTIFF" in str(raised.value)
    assert os.listdir(folder) == []


def test_radius_0_gives_msii_s_suggestion(processing, data):
    """RADIUS 0: msii names a radius for the DEM, in its one error line, and computes nothing."""
    folder = subfolder(data, "suggestion")
    with pytest.raises(QgsProcessingException) as raised:
        processing.run("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 0, "OUTPUT": str(folder / "out.tif")})
    assert "msii: error: --radius is required" in str(raised.value) and "try --radius 15" in str(raised.value)
    assert os.listdir(folder) == []


def test_cancel_stops_msii_and_leaves_nothing(processing, data):
    """8. Cancel at the first progress report of a large DEM stops msii within seconds, and
    leaves neither the output nor a temporary file."""
    folder = subfolder(data, "cancel")
    dem = generate(data / "big.tif", 1500, 1500)  # about a minute of computing on 2 cores
    feedback = Recorder(cancel_on_progress=True)
    out = folder / "out.tif"
    with pytest.raises(QgsProcessingException) as raised:
        processing.run("msii:compute", {"INPUT": dem, "RADIUS": 10, "OUTPUT": str(out)}, feedback=feedback)
    stopped = time.monotonic() - feedback.cancelled_at
    assert "Cancelled" in str(raised.value)
    assert stopped < 5, f"msii took {stopped:.1f} s to stop"
    assert not out.exists() and not (folder / "out.json").exists()
    assert os.listdir(folder) == [], os.listdir(folder)


def test_compute_output_loads_styled_on_quality(processing, data):
    """9. Loaded into the project, the output is a pseudocolour of the band named quality
    (found by name: it is the second band here), min / max the cumulative cut 2–98 %."""
    folder = subfolder(data, "style")
    out = str(folder / "out.tif")
    processing.runAndLoadResults("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 10,
                                                  "BANDS": "V_05,quality", "OUTPUT": out})
    layers = [l for l in QgsProject.instance().mapLayers().values() if l.source() == out]
    assert len(layers) == 1
    layer = layers[0]
    assert gdal.Open(out).GetRasterBand(2).GetDescription() == "quality"
    renderer = layer.renderer()
    assert renderer.type() == "singlebandpseudocolor"
    assert renderer.band() == 2
    limits = renderer.minMaxOrigin()
    assert limits.limits() == QgsRasterMinMaxOrigin.CumulativeCut
    assert (limits.cumulativeCutLower(), limits.cumulativeCutUpper()) == (0.02, 0.98)
    low, high = layer.dataProvider().cumulativeCut(2, 0.02, 0.98, layer.extent(), int(QgsRasterLayer.SAMPLE_SIZE))
    assert (renderer.classificationMin(), renderer.classificationMax()) == (low, high)
    assert 0.4 < low < 0.5 < high < 0.6  # V̂ around the flat 0.5, a cut inside the values
    items = renderer.shader().rasterShaderFunction().colorRampItemList()
    assert items[0].color.name() == "#440154" and items[-1].color.name() == "#fde725"  # viridis


def test_provider_has_the_four_algorithms(processing):
    """10. The provider msii lists exactly msii:compute, render, metric and smooth."""
    provider = QgsApplication.processingRegistry().providerById("msii")
    assert provider is not None and provider.name() == "msii"
    assert sorted(a.id() for a in provider.algorithms()) == ["msii:compute", "msii:metric", "msii:render",
                                                            "msii:smooth"]


def test_missing_program_says_what_to_set(processing, data, monkeypatch):
    """A program that is not there: the error names where it was set, before running anything."""
    monkeypatch.setenv("MSII_EXE", str(data / "no-such-msii"))
    with pytest.raises(QgsProcessingException) as raised:
        processing.run("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 10,
                                        "OUTPUT": str(data / "never.tif")})
    assert "MSII_EXE" in str(raised.value) and "no-such-msii" in str(raised.value)
    assert not (data / "never.tif").exists()


def test_the_setting_comes_before_the_environment(processing, data, monkeypatch):
    """The provider setting "msii program" is used before MSII_EXE (set in memory only, not in
    the user's QGIS settings)."""
    from processing.core.ProcessingConfig import ProcessingConfig
    setting = ProcessingConfig.settings["MSII_PROGRAM"]
    monkeypatch.setattr(setting, "value", MSII)
    monkeypatch.setenv("MSII_EXE", str(data / "no-such-msii"))
    out = data / "setting.tif"
    processing.run("msii:compute", {"INPUT": str(data / "dem.tif"), "RADIUS": 10, "OUTPUT": str(out)})
    assert out.stat().st_size > 0
