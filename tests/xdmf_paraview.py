# drape.xdmf as ParaView reads it, against drape.h5 read with h5py: the
# point and cell counts, every attribute array (name, components, and its
# values at the last step), the time steps, and the last step's positions.
# Run by pvbatch (ParaView's Python, headless; nothing is rendered).
# Usage: pvbatch xdmf_paraview.py OUTPUT_DIR
import os
import sys

import h5py
import numpy as np
from paraview import servermanager
from paraview.simple import XDMFReader
from vtk.util.numpy_support import vtk_to_numpy

out = sys.argv[1]
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)


with h5py.File(os.path.join(out, "drape.h5"), "r") as f:
    ni, nj = int(f.attrs["ni"]), int(f.attrs["nj"])
    names = sorted(f["frames"].keys())
    times = [float(f["frames"][n].attrs["time"]) for n in names]
    last = f["frames"][names[-1]]
    # The node attributes drape.xdmf describes: every frame dataset but the
    # positions (its geometry) and the flags (not described).
    expected = {k: last[k][...] for k in last.keys() if k not in ("positions", "flags")}
    positions = last["positions"][...]

reader = XDMFReader(FileNames=[os.path.join(out, "drape.xdmf")])
reader.UpdatePipelineInformation()
pv_times = list(reader.TimestepValues) if len(names) > 1 else [times[0]]
check(len(pv_times) == len(times), f"{len(pv_times)} time steps, drape.h5 has {len(times)} frames")
check(np.allclose(pv_times, times, rtol=1e-12, atol=0), f"time steps {pv_times}, drape.h5 {times}")

reader.UpdatePipeline(times[-1])
grid = servermanager.Fetch(reader)
if grid.IsA("vtkMultiBlockDataSet"):  # a temporal collection may come back as one block
    grid = grid.GetBlock(0)
check(grid.GetNumberOfPoints() == ni * nj, f"{grid.GetNumberOfPoints()} points, expected {ni * nj}")
check(grid.GetNumberOfCells() == (ni - 1) * (nj - 1),
      f"{grid.GetNumberOfCells()} cells, expected {(ni - 1) * (nj - 1)}")
if grid.GetNumberOfCells() > 0:
    check(grid.GetCell(0).GetNumberOfPoints() == 4, "cells are not quadrilaterals")

pd = grid.GetPointData()
got = sorted(pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays()))
check(got == sorted(expected), f"point arrays {got}, drape.h5 frames have {sorted(expected)}")
for name, want in expected.items():
    arr = pd.GetArray(name)
    if arr is None:
        continue
    comps = want.shape[2] if want.ndim == 3 else 1
    check(arr.GetNumberOfComponents() == comps, f"{name}: {arr.GetNumberOfComponents()} components, expected {comps}")
    values = vtk_to_numpy(arr).reshape(want.shape)
    check(np.array_equal(values, want), f"{name}: the last step's values differ from drape.h5")

xyz = vtk_to_numpy(grid.GetPoints().GetData()).reshape(ni, nj, 3)
check(np.array_equal(xyz, positions),
      f"last step's positions differ from drape.h5 (max {np.max(np.abs(xyz - positions)):.3g} m)")

for what in failures:
    print("FAIL " + what)
if failures:
    sys.exit(1)
print(f"ok {out}: {ni * nj} points, {(ni - 1) * (nj - 1)} cells, {len(times)} time steps, arrays {got}")
