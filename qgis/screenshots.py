# SPDX-License-Identifier: GPL-3.0-or-later
"""Makes the pictures of docs/terrain.md's "In QGIS": the Processing Toolbox with msii's
algorithms and the msii:compute dialog (docs/images/qgis-compute-dialog.png), and the
result of msii:compute on a generated DEM in the map, styled on quality
(docs/images/qgis-result.png). Runs inside the QGIS application, under Xvfb.

Usage, from the repository's root, with msii built:
    rm -rf /tmp/msii-qgis-profile && MSII_EXE=$PWD/build/tools/msii \\
    MSII_SAMPLES_EXE=$PWD/build/samples/msii-samples QGIS_PLUGINPATH=$PWD/qgis \\
    xvfb-run -a -s "-screen 0 1400x900x24" qgis --nologo --noversioncheck \\
        --profiles-path /tmp/msii-qgis-profile --code qgis/screenshots.py
"""
# --code runs this file with exec() once QGIS has started: no __file__, and `iface` is QGIS's.

import os
import shutil
import subprocess
import tempfile
import traceback

from qgis.core import QgsProject
from qgis.PyQt.QtCore import QCoreApplication, QRect, QTimer
from qgis.PyQt.QtGui import QGuiApplication
from qgis.PyQt.QtWidgets import QDockWidget
from qgis.utils import iface, loadPlugin, plugins, startPlugin

import processing

IMAGES = os.path.abspath(os.environ.get("MSII_SCREENSHOTS_DIR", os.path.join("docs", "images")))
WORK = tempfile.mkdtemp(prefix="msii-screenshots-")
# 600 x 450 m of hills at 1 m, with small nodata patches that msii fills.
TERRAIN = ["terrain", "--geotiff", "--width", "600", "--height", "450", "--spacing", "1",
           "--relief", "4", "--hill-width", "25", "--holes", "8", "--hole-size", "2", "-q"]
RADIUS = 15


def settle(milliseconds=1500):
    """Lets QGIS draw (the map renders in the background) for @p milliseconds."""
    deadline = QTimer()
    deadline.setSingleShot(True)
    deadline.start(milliseconds)
    while deadline.isActive():
        QCoreApplication.processEvents()


def grab(name):
    """Saves the screen as IMAGES/NAME and prints its size."""
    settle()
    path = os.path.join(IMAGES, name)
    QGuiApplication.primaryScreen().grabWindow(0).save(path, "PNG", 0)
    print(f"{path}: {os.path.getsize(path) // 1024} KB")


def load_plugin():
    if "msii_processing" not in plugins:
        loadPlugin("msii_processing")
        startPlugin("msii_processing")


def window():
    iface.mainWindow().setGeometry(QRect(0, 0, 1400, 900))
    for dock in iface.mainWindow().findChildren(QDockWidget):  # only the layers and the toolbox
        if dock.objectName() not in ("Layers", "ProcessingToolbox"):
            dock.hide()
    settle(500)


def compute_dialog(dem):
    """(a) The toolbox filtered to msii, and the msii:compute dialog with the DEM chosen."""
    toolbox = plugins["processing"].toolbox
    toolbox.show()
    toolbox.searchBox.setText("msii")
    settle(300)
    iface.mapCanvas().zoomToFullExtent()  # in the canvas the toolbox narrowed
    dialog = processing.createAlgorithmDialog("msii:compute", {"INPUT": dem, "RADIUS": RADIUS})
    dialog.setGeometry(QRect(300, 110, 720, 700))
    dialog.show()
    grab("qgis-compute-dialog.png")
    dialog.close()
    toolbox.hide()


def result(dem):
    """(b) The features of the DEM, as msii:compute loads them, over the DEM."""
    output = os.path.join(WORK, "dem.msii.tif")
    processing.runAndLoadResults("msii:compute", {"INPUT": dem, "RADIUS": RADIUS, "OUTPUT": output})
    settle(500)
    # The legend of the features (band name and colour ramp) open, the DEM's closed.
    view = iface.layerTreeView()
    for node in QgsProject.instance().layerTreeRoot().findLayers():
        view.setExpanded(view.node2index(node), node.layer().source() == output)
    iface.mapCanvas().refresh()
    grab("qgis-result.png")


def main():
    try:
        os.makedirs(IMAGES, exist_ok=True)
        dem = os.path.join(WORK, "dem.tif")
        subprocess.run([os.environ.get("MSII_SAMPLES_EXE", "msii-samples"), *TERRAIN, "-o", dem], check=True)
        load_plugin()
        window()
        layer = iface.addRasterLayer(dem, "dem")
        QgsProject.instance().setCrs(layer.crs())
        compute_dialog(dem)
        result(dem)
    except Exception:  # QGIS would otherwise stay open, under Xvfb, with nobody to close it
        traceback.print_exc()
    QgsProject.instance().clear()  # nothing to save: QGIS quits without asking
    shutil.rmtree(WORK, ignore_errors=True)
    QTimer.singleShot(0, iface.actionExit().trigger)


# After QGIS's own start-up has finished drawing its window.
QTimer.singleShot(2000, main)
