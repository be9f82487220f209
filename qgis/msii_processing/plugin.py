# SPDX-License-Identifier: GPL-3.0-or-later
"""The QGIS plugin: registers the Processing provider msii. It has no window of its own, so
it works without a GUI (iface None): in qgis_process and in scripts."""

from qgis.core import QgsApplication

from .provider import MsiiProvider

# The registry owns the provider's C++ side only: were the Python side collected (a script's
# `classFactory(None).initProcessing()` keeps no plugin), its algorithms would vanish with it.
_registered = []


class MsiiPlugin:

    def __init__(self, iface=None):
        self.iface = iface
        self.provider = None

    def initProcessing(self):
        if self.provider is None:
            self.provider = MsiiProvider()
            _registered.append(self.provider)
            QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self):
        self.initProcessing()

    def unload(self):
        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)
            _registered.remove(self.provider)
            self.provider = None
