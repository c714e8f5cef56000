#!/usr/bin/python3
"""Checks an XDMF sidecar against its HDF5 file, with h5py only: every dataset the XML
names exists with as many values as the XML says, every time step's view (a dataset, a
few values written into the sidecar as text, or a binary DataItem that reads a row where it
lies in the results file) holds the values of its row of the series it shows, bit for bit,
no two time steps name the file of their binary items alike, and the time steps match /time.

usage: check_xdmf.py FILE.xdmf [--position-views KIND] [--column-views KIND]   (exit 0 when consistent)
KIND: text|binary|compact|virtual

--position-views also checks how the views of /bodies/position are stored: as text in the
sidecar (a few bodies), read in place from the series' chunks (up to 256 bodies), copies of
their rows in the dataset's header (a small series of more bodies) or HDF5 virtual datasets
(a large one). --column-views checks the same of the views of columns of a series (the
per-body energies, joint forces and torques, beam section forces): text (a few bodies),
binary (read in place from their tables in /xdmf/columns) or datasets.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np


def fail(msg):
    print("check_xdmf: " + msg)
    sys.exit(1)


def source_row(h5, name, t):
    """What the view /xdmf/<t>/<name> must hold: a row of a series."""
    if name == "energy":
        return h5["energy"][t]
    if name in ("kinetic_energy", "gravity_energy"):
        return h5["bodies/energy"][t][:, 0 if name == "kinetic_energy" else 1]
    if name == "attachment":
        return h5["joints/attachment"][t].reshape(-1, 3)
    if name in ("force", "torque"):
        f = h5["joints/force"][t]
        return f[:, :3] if name == "force" else f[:, 3:]
    if name in ("section_force", "section_moment"):
        f = h5["beams/section_force"][t]
        return f[:, :3] if name == "section_force" else f[:, 3:]
    return h5["bodies/" + name][t]


LAYOUTS = {h5py.h5d.COMPACT: "compact", h5py.h5d.CONTIGUOUS: "contiguous", h5py.h5d.CHUNKED: "chunked",
           h5py.h5d.VIRTUAL: "virtual"}


COLUMN_VIEWS = ("kinetic_energy", "gravity_energy", "force", "torque", "section_force", "section_moment")


def wanted_kind(name, want):
    """The kind of view the command line asks `name`'s views to be, or None."""
    return want.get("position") if name == "position" else want.get("column") if name in COLUMN_VIEWS else None


def view_name(item, parents):
    """Which view a DataItem of the sidecar's own (text or binary) shows, from what holds it."""
    holder = parents[item]
    if holder.tag == "Geometry":
        return "attachment" if parents[holder].get("Name") == "joints" else "position"
    return {"energy_kinetic_gravity_elastic": "energy"}.get(holder.get("Name"), holder.get("Name"))


def main():
    xdmf = sys.argv[1]
    want = {}
    if len(sys.argv) % 2:
        fail(f"{sys.argv[-1]} needs a kind")
    for k in range(2, len(sys.argv), 2):
        if sys.argv[k] not in ("--position-views", "--column-views"):
            fail(f"unknown option {sys.argv[k]}")
        want[sys.argv[k][2:].split("-")[0]] = sys.argv[k + 1]
    root = ET.parse(xdmf).getroot()
    parents = {child: parent for parent in root.iter() for child in parent}
    h5_name = os.path.splitext(os.path.basename(xdmf))[0] + ".h5"  # side by side, as the sidecar names it
    folder = os.path.dirname(os.path.abspath(xdmf))
    steps = root.findall("./Domain/Grid/Grid")
    if not steps:
        fail("no time steps")
    files, times, rows, checked = {}, [], [], 0
    binary_names = {}  # the file name of a step's binary items -> that step's row
    for step in steps:
        times.append(float(step.find("Time").get("Value")))
        rows.append(int(step.get("Name")[1:]))  # t<row>
        for item in step.iter("DataItem"):
            dims = [int(x) for x in item.get("Dimensions").split()]
            if item.get("Format") == "Binary":  # a row read where it lies in the results file
                name, written = view_name(item, parents), item.text.strip()
                if binary_names.setdefault(written, rows[-1]) != rows[-1]:
                    fail(f"rows {binary_names[written]} and {rows[-1]} name their binary file alike, '{written}'")
                if item.get("Endian") != "Little" or item.get("NumberType") != "Float" or item.get("Precision") != "8":
                    fail(f"{name} at row {rows[-1]}: a binary item that is not little-endian float64")
                path = os.path.normpath(os.path.join(folder, written))
                if path != os.path.join(folder, h5_name):
                    fail(f"{name} at row {rows[-1]} reads {written}, not the results file")
                with open(path, "rb") as raw:
                    raw.seek(int(item.get("Seek")))
                    values = np.frombuffer(raw.read(8 * math.prod(dims)), dtype="<f8")
                h5 = files.setdefault(h5_name, h5py.File(os.path.join(folder, h5_name), "r"))
                if not np.array_equal(values, np.asarray(source_row(h5, name, rows[-1]), dtype=float).ravel()):
                    fail(f"the binary item of {name} at row {rows[-1]} differs from its row of the series")
                if wanted_kind(name, want) not in (None, "binary"):
                    fail(f"{name} at row {rows[-1]} is binary, not {wanted_kind(name, want)}")
                checked += 1
                continue
            if item.get("Format") == "XML":  # a view's values as text
                name = view_name(item, parents)
                values = np.array([float(x) for x in item.text.split()])
                h5 = files.setdefault(h5_name, h5py.File(os.path.join(folder, h5_name), "r"))
                expected = np.asarray(source_row(h5, name, rows[-1]), dtype=float).ravel()
                if math.prod(dims) != values.size or not np.array_equal(values, expected):
                    fail(f"the text of {name} at row {rows[-1]} differs from its row of the series")
                if wanted_kind(name, want) not in (None, "text"):
                    fail(f"{name} at row {rows[-1]} is text, not {wanted_kind(name, want)}")
                checked += 1
                continue
            if item.get("Format") != "HDF":
                fail("a DataItem that is neither an HDF reference, XML text nor binary")
            name, path = item.text.strip().split(":", 1)
            h5 = files.setdefault(name, h5py.File(os.path.join(folder, name), "r"))
            if path not in h5:
                fail(f"{path} is not in {name}")
            if math.prod(dims) != h5[path].size:
                fail(f"{path}: XDMF says {dims}, the file has {h5[path].shape}")
            parts = path.strip("/").split("/")
            if len(parts) == 3 and parts[0] == "xdmf":
                expected = source_row(h5, parts[2], int(parts[1]))
                if not np.array_equal(h5[path][()], expected):
                    fail(f"{path} differs from its row of the series")
                layout = LAYOUTS.get(h5[path].id.get_create_plist().get_layout(), "?")
                if wanted_kind(parts[2], want) not in (None, layout):
                    fail(f"{path} is {layout}, not {wanted_kind(parts[2], want)}")
            checked += 1
    for h5 in files.values():
        if [h5["time"][r] for r in rows] != times:
            fail("time values differ from /time")
        if rows[0] != 0 or rows[-1] != h5["time"].shape[0] - 1 or len(rows) > 1000:
            fail(f"the steps shown are rows {rows[0]}..{rows[-1]}, {len(rows)} of them, of {h5['time'].shape[0]}")
    print(f"check_xdmf: {len(steps)} time steps, {checked} references consistent")


if __name__ == "__main__":
    main()
