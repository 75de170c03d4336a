#!/usr/bin/env python3
"""How far apart two runs' final drapes lie, surface to surface.

Usage: run/rest_distance.py RUN_A RUN_B [RUN_A RUN_B ...]

For each pair of output directories (each with a drape.h5), the final frame's
positions of each run are measured against the other's surface (each quad two
triangles; table1.py's surface_distance): a point's distance to the nearest
point of the other drape, not to the same material point, so cloth that slid
along itself does not count. The finer grid is the reference; the coarser
run is sampled on it (bilinear). Prints the maximum and mean over both
directions (and their RMS) in mm, so that a rest state's
dependence on the path (drag, preconditioner) can be set against the mesh's
own error (the same drape on the next coarser grid).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from table1 import final_positions, on_grid, surface_distance  # noqa: E402


def one_way(x, ref):
    """Distances (m) of the points of x from ref's surface, both sampled on ref's grid."""
    return surface_distance(on_grid(x, ref.shape[0]), ref).ravel()


def pair(a, b):
    xa, xb = final_positions(a), final_positions(b)
    ref, other = (xa, xb) if xa.shape[0] >= xb.shape[0] else (xb, xa)
    d1, d2 = one_way(other, ref), one_way(ref, on_grid(other, ref.shape[0]))
    both = np.concatenate([d1, d2])
    return float(both.max()), float(both.mean()), float(np.sqrt(np.mean(both ** 2)))


def main(argv):
    if len(argv) < 2 or len(argv) % 2:
        sys.exit(__doc__)
    print("%-28s %-28s %9s %9s %9s" % ("A", "B", "max mm", "mean mm", "RMS mm"))
    for a, b in zip(argv[0::2], argv[1::2]):
        mx, mean, rms = pair(a, b)
        print("%-28s %-28s %9.2f %9.2f %9.2f" % (a, b, 1e3 * mx, 1e3 * mean, 1e3 * rms))


if __name__ == "__main__":
    main(sys.argv[1:])
