#!/usr/bin/env python3
"""The best mesh AMRC's criterion could pick on a given cloth state.

Usage: run/amrc_bound.py [--deflection] [--upsample] DRAPE.h5 [MAX_LEVEL] [REFINE ...]

Reads the last frame of a finest-mesh run (drape.h5) and, for each refine
threshold (rad, default 0.1 0.2 0.3 0.5 0.8), builds the quadtree top-down
that AMRC's criterion would keep on that state: a cell of width w stays a leaf
when the mesh lines through its corners turn by at most the threshold at
triples of spacing w. It prints the active particles of that mesh (the work
an AMRC run would do per iteration, were it handed the state) and the RMS
distance of its bilinear surface from the finest one. A bound, not a run:
2:1 balance and hanging particles are left out, and an AMRC run reaches its
own state by its own path. --deflection: amrc.indicator = "deflection", the
turn scaled by w over the coarsest cell's width. --upsample: the state
interpolated (bicubic) onto a grid twice as fine, 2n - 1 particles a side, a
guess at the larger size's rest state before anyone pays for its run. Why it exists: an hour-long Table 1 run is worth
starting only where this leaves most of the cloth coarse.
"""
import sys

import h5py
import numpy as np


def first_and_last_frames(path):
    with h5py.File(path, "r") as f:
        ni, nj = int(f.attrs["ni"]), int(f.attrs["nj"])
        frames = sorted(f["frames"].keys())
        return [f["frames"][k]["positions"][:].reshape(ni, nj, 3) for k in (frames[0], frames[-1])]


def turn(a, b, c):
    """Angle (rad) between the segments a->b and b->c."""
    u, v = b - a, c - b
    cos = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v))
    return float(np.arccos(np.clip(cos, -1.0, 1.0)))


def corner_turns_ok(x, i, j, w, refine):
    """refine: the threshold the turn at spacing w is held to."""
    ni, nj = x.shape[:2]
    if 0 <= i - w and i + w < ni and turn(x[i - w, j], x[i, j], x[i + w, j]) > refine:
        return False
    if 0 <= j - w and j + w < nj and turn(x[i, j - w], x[i, j], x[i, j + w]) > refine:
        return False
    return True


def leaves(x, max_level, refine, deflection=False):
    ni, nj = x.shape[:2]
    out = []

    def visit(i0, j0, level):
        w = 1 << level
        i1, j1 = min(i0 + w, ni - 1), min(j0 + w, nj - 1)
        limit = refine * (1 << max_level) / w if deflection else refine  # turn * w / w_max <= refine
        if level == 0 or all(corner_turns_ok(x, i, j, w, limit) for i in (i0, i1) for j in (j0, j1)):
            out.append((i0, j0, i1, j1))
            return
        h = w // 2
        for di in (0, h):
            for dj in (0, h):
                if i0 + di < ni - 1 and j0 + dj < nj - 1:
                    visit(i0 + di, j0 + dj, level - 1)

    w = 1 << max_level
    for i0 in range(0, ni - 1, w):
        for j0 in range(0, nj - 1, w):
            visit(i0, j0, max_level)
    return out


def bilinear(x, cells):
    y = np.empty_like(x)
    for i0, j0, i1, j1 in cells:
        a = np.linspace(0.0, 1.0, i1 - i0 + 1)[:, None, None]
        b = np.linspace(0.0, 1.0, j1 - j0 + 1)[None, :, None]
        y[i0:i1 + 1, j0:j1 + 1] = ((1 - a) * (1 - b) * x[i0, j0] + a * (1 - b) * x[i1, j0]
                                   + (1 - a) * b * x[i0, j1] + a * b * x[i1, j1])
    return y


def upsample(x):
    from scipy.interpolate import RectBivariateSpline
    ni, nj = x.shape[:2]
    u, v = np.arange(ni), np.arange(nj)
    fu, fv = np.linspace(0, ni - 1, 2 * ni - 1), np.linspace(0, nj - 1, 2 * nj - 1)
    return np.stack([RectBivariateSpline(u, v, x[..., k])(fu, fv) for k in range(3)], axis=-1)


def main(argv):
    flags = {a for a in argv[1:] if a.startswith("--")}
    argv = [a for a in argv if not a.startswith("--")]
    if len(argv) < 2 or flags - {"--deflection", "--upsample"}:
        sys.exit(__doc__)
    deflection = "--deflection" in flags
    flat, x = first_and_last_frames(argv[1])
    if "--upsample" in flags:
        flat, x = upsample(flat), upsample(x)
    max_level = int(argv[2]) if len(argv) > 2 else 2
    thresholds = [float(t) for t in argv[3:]] or [0.1, 0.2, 0.3, 0.5, 0.8]
    ni, nj = x.shape[:2]
    width = float(np.ptp(flat[..., 0]))  # the flat cloth's, as run/table1.py
    print(f"{argv[1]}: {ni}x{nj}, max_level {max_level}, {'deflection' if deflection else 'angle'}")
    print("refine [rad]   particles   share   surface error (RMS / width)")
    for refine in thresholds:
        cells = leaves(x, max_level, refine, deflection)
        corners = {(i, j) for i0, j0, i1, j1 in cells for i in (i0, i1) for j in (j0, j1)}
        err = np.sqrt(np.mean(np.sum((bilinear(x, cells) - x) ** 2, axis=-1))) / width
        print(f"{refine:12.2f} {len(corners):11d} {len(corners) / (ni * nj):7.0%} {err:14.4f}")


if __name__ == "__main__":
    main(sys.argv)
