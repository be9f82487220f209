"""Loads a scan, computes its integral invariants with msii, and plots V at three radii
(docs/python.md).   python3 examples/plot_volume.py SCAN RADIUS OUT.png"""
import sys

import matplotlib

matplotlib.use("Agg")  # files, no window
import matplotlib.pyplot as plt
import matplotlib.tri
import numpy as np

import msii

scan, radius, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
vertices, faces = msii.read_mesh(scan)
result = msii.compute(vertices, faces, radius, invariants="V")
for warning in result.warnings:
    print("msii:", warning.message)

fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
for ax, j in zip(axes, [3, 7, 15]):  # r = R/4, R/2 and R (N = 16)
    v = result.V[:, j]
    masked = np.isnan(v)  # NaN: the ball reaches the scan's open border
    lo, hi = np.percentile(v[~masked], [1, 99])
    # Seen from above (x, y), triangles with a masked vertex left out.
    mesh = matplotlib.tri.Triangulation(vertices[:, 0], vertices[:, 1], faces, mask=masked[faces].any(axis=1))
    colours = ax.tripcolor(mesh, np.nan_to_num(v, nan=lo), shading="gouraud", cmap="viridis", vmin=lo, vmax=hi)
    ax.set_title("V at r = %.3g (%d of %d vertices)" % (result.radii[j], (~masked).sum(), len(v)))
    ax.set_aspect("equal")
    fig.colorbar(colours, ax=ax, shrink=0.8)
fig.savefig(out, dpi=120)
print("%d vertices, voxel %.4g -> %s" % (len(vertices), result.voxel_size, out))
