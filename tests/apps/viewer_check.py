#!/usr/bin/python3
"""mbsflow view in a real browser (Debian's chromium and chromedriver, headless, WebGL on
SwiftShader, driven by python3-selenium): the page of a run loads without console errors,
shows as many frames as the file has snapshots, and after seeking draws every body where
the file says it is (its pixel, projected from the file's position through the page's
camera, is not background, and the background stays background). Also prints the time
per frame for a 10 000-body model (a measurement, not a pass condition).

usage: viewer_check.py MBSFLOW WORK_DIR
"""
import math
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
from PIL import Image
from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.remote.remote_connection import RemoteConnection


def fail(msg):
    print("viewer_check: " + msg)
    sys.exit(1)


def browser():
    o = Options()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--use-gl=angle", "--use-angle=swiftshader",
              "--enable-unsafe-swiftshader", "--window-size=1000,800"):
        o.add_argument(a)
    o.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    RemoteConnection.set_timeout(600)  # a loaded 2-core machine takes long over the 14 MB page
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=o)


def open_page(driver, page):
    driver.get("file://" + os.path.abspath(page))
    driver.set_script_timeout(600)
    ready = driver.execute_async_script(
        "const done = arguments[0]; const t0 = Date.now();"
        "(function wait() { if (window.viewer && window.viewer.ready) done(true);"
        " else if (Date.now() - t0 > 300000) done(false); else setTimeout(wait, 50); })();")
    if not ready:
        fail(f"{page}: the viewer did not start")
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    if errors:
        fail(f"{page}: console errors: {errors}")


def check_positions(driver, positions, work, frames_to_check):
    """positions[k]: the N x 3 body positions the page must show at frame k."""
    frames = driver.execute_script("return window.viewer.frames")
    if frames != len(positions):
        fail(f"the page shows {frames} frames, the file has {len(positions)}")
    for k in frames_to_check:
        if driver.execute_script(f"return window.viewer.seek({k})") != k:
            fail(f"seeking to frame {k} failed")
        p = positions[k]
        centre = (p.min(axis=0) + p.max(axis=0)) / 2
        extent = max(float((p.max(axis=0) - p.min(axis=0)).max()), 1e-3)
        fov, distance = 40.0, 2.5 * extent
        driver.execute_script(f"window.viewer.setView({{target: {list(map(float, centre))}, distance: {distance}, fov: {fov}}})")
        width, height = driver.execute_script("return [window.innerWidth, window.innerHeight]")
        shot = os.path.join(work, f"viewer_frame{k}_{len(positions)}.png")
        driver.save_screenshot(shot)
        image = Image.open(shot).convert("RGB")
        scale = image.size[0] / width  # device pixels per CSS pixel
        tan = math.tan(math.radians(fov) / 2)
        for i, (x, y, z) in enumerate(p):
            depth = centre[2] + distance - z
            u = ((x - centre[0]) / depth / (tan * width / height) + 1) / 2 * width
            v = (1 - (y - centre[1]) / depth / tan) / 2 * height
            r, g, b = image.getpixel((int(u * scale), int(v * scale)))
            if min(r, g, b) > 240:
                fail(f"frame {k}: body {i} at {list(p[i])} should be drawn at pixel ({u:.0f}, {v:.0f}); it is background")
        r, g, b = image.getpixel((int(0.95 * width * scale), int(0.15 * height * scale)))
        if min(r, g, b) < 240:
            fail(f"frame {k}: the background far from every body is drawn on")
    print(f"viewer_check: {frames} frames; after seeking, every body drawn where the file puts it")


def check_tubes(driver, h5):
    """Each beam is drawn as a tube around its centreline: at every frame checked, every
    node of the beam lies inside the tube, one radius from its nearest vertex (up to the
    spacing of the tube's rings, a quarter of an element)."""
    lines, index = h5["xdmf/beam_lines"][:], h5["xdmf/beam_index"][:]
    positions = h5["bodies/position"][:]
    frames = driver.execute_script("return window.viewer.frames")
    for k in (0, frames // 2, frames - 1):
        driver.execute_script(f"window.viewer.seek({k})")
        tubes = driver.execute_script("return window.viewer.tubes()")
        if len(tubes) != index.max() + 1:
            fail(f"frame {k}: {len(tubes)} tubes for {index.max() + 1} beams")
        for b, tube in enumerate(tubes):
            segments = lines[index == b]
            nodes = np.concatenate([segments[:1, 0], segments[:, 1]])
            length = np.linalg.norm(np.diff(positions[k][nodes], axis=0), axis=1).max()
            r = tube["radius"]
            far = np.sqrt(r * r + (length / 4) ** 2) * 1.01
            for node, d in zip(nodes, tube["nodes"]):
                if not 0.99 * r <= d <= far:
                    fail(f"frame {k}: beam {b}'s node {node} is {d:.4g} from its tube's nearest vertex (radius {r:.4g})")
    print(f"viewer_check: {len(tubes)} beam(s) drawn as tubes through their nodes at 3 frames of {frames}")


def check_surface(driver, h5):
    """A flexible body's surface is drawn deformed: at every frame checked, its points are
    the XDMF sidecar's for that snapshot (to float precision)."""
    frames = driver.execute_script("return window.viewer.frames")
    if frames != len(h5["time"]):
        fail(f"the flexible run shows {frames} frames of {len(h5['time'])} snapshots")
    for k in (0, frames // 2, frames - 1):
        driver.execute_script(f"window.viewer.seek({k})")
        surfaces = driver.execute_script("return window.viewer.surfaces()")
        if len(surfaces) != 1:
            fail(f"frame {k}: {len(surfaces)} surfaces for one flexible body")
        drawn, written = np.array(surfaces[0]).reshape(-1, 3), h5[f"xdmf/{k}/surface0"][:]
        if drawn.shape != written.shape or np.abs(drawn - written).max() > 1e-6 * np.abs(written).max():
            fail(f"frame {k}: the flexible body's surface is not where the XDMF sidecar draws it")
    print(f"viewer_check: a flexible body's surface drawn deformed as ParaView draws it at 3 frames of {frames}")


def mode_positions(h5, mode, frames):
    """The bodies of mode `mode` at frames 0..frames-1 of a period, from the modes file's
    shapes: the equilibrium moved by a Re(shape e^(i phase)), the largest body translation
    a twentieth of the model's size."""
    shape = h5["modes/shape"][mode - 1, :, :3] + 1j * h5["modes/shape_imag"][mode - 1, :, :3]
    rest = h5["equilibrium/position"][:]
    size = np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)) or 1.0
    a = 0.05 * size / np.max(np.linalg.norm(np.abs(shape), axis=1))
    return [rest + a * np.real(shape * np.exp(2j * np.pi * f / frames)) for f in range(frames)]


def run(mbsflow, work, *args):
    subprocess.run([mbsflow, *args], cwd=work, check=True, stderr=subprocess.DEVNULL)


def main():
    mbsflow, work = os.path.abspath(sys.argv[1]), sys.argv[2]
    os.makedirs(work, exist_ok=True)
    run(mbsflow, work, "generate", "chain", "--bodies", "5", "-o", "chain.json")
    run(mbsflow, work, "run", "chain.json", "--t-end", "0.3", "--output-interval", "0.05", "--fields", "all", "-o", "chain.h5")
    run(mbsflow, work, "view", "chain.h5", "-o", "chain.html")
    run(mbsflow, work, "modes", "chain.json", "-n", "3", "-o", "modes.h5")
    run(mbsflow, work, "view", "modes.h5", "--mode", "2", "-o", "modes.html")
    boom = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "models", "flexible_boom.json")
    run(mbsflow, work, "run", boom, "--t-end", "2", "--output-interval", "0.1", "-o", "boom.h5")
    run(mbsflow, work, "view", "boom.h5", "-o", "boom.html")
    # A reduced FE bar as a flexible body (ccx writes its matrices): the pendulum of examples/fe.
    fe = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "fe")
    shutil.copy(os.path.join(fe, "bar.inp"), work)
    shutil.copy(os.path.join(fe, "bar_pendulum.json"), work)
    subprocess.run(["ccx", "bar"], cwd=work, check=True, stdout=subprocess.DEVNULL)
    run(mbsflow, work, "reduce", "bar.inp", "--rigid-face", "END0", "--modes", "10", "-o", "bar.h5")
    run(mbsflow, work, "run", "bar_pendulum.json", "--t-end", "0.05", "--output-interval", "0.005", "-o", "pendulum.h5")
    run(mbsflow, work, "view", "pendulum.h5", "-o", "pendulum.html")
    run(mbsflow, work, "generate", "grid", "--rows", "100", "--cols", "100", "-o", "grid.json")
    run(mbsflow, work, "run", "grid.json", "--t-end", "0.02", "--output-interval", "0.002", "-o", "grid.h5")
    run(mbsflow, work, "view", "grid.h5", "-o", "grid.html")
    driver = browser()
    try:
        open_page(driver, os.path.join(work, "chain.html"))
        with h5py.File(os.path.join(work, "chain.h5"), "r") as h5:
            positions = h5["bodies/position"][:]
            check_positions(driver, positions, work, (len(positions) - 1, 0))
        if driver.execute_script("return window.viewer.tubes()") != []:
            fail("a chain without beams is drawn with tubes")
        open_page(driver, os.path.join(work, "boom.html"))
        with h5py.File(os.path.join(work, "boom.h5"), "r") as h5:
            check_tubes(driver, h5)
        open_page(driver, os.path.join(work, "pendulum.html"))
        with h5py.File(os.path.join(work, "pendulum.h5"), "r") as h5:
            check_surface(driver, h5)
        open_page(driver, os.path.join(work, "modes.html"))
        with h5py.File(os.path.join(work, "modes.h5"), "r") as h5:
            check_positions(driver, mode_positions(h5, 2, 48), work, (12, 36))  # a quarter and three quarters of a period
        open_page(driver, os.path.join(work, "grid.html"))
        bodies = driver.execute_script("return window.viewer.bodies")
        ms = driver.execute_async_script("window.viewer.timeFrames(5, arguments[0])")
        print(f"viewer_check: {bodies} bodies: {ms:.1f} ms per frame in headless chromium on SwiftShader (CPU rendering)")
    finally:
        driver.quit()


if __name__ == "__main__":
    main()
