# SPDX-License-Identifier: GPL-3.0-or-later
"""The Processing provider `msii`: its algorithms and its setting "msii program"."""

import os

from qgis.core import QgsProcessingProvider
from qgis.PyQt.QtGui import QIcon

from .algorithms import ALGORITHMS
from .program import PROGRAM_SETTING

ICON = os.path.join(os.path.dirname(__file__), "icon.svg")


class MsiiProvider(QgsProcessingProvider):

    def id(self):
        return "msii"

    def name(self):
        return "msii"

    def longName(self):
        return "msii: Multi-Scale Integral Invariants"

    def icon(self):
        return QIcon(ICON)

    def svgIconPath(self):
        return ICON

    def load(self):
        # Processing's options dialog lists the settings of each group that is not its own
        # under Providers: here Providers ▸ msii ▸ msii program.
        from processing.core.ProcessingConfig import ProcessingConfig, Setting
        ProcessingConfig.settingIcons[self.name()] = self.icon()
        ProcessingConfig.addSetting(Setting(
            self.name(), PROGRAM_SETTING, "msii program", "", valuetype=Setting.FILE,
            placeholder="the MSII_EXE variable, the installed msii, else msii on the PATH"))
        ProcessingConfig.readSettings()
        self.refreshAlgorithms()
        return True

    def unload(self):
        from processing.core.ProcessingConfig import ProcessingConfig
        if PROGRAM_SETTING in ProcessingConfig.settings:
            ProcessingConfig.removeSetting(PROGRAM_SETTING)

    def loadAlgorithms(self):
        for algorithm in ALGORITHMS:
            self.addAlgorithm(algorithm())

    def defaultRasterFileExtension(self):
        return "tif"

    def supportedOutputRasterLayerExtensions(self):
        # msii writes GeoTIFF (Cloud-Optimized) whatever the name.
        return ["tif", "tiff"]

    def supportsNonFileBasedOutput(self):
        return False
