# SPDX-License-Identifier: GPL-3.0-or-later
"""msii's QGIS Processing provider: the algorithms msii:compute, msii:render, msii:metric
and msii:smooth, which run the msii program (docs/terrain.md, "In QGIS")."""


def classFactory(iface):
    """QGIS's entry point; @p iface is None in qgis_process and scripts."""
    from .plugin import MsiiPlugin
    return MsiiPlugin(iface)
