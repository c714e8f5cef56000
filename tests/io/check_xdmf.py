#!/usr/bin/python3
"""Checks an XDMF sidecar against its HDF5 file: parses the XML with the standard
library's parser and verifies that every referenced dataset exists with the stated
shape, that every hyperslab lies inside it, and that the time steps match /time.

usage: check_xdmf.py FILE.xdmf      (exit 0 when consistent)
"""
import os
import sys
import xml.etree.ElementTree as ET

import h5py


def fail(msg):
    print("check_xdmf: " + msg)
    sys.exit(1)


def main():
    xdmf = sys.argv[1]
    root = ET.parse(xdmf).getroot()
    folder = os.path.dirname(os.path.abspath(xdmf))
    grids = root.findall("./Domain/Grid/Grid")
    if not grids:
        fail("no time grids")
    files = {}
    times = []
    checked = 0
    for grid in grids:
        times.append(float(grid.find("Time").get("Value")))
        n = int(grid.find("Topology").get("NumberOfElements"))
        for slab in grid.iter("DataItem"):
            if slab.get("ItemType") != "HyperSlab":
                continue
            select, ref = slab.findall("DataItem")
            numbers = [int(x) for x in select.text.split()]
            start, stride, count = numbers[0:3], numbers[3:6], numbers[6:9]
            name, path = ref.text.strip().split(":", 1)
            h5 = files.setdefault(name, h5py.File(os.path.join(folder, name), "r"))
            if path not in h5:
                fail(f"{path} is not in {name}")
            shape = tuple(int(x) for x in ref.get("Dimensions").split())
            if h5[path].shape != shape:
                fail(f"{path}: XDMF says {shape}, the file has {h5[path].shape}")
            for d in range(3):
                if start[d] + (count[d] - 1) * stride[d] >= shape[d]:
                    fail(f"{path}: hyperslab {numbers} outside {shape}")
            if tuple(int(x) for x in slab.get("Dimensions").split()) != (count[1], count[2]) or count[1] != n:
                fail(f"{path}: hyperslab dimensions disagree with the topology")
            checked += 1
    for h5 in files.values():
        if list(h5["time"][:]) != times:
            fail("time values differ from /time")
    print(f"check_xdmf: {len(grids)} time steps, {checked} hyperslabs consistent")


if __name__ == "__main__":
    main()
