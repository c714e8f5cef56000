"""Opens a results file's XDMF sidecar in the real ParaView (pvpython, on an Xvfb X server)
with its default reader (Xdmf3) and with the legacy XDMF reader, reads every time step,
checks the bodies, joints and energies against the HDF5 file, and renders a picture.

usage: pvpython paraview_xdmf.py FILE.xdmf PICTURE.png      (exit 0 when all agree)
"""
import os
import sys

import h5py
import numpy as np
from paraview import servermanager as sm
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy


def fail(msg):
    print("paraview_xdmf: " + msg)
    sys.exit(1)


def blocks(data):
    out = []
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        out.append(it.GetCurrentDataObject())
        it.GoToNextItem()
    return out


def array(attributes, name):
    a = attributes.GetArray(name)
    if a is None:
        fail(f"no array '{name}'")
    return vtk_to_numpy(a)


def check_reader(label, reader, h5):
    times = h5["time"][:]
    if not np.array_equal(np.array(reader.TimestepValues), times):
        fail(f"{label}: time steps {list(reader.TimestepValues)} are not /time")
    joints = h5["joints/attachment"].shape[1] if "joints/attachment" in h5 else 0
    segments = h5["xdmf/beam_lines"][:] if "xdmf/beam_lines" in h5 else None
    surfaces = []
    while f"xdmf/surface{len(surfaces)}_triangles" in h5:
        surfaces.append(h5[f"xdmf/surface{len(surfaces)}_triangles"][:])
    for t, time in enumerate(times):
        reader.UpdatePipeline(time)
        parts = blocks(sm.Fetch(reader))
        if len(parts) != 1 + len(surfaces) + (segments is not None) + (joints > 0):
            fail(f"{label}: {len(parts)} blocks at t = {time}")
        for k, triangles in enumerate(surfaces):  # flexible bodies' deformed surfaces, after the bodies
            surface = parts[1 + k]
            if surface.GetNumberOfCells() != len(triangles):
                fail(f"{label}: flexible body {k}: {surface.GetNumberOfCells()} cells, {len(triangles)} triangles")
            if not np.array_equal(vtk_to_numpy(surface.GetPoints().GetData()), h5[f"xdmf/{t}/surface{k}"][:]):
                fail(f"{label}: flexible body {k}'s surface at t = {time} differs from the file")
            if not np.array_equal(array(surface.GetPointData(), "elastic_displacement"), h5[f"xdmf/{t}/elastic{k}"][:]):
                fail(f"{label}: flexible body {k}'s elastic displacement at t = {time} differs from the file")
        parts = [parts[0]] + parts[1 + len(surfaces):]
        if segments is not None:  # the beams' centrelines: segments between their node bodies
            beams = parts[1]
            if beams.GetNumberOfCells() != len(segments):
                fail(f"{label}: {beams.GetNumberOfCells()} beam segments, {len(segments)} elements")
            ends = vtk_to_numpy(beams.GetPoints().GetData())[segments.reshape(-1)]
            if not np.array_equal(ends, h5["bodies/position"][t][segments.reshape(-1)]):
                fail(f"{label}: beam segments at t = {time} do not join their nodes' positions")
            cell = beams.GetCell(0)
            if cell.GetNumberOfPoints() != 2 or cell.GetPointId(0) != segments[0][0] or cell.GetPointId(1) != segments[0][1]:
                fail(f"{label}: the first beam segment is not between bodies {segments[0]}")
            if "beams/section_force" in h5:  # section forces and moments per element, as cell data
                section = h5["beams/section_force"][t]
                if not (np.array_equal(array(beams.GetCellData(), "section_force"), section[:, :3])
                        and np.array_equal(array(beams.GetCellData(), "section_moment"), section[:, 3:])):
                    fail(f"{label}: beam section forces at t = {time} differ from the file")
            parts = [parts[0]] + parts[2:]
        bodies = parts[0]
        if bodies.GetNumberOfCells() != h5["bodies/names"].shape[0]:
            fail(f"{label}: {bodies.GetNumberOfCells()} body cells, {h5['bodies/names'].shape[0]} bodies")
        points = vtk_to_numpy(bodies.GetPoints().GetData())
        if not np.array_equal(points, h5["bodies/position"][t]):
            fail(f"{label}: body positions at t = {time} differ from the file")
        for name in ("velocity", "angular_velocity", "orientation"):
            if f"bodies/{name}" in h5 and not np.array_equal(array(bodies.GetPointData(), name), h5[f"bodies/{name}"][t]):
                fail(f"{label}: {name} at t = {time} differs from the file")
        if not np.array_equal(array(bodies.GetPointData(), "body_index"), np.arange(bodies.GetNumberOfPoints())):
            fail(f"{label}: body_index is not 0..N-1")
        if "energy" in h5:
            energy = array(bodies.GetFieldData(), "energy_kinetic_gravity_elastic").reshape(-1)
            if not np.array_equal(energy, h5["energy"][t]):
                fail(f"{label}: energies at t = {time} differ from the file")
            per_body = h5["bodies/energy"][t]
            if not (np.array_equal(array(bodies.GetPointData(), "kinetic_energy"), per_body[:, 0])
                    and np.array_equal(array(bodies.GetPointData(), "gravity_energy"), per_body[:, 1])):
                fail(f"{label}: body energies at t = {time} differ from the file")
        if joints:
            lines = parts[1]
            if lines.GetNumberOfCells() != joints or lines.GetNumberOfPoints() != 2 * joints:
                fail(f"{label}: {lines.GetNumberOfCells()} joint lines for {joints} joints")
            ends = vtk_to_numpy(lines.GetPoints().GetData())
            if not np.array_equal(ends, h5["joints/attachment"][t].reshape(-1, 3)):
                fail(f"{label}: joint attachment points at t = {time} differ from the file")
            if "joints/force" in h5:
                wrench = h5["joints/force"][t]
                if not (np.array_equal(array(lines.GetCellData(), "force"), wrench[:, :3])
                        and np.array_equal(array(lines.GetCellData(), "torque"), wrench[:, 3:])):
                    fail(f"{label}: joint forces at t = {time} differ from the file")
    print(f"paraview_xdmf: {label}: {len(times)} time steps agree with the file")


def render(reader, picture, colour_by=("POINTS", "velocity", "Magnitude"), time=None):
    """Renders the reader's bodies at `time` (default: the last step) to `picture` and
    fails unless something is drawn."""
    view = simple.GetActiveViewOrCreate("RenderView")
    view.ViewSize = [640, 480]
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    shown = simple.Show(reader, view)
    shown.SetRepresentationType("Points")
    shown.PointSize = 10
    shown.RenderPointsAsSpheres = 1
    simple.ColorBy(shown, colour_by)
    view.ViewTime = reader.TimestepValues[-1] if time is None else time
    simple.ResetCamera(view)
    simple.SaveScreenshot(picture, view, ImageResolution=[640, 480])
    from vtkmodules.vtkIOImage import vtkPNGReader
    png = vtkPNGReader()
    png.SetFileName(picture)
    png.Update()
    pixels = vtk_to_numpy(png.GetOutput().GetPointData().GetScalars())[:, :3]
    drawn = np.count_nonzero(np.any(pixels < 200, axis=1))
    if drawn < 20:
        fail(f"the picture shows nothing ({drawn} pixels drawn)")
    print(f"paraview_xdmf: rendered {picture} ({drawn} pixels drawn)")


def open_with_default_reader(xdmf, say=None):
    """The sidecar opened as ParaView opens an .xdmf file, and its HDF5 file beside it;
    fails unless the reader is the default one, Xdmf3ReaderS."""
    reader = simple.OpenDataFile(xdmf)
    if reader.GetXMLName() != "Xdmf3ReaderS":
        (say or fail)(f"ParaView opens .xdmf with {reader.GetXMLName()}, not Xdmf3ReaderS")
    return reader, h5py.File(os.path.splitext(xdmf)[0] + ".h5", "r")


def main():
    xdmf, picture = sys.argv[1], sys.argv[2]
    default, h5 = open_with_default_reader(xdmf)  # what ParaView's File > Open picks
    check_reader("Xdmf3 reader (default)", default, h5)
    check_reader("legacy XDMF reader", simple.XDMFReader(FileNames=[xdmf]), h5)
    render(default, picture)


if __name__ == "__main__":
    main()
