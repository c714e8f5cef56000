"""Opens a modes file's XDMF sidecar in the real ParaView (pvpython, on an Xvfb X server)
with its default reader, reads every frame and checks it against the modes themselves:
time k + f/F is mode k at phase 2 pi f/F, the bodies drawn at the equilibrium moved by
a Re(shape e^(i phase)), with a making the mode's largest body translation a twentieth of
the model's size. Renders a picture.

usage: pvpython paraview_modes.py MODES.xdmf PICTURE.png      (exit 0 when all agree)
"""
import os
import sys

import h5py
import numpy as np
from paraview import servermanager as sm
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paraview_xdmf import open_with_default_reader, render  # noqa: E402


def fail(msg):
    print("paraview_modes: " + msg)
    sys.exit(1)


def main():
    xdmf, picture = sys.argv[1], sys.argv[2]
    reader, h5 = open_with_default_reader(xdmf, fail)
    shape = h5["modes/shape"][:] + 1j * h5["modes/shape_imag"][:]  # K x N x 6
    rest = h5["equilibrium/position"][:]
    size = np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)) or 1.0
    modes, bodies = shape.shape[0], shape.shape[1]
    times = np.array(reader.TimestepValues)
    frames = len(times) // modes
    if frames < 4 or len(times) != modes * frames:
        fail(f"{len(times)} time steps for {modes} modes")
    expected = np.array([k + f / frames for k in range(1, modes + 1) for f in range(frames)])
    if not np.allclose(times, expected, rtol=0, atol=1e-12):
        fail(f"time steps {times} are not k + f/{frames}")
    for t in times:
        k, f = int(round(t * frames)) // frames, int(round(t * frames)) % frames
        reader.UpdatePipeline(t)
        data = sm.Fetch(reader)
        if data.GetNumberOfPoints() != bodies or data.GetNumberOfCells() != bodies:
            fail(f"t = {t}: {data.GetNumberOfPoints()} points, {data.GetNumberOfCells()} cells for {bodies} bodies")
        points = vtk_to_numpy(data.GetPoints().GetData())
        translation = shape[k - 1, :, :3]
        a = 0.05 * size / np.max(np.linalg.norm(np.abs(translation), axis=1))
        moved = rest + a * np.real(translation * np.exp(2j * np.pi * f / frames))
        if not np.allclose(points, moved, rtol=0, atol=1e-9 * size):
            fail(f"mode {k}, frame {f}: the bodies lie {np.abs(points - moved).max():.3g} m off the scaled shape")
        frequency = vtk_to_numpy(data.GetFieldData().GetArray("mode_frequency_hz")).reshape(-1)
        if frequency[0] != k or frequency[1] != h5["modes/frequency"][k - 1]:
            fail(f"mode {k}: field data {frequency}")
    print(f"paraview_modes: {modes} modes x {frames} frames agree with the modes file")
    render(reader, picture, ("POINTS", "kinetic_share"), times[frames // 4])


if __name__ == "__main__":
    main()
