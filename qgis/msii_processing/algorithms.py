# SPDX-License-Identifier: GPL-3.0-or-later
"""The algorithms msii:compute, msii:render, msii:metric and msii:smooth: each maps its
parameters to the options of one msii command (docs/cli.md) and runs it (program.py)."""

import os

from qgis.core import (QgsProcessingAlgorithm, QgsProcessingException, QgsProcessingOutputFile,
                       QgsProcessingParameterBoolean, QgsProcessingParameterDefinition,
                       QgsProcessingParameterDistance, QgsProcessingParameterEnum,
                       QgsProcessingParameterFileDestination, QgsProcessingParameterNumber,
                       QgsProcessingParameterRasterDestination, QgsProcessingParameterRasterLayer,
                       QgsProcessingParameterString, QgsProviderRegistry)
from qgis.PyQt.QtCore import QCoreApplication

from . import program, style

COLORMAPS = ["viridis", "cividis", "gray", "coolwarm"]
BORDERS = ["continue", "mask"]
METRICS = ["mahalanobis", "l1", "l2", "linf", "lp", "l1w", "l2w", "linfw", "lpw", "cosine",
           "correlation", "autocorrelation", "tanimoto", "neuclid"]
FILTERS = ["mean", "median"]


def number(value):
    """@p value as msii reads it back to the same double (Python's shortest round trip)."""
    return repr(float(value))


class MsiiAlgorithm(QgsProcessingAlgorithm):
    """What the four algorithms share: their group, and reading a raster parameter as a file."""

    def group(self):
        return self.tr("Relief")

    def groupId(self):
        return "relief"

    def createInstance(self):
        return type(self)()

    def tr(self, text):
        return QCoreApplication.translate("msii", text)

    @staticmethod
    def given(parameters, name):
        """Whether the optional parameter @p name has a value (else msii's default applies)."""
        value = parameters.get(name)
        return value is not None and value != "" and not (hasattr(value, "isNull") and value.isNull())

    def raster_file(self, parameters, name, context):
        """The file of the raster layer @p name: msii reads the file itself, so the layer
        must be one file that GDAL opens (not a database table, a web service or a layer
        inside a multi-layer file)."""
        layer = self.parameterAsRasterLayer(parameters, name, context)
        if layer is None:
            raise QgsProcessingException(self.invalidRasterError(parameters, name))
        parts = QgsProviderRegistry.instance().decodeUri(layer.providerType(), layer.source())
        path = parts.get("path", "")
        inner = parts.get("layerName") or parts.get("subdataset")
        if layer.providerType() != "gdal" or inner or not os.path.isfile(path):
            raise QgsProcessingException(self.tr(
                "msii reads rasters from files: '{}' is not a raster file that GDAL opens "
                "(it is {}). Save it as a GeoTIFF first (Export ▸ Save As…).").format(
                    layer.name(), layer.source()))
        return os.path.abspath(path)


class ComputeAlgorithm(MsiiAlgorithm):
    """msii compute on a DEM: the feature GeoTIFF on the DEM's grid."""

    def name(self):
        return "compute"

    def displayName(self):
        return self.tr("Integral invariants of a DEM")

    def shortHelpString(self):
        return self.tr(
            "<p>Computes the integral invariants of a DEM at N radii r<sub>j</sub> = j·R/N "
            "(<code>msii compute DEM -r R --raster-output OUTPUT</code>) and writes them as a "
            "GeoTIFF on the DEM's grid, one band per feature, with a JSON record of the run next "
            "to it (<i>OUTPUT stem</i>.json).</p>"
            "<p>V̂ (band <b>quality</b>: V̂ at R) is the share of a ball around each cell that lies "
            "below the ground: 0.5 on a plane, less on crests, banks and mounds, more in ditches, "
            "hollows and pits. The layer loads with a pseudocolour style on <b>quality</b>, "
            "min / max from a cumulative count cut of 2–98 %.</p>"
            "<p><b>R</b> in the DEM's units (metres for UTM): about the size of the largest "
            "feature to detect: 5–10 m for ditches, pits and field boundaries, 15–30 m for "
            "banks, barrows and terraces, more for hill forts. Left at 0, msii names a radius "
            "for this DEM (15 cells, at most a tenth of the extent) and computes nothing.</p>"
            "<p><b>Number of radii</b> (-n): default R / cell size, between 4 and 16, so that "
            "the smallest radius is a whole cell.</p>"
            "<p><b>Bands</b> (--bands): the features written, e.g. <code>quality,V_04,V_16,height</code>; "
            "a letter alone is that invariant at every radius (<code>quality,V</code>). Default: "
            "quality and V̂ at a quarter, half, three quarters of R and R. Only the invariants the "
            "bands need are computed.</p>"
            "<p><b>Fill holes up to</b> (--fill-holes): nodata gaps up to this perimeter are "
            "filled for the computation (default π·R). <b>Border</b> (--border): <i>continue</i> "
            "continues the surface past the DEM's edge and open gaps, so every cell has values "
            "(the band filled_share says how much rests on it); <i>mask</i> gives NaN where a "
            "ball reaches them. <b>Float32</b> (--float32): float bands instead of 16-bit "
            "integers scaled to 1.5e-5 (3 times the size).</p>"
            "<p>The DEM must be in a projected coordinate system; msii refuses rasters "
            "without one, or in degrees, with the fix. See docs/terrain.md.</p>")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", self.tr("DEM")))
        radius = QgsProcessingParameterDistance("RADIUS", self.tr("Largest radius R"),
                                                parentParameterName="INPUT", minValue=0.0)
        self.addParameter(radius)
        self.addParameter(QgsProcessingParameterNumber(
            "SCALES", self.tr("Number of radii N"), QgsProcessingParameterNumber.Integer,
            optional=True, minValue=1, maxValue=256))
        self.addParameter(QgsProcessingParameterString(
            "BANDS", self.tr("Bands (e.g. quality,V)"), optional=True))
        self.addParameter(QgsProcessingParameterDistance(
            "FILL_HOLES", self.tr("Fill holes up to this perimeter (default π·R)"),
            parentParameterName="INPUT", optional=True, minValue=0.0))
        self.addParameter(QgsProcessingParameterEnum(
            "BORDER", self.tr("At the DEM's edge and open gaps"), BORDERS, defaultValue="continue",
            usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterBoolean(
            "FLOAT32", self.tr("Float32 bands"), defaultValue=False))
        self.addParameter(QgsProcessingParameterRasterDestination("OUTPUT", self.tr("Features")))
        self.addOutput(QgsProcessingOutputFile("RECORD", self.tr("JSON record of the run")))

    def processAlgorithm(self, parameters, context, feedback):
        dem = self.raster_file(parameters, "INPUT", context)
        output = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        arguments = ["compute", dem]
        radius = self.parameterAsDouble(parameters, "RADIUS", context)
        if radius > 0:  # else msii refuses with a radius for this DEM
            arguments += ["-r", number(radius)]
        if self.given(parameters, "SCALES"):
            arguments += ["-n", str(self.parameterAsInt(parameters, "SCALES", context))]
        bands = self.parameterAsString(parameters, "BANDS", context).strip()
        if bands:
            arguments += ["--bands", bands]
        if self.given(parameters, "FILL_HOLES"):
            arguments += ["--fill-holes", number(self.parameterAsDouble(parameters, "FILL_HOLES", context))]
        if self.parameterAsEnumString(parameters, "BORDER", context) == "mask":
            arguments += ["--border", "mask"]
        if self.parameterAsBoolean(parameters, "FLOAT32", context):
            arguments += ["--float32"]
        arguments += ["--raster-output", output]

        record = os.path.splitext(output)[0] + ".json"
        program.run(arguments, feedback, outputs=[output, record])
        style.load_styled(context, output)
        return {"OUTPUT": output, "RECORD": record}


class RenderAlgorithm(MsiiAlgorithm):
    """msii render of a feature GeoTIFF: a PNG with colour bar and scale bar."""

    def name(self):
        return "render"

    def displayName(self):
        return self.tr("Picture of features (PNG)")

    def shortHelpString(self):
        return self.tr(
            "<p>Draws a GeoTIFF of msii:compute as a PNG picture "
            "(<code>msii render INPUT --show SHOW --colormap COLORMAP --pixels PIXELS -o OUTPUT</code>), "
            "one picture pixel per cell (blocks of cells averaged beyond the size), with a "
            "colour bar and a scale bar in the raster's units. The colour range is the 1st to "
            "99th percentile.</p>"
            "<p><b>Show</b>: a band by name (quality, V_04, …). <b>Shade</b>: shades the colours "
            "with the DEM's relief (found through the GeoTIFF's MSII_INPUT metadata, or its "
            "height band).</p>")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", self.tr("Features (GeoTIFF of msii:compute)")))
        self.addParameter(QgsProcessingParameterString("SHOW", self.tr("Show band"), defaultValue="quality"))
        self.addParameter(QgsProcessingParameterEnum(
            "COLORMAP", self.tr("Colour map"), COLORMAPS, defaultValue="viridis", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterBoolean("SHADE", self.tr("Shade with the relief"), defaultValue=False))
        self.addParameter(QgsProcessingParameterNumber(
            "PIXELS", self.tr("Longer side in pixels"), QgsProcessingParameterNumber.Integer,
            defaultValue=2048, minValue=16, maxValue=16384))
        self.addParameter(QgsProcessingParameterFileDestination(
            "OUTPUT", self.tr("Picture"), self.tr("PNG files (*.png)")))

    def processAlgorithm(self, parameters, context, feedback):
        features = self.raster_file(parameters, "INPUT", context)
        output = self.parameterAsFileOutput(parameters, "OUTPUT", context)
        arguments = ["render", features,
                     "--show", self.parameterAsString(parameters, "SHOW", context).strip() or "quality",
                     "--colormap", self.parameterAsEnumString(parameters, "COLORMAP", context)]
        if self.parameterAsBoolean(parameters, "SHADE", context):
            arguments += ["--shade"]
        arguments += ["--pixels", str(self.parameterAsInt(parameters, "PIXELS", context)), "-o", output]
        program.run(arguments, feedback, outputs=[output])
        return {"OUTPUT": output}


class MetricAlgorithm(MsiiAlgorithm):
    """msii metric of a feature GeoTIFF: one value per cell, a GeoTIFF on the same grid."""

    def name(self):
        return "metric"

    def displayName(self):
        return self.tr("Metric of the feature vectors")

    def shortHelpString(self):
        return self.tr(
            "<p>One value per cell from its feature vector: its distance to a reference, by "
            "default to the flat surface (<code>msii metric INPUT -m METRIC -i INVARIANTS "
            "--reference REFERENCE -o OUTPUT</code>). Writes a float32 GeoTIFF on the input's grid "
            "with the bands quality and f_<i>metric</i>, both the metric.</p>"
            "<p>The input needs the invariants at every radius: compute it with bands "
            "<code>quality,V</code> (and S, P, L for those invariants).</p>"
            "<p><b>Metric</b>: mahalanobis (Eq. 11 of the paper, default), l1, l2, linf, lp "
            "(p-norms of x − o), their scale-weighted forms l1w … lpw, cosine, correlation, "
            "autocorrelation, tanimoto (these need a reference other than flat) and neuclid. "
            "<b>Invariants</b>: V (default), or several, as V,P. <b>Reference</b>: flat, "
            "vertex:INDEX, point:X,Y,Z or vector:V1,V2,…</p>")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", self.tr("Features (GeoTIFF of msii:compute)")))
        self.addParameter(QgsProcessingParameterEnum(
            "METRIC", self.tr("Metric"), METRICS, defaultValue="mahalanobis", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterString("INVARIANTS", self.tr("Invariants"), defaultValue="V"))
        self.addParameter(QgsProcessingParameterString("REFERENCE", self.tr("Reference"), defaultValue="flat"))
        p = QgsProcessingParameterNumber("P", self.tr("p of lp and lpw"), QgsProcessingParameterNumber.Double,
                                         optional=True, minValue=1e-9)
        p.setFlags(p.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
        self.addParameter(p)
        self.addParameter(QgsProcessingParameterRasterDestination("OUTPUT", self.tr("Metric")))

    def processAlgorithm(self, parameters, context, feedback):
        features = self.raster_file(parameters, "INPUT", context)
        output = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        arguments = ["metric", features,
                     "-m", self.parameterAsEnumString(parameters, "METRIC", context),
                     "-i", self.parameterAsString(parameters, "INVARIANTS", context).strip() or "V",
                     "--reference", self.parameterAsString(parameters, "REFERENCE", context).strip() or "flat"]
        if self.given(parameters, "P"):
            arguments += ["--p", number(self.parameterAsDouble(parameters, "P", context))]
        arguments += ["-o", output]
        program.run(arguments, feedback, outputs=[output])
        style.load_styled(context, output)
        return {"OUTPUT": output}


class SmoothAlgorithm(MsiiAlgorithm):
    """msii smooth of a feature or metric GeoTIFF: the chosen bands, smoothed."""

    def name(self):
        return "smooth"

    def displayName(self):
        return self.tr("Smooth (1-ring mean or median)")

    def shortHelpString(self):
        return self.tr(
            "<p>The paper's fast 1-ring smoothing, repeated k times, of chosen bands of a "
            "GeoTIFF of msii:compute or msii:metric (<code>msii smooth INPUT --filter FILTER -k "
            "ITERATIONS --properties PROPERTIES -o OUTPUT</code>). Writes a float32 GeoTIFF on "
            "the input's grid with the chosen bands, smoothed.</p>"
            "<p><b>Filter</b>: mean (default) or median. <b>Passes</b>: 30 by default, as in the "
            "paper; k passes act like a larger filter. <b>Bands</b>: comma-separated names "
            "(default quality).</p>")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", self.tr("Features or metric (GeoTIFF)")))
        self.addParameter(QgsProcessingParameterEnum(
            "FILTER", self.tr("Filter"), FILTERS, defaultValue="mean", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterNumber(
            "ITERATIONS", self.tr("Passes"), QgsProcessingParameterNumber.Integer, defaultValue=30, minValue=0))
        self.addParameter(QgsProcessingParameterString("PROPERTIES", self.tr("Bands to smooth"), defaultValue="quality"))
        self.addParameter(QgsProcessingParameterRasterDestination("OUTPUT", self.tr("Smoothed")))

    def processAlgorithm(self, parameters, context, feedback):
        features = self.raster_file(parameters, "INPUT", context)
        output = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        arguments = ["smooth", features,
                     "--filter", self.parameterAsEnumString(parameters, "FILTER", context),
                     "-k", str(self.parameterAsInt(parameters, "ITERATIONS", context)),
                     "--properties", self.parameterAsString(parameters, "PROPERTIES", context).strip() or "quality",
                     "-o", output]
        program.run(arguments, feedback, outputs=[output])
        style.load_styled(context, output)
        return {"OUTPUT": output}


ALGORITHMS = [ComputeAlgorithm, RenderAlgorithm, MetricAlgorithm, SmoothAlgorithm]
