"""Opens a reduced part's XDMF sidecar (mbsflow reduce) in the real ParaView (pvpython, on
an Xvfb X server) with its default reader and checks every time step against the part's
file: time q is reduced coordinate q, the outer surface's triangles on the display nodes,
with coordinate q's displacement of each node as the point vector `shape`. Renders the
first fixed-interface mode warped by its shape.

usage: pvpython paraview_part.py PART.xdmf PICTURE.png      (exit 0 when all agree)
"""
import os
import sys

import h5py
import numpy as np
from paraview import servermanager as sm
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paraview_xdmf import open_with_default_reader  # noqa: E402


def fail(msg):
    print("paraview_part: " + msg)
    sys.exit(1)


def main():
    xdmf, picture = sys.argv[1], sys.argv[2]
    reader, h5 = open_with_default_reader(xdmf, fail)
    shape, position, triangle = h5["display/shape"][:], h5["display/position"][:], h5["display/triangle"][:]
    times = np.array(reader.TimestepValues)
    if not np.array_equal(times, np.arange(1, shape.shape[0] + 1)):
        fail(f"time steps {times}, coordinates {shape.shape[0]}")
    for q in range(shape.shape[0]):
        reader.UpdatePipeline(q + 1)
        data = sm.Fetch(reader)
        if data.GetNumberOfCells() != len(triangle) or data.GetNumberOfPoints() != len(position):
            fail(f"coordinate {q + 1}: {data.GetNumberOfCells()} cells, {data.GetNumberOfPoints()} points")
        if not np.array_equal(vtk_to_numpy(data.GetPoints().GetData()), position):
            fail("the surface's points are not /display/position")
        cell = data.GetCell(len(triangle) - 1)
        if [cell.GetPointId(k) for k in range(3)] != list(triangle[-1]):
            fail("the last triangle is not /display/triangle's")
        if not np.array_equal(vtk_to_numpy(data.GetPointData().GetArray("shape")), shape[q]):
            fail(f"coordinate {q + 1}: the shape differs from /display/shape")
    print(f"paraview_part: {shape.shape[0]} coordinates, {len(triangle)} triangles agree with the part's file")
    first_mode = int(np.count_nonzero(h5["reduced/coordinate_dof"][:, 1]))  # after the interface coordinates
    view = simple.GetActiveViewOrCreate("RenderView")
    view.ViewSize = [640, 480]
    view.ViewTime = first_mode + 1
    size = np.linalg.norm(position.max(axis=0) - position.min(axis=0))
    warp = simple.WarpByVector(Input=reader, Vectors=["POINTS", "shape"],
                               ScaleFactor=0.1 * size / max(np.abs(shape[first_mode]).max(), 1e-30))
    shown = simple.Show(warp, view)
    simple.ColorBy(shown, ("POINTS", "shape", "Magnitude"))
    view.ResetCamera()
    simple.SaveScreenshot(picture, view)
    print(f"paraview_part: rendered {picture}")


if __name__ == "__main__":
    main()
