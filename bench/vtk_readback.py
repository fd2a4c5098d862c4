#!/usr/bin/env python3
"""vtk_readback.py A.vtu B.vtu ... — reads bigstep's VTK files with VTK's own
readers (python3-vtk / pvpython) and, when meshio is installed, with meshio,
and prints per file the counts and every array's name, components and range.
With --same A B: checks that two .vtu files (e.g. raw and zlib-compressed)
hold identical points, cells and arrays, bit for bit; exit status 1 if not.
.vti files are read with vtkXMLImageDataReader (origin, spacing, direction).
Not part of the test suite (bigstep's tests do not need Python)."""
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path):
    r = vtk.vtkXMLImageDataReader() if path.endswith(".vti") else vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode():
        raise SystemExit(f"{path}: VTK could not read it (error {r.GetErrorCode()})")
    return r.GetOutput()


def arrays(data):
    out = {}
    for kind, d in (("point", data.GetPointData()), ("cell", data.GetCellData())):
        for i in range(d.GetNumberOfArrays()):
            a = d.GetArray(i)
            out[(kind, a.GetName())] = vtk_to_numpy(a)
    return out


def show(path):
    g = read(path)
    print(f"{path}: {g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} cells")
    if path.endswith(".vti"):
        print(f"  origin {g.GetOrigin()} spacing {g.GetSpacing()} dims {g.GetDimensions()}")
        m = g.GetDirectionMatrix()
        print("  direction", [m.GetElement(i, j) for i in range(3) for j in range(3)])
    for (kind, name), a in arrays(g).items():
        ncomp = 1 if a.ndim == 1 else a.shape[1]
        print(f"  {kind:5s} {name:16s} {ncomp} comp  [{np.nanmin(a):.6g}, {np.nanmax(a):.6g}]")
    try:
        import meshio
    except ImportError:
        return
    if path.endswith(".vtu"):
        m = meshio.read(path)
        print(f"  meshio: {len(m.points)} points, {sum(len(c.data) for c in m.cells)} cells, "
              f"point data {sorted(m.point_data)}, cell data {sorted(m.cell_data)}")


def same(a, b):
    ga, gb = read(a), read(b)
    ok = np.array_equal(vtk_to_numpy(ga.GetPoints().GetData()), vtk_to_numpy(gb.GetPoints().GetData()))
    ok &= np.array_equal(vtk_to_numpy(ga.GetCells().GetConnectivityArray()),
                         vtk_to_numpy(gb.GetCells().GetConnectivityArray()))
    xa, xb = arrays(ga), arrays(gb)
    ok &= xa.keys() == xb.keys()
    for k in xa:
        eq = k in xb and np.array_equal(xa[k], xb[k], equal_nan=True)
        ok &= eq
        if not eq:
            print(f"  {k} differs")
    print(f"{a} and {b}: {'identical' if ok else 'DIFFERENT'} ({len(xa)} arrays)")
    return ok


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["--same"]:
        sys.exit(0 if same(args[1], args[2]) else 1)
    for p in args:
        show(p)
