# SPDX-License-Identifier: GPL-3.0-or-later
"""The style msii's GeoTIFFs load with: singleband pseudocolour on the band named `quality`
(else the first band), min / max from a cumulative count cut of 2–98 %, a viridis ramp, as
docs/terrain.md recommends. QGIS would otherwise show bands 1–3 as red, green and blue."""

from osgeo import gdal
from qgis.core import (QgsColorRampShader, QgsGradientColorRamp, QgsGradientStop,
                       QgsProcessingLayerPostProcessorInterface, QgsRasterLayer,
                       QgsRasterMinMaxOrigin, QgsSingleBandPseudoColorRenderer, QgsStyle)
from qgis.PyQt.QtGui import QColor

CUT_LOWER, CUT_UPPER = 0.02, 0.98


def feature_band(path, name="quality"):
    """The number (1, 2, ...) of the band of @p path whose description is @p name, else 1.
    By description: its number depends on --bands."""
    dataset = gdal.Open(path)
    if dataset is not None:
        for i in range(1, dataset.RasterCount + 1):
            if dataset.GetRasterBand(i).GetDescription() == name:
                return i
    return 1


def viridis():
    """QGIS's own "Viridis" ramp, or one made of viridis's colours at five stops where the
    default style lacks it."""
    ramp = QgsStyle.defaultStyle().colorRamp("Viridis")
    if ramp is not None:
        return ramp
    stops = [QgsGradientStop(0.25, QColor("#3b528b")), QgsGradientStop(0.5, QColor("#21918c")),
             QgsGradientStop(0.75, QColor("#5ec962"))]
    return QgsGradientColorRamp(QColor("#440154"), QColor("#fde725"), False, stops)


def apply(layer):
    """Gives @p layer (an msii GeoTIFF) the pseudocolour style on its feature band."""
    if not isinstance(layer, QgsRasterLayer) or not layer.isValid():
        return
    provider = layer.dataProvider()
    band = feature_band(layer.source())

    # What the Symbology panel's "Cumulative count cut" computes, with QGIS's own sample size;
    # recorded in the renderer so that the panel shows the choice.
    limits = QgsRasterMinMaxOrigin()
    limits.setLimits(QgsRasterMinMaxOrigin.CumulativeCut)
    limits.setCumulativeCutLower(CUT_LOWER)
    limits.setCumulativeCutUpper(CUT_UPPER)
    limits.setExtent(QgsRasterMinMaxOrigin.WholeRaster)
    limits.setStatAccuracy(QgsRasterMinMaxOrigin.Estimated)
    low, high = provider.cumulativeCut(band, CUT_LOWER, CUT_UPPER, provider.extent(),
                                       int(QgsRasterLayer.SAMPLE_SIZE))

    renderer = QgsSingleBandPseudoColorRenderer(provider, band)
    renderer.setMinMaxOrigin(limits)
    renderer.setClassificationMin(low)
    renderer.setClassificationMax(high)
    renderer.createShader(viridis(), QgsColorRampShader.Interpolated, QgsColorRampShader.Continuous)
    layer.setRenderer(renderer)
    layer.triggerRepaint()


class FeatureStyle(QgsProcessingLayerPostProcessorInterface):
    """Styles the output layer once Processing has loaded it."""

    def postProcessLayer(self, layer, context, feedback):
        apply(layer)


# Processing keeps only a pointer to the post-processor: it must outlive the run, so one
# instance lives here, for every run (it holds no state).
_POST_PROCESSOR = FeatureStyle()


def load_styled(context, path):
    """Has the output @p path styled when Processing loads it into a project."""
    if context.willLoadLayerOnCompletion(path):
        context.layerToLoadOnCompletionDetails(path).setPostProcessor(_POST_PROCESSOR)
