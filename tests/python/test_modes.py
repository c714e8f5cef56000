"""mbsflow.modes, mbsflow.linearize and mbsflow.frf: the same numbers as the CLI's, scipy
sparse matrices, closed-form answers."""
import math

import numpy as np
import mbsflow

MOUNT = {"name": "mount", "gravity": [0, 0, 0],
         "bodies": [{"name": "block", "mass": 2.0, "inertia": [0.3, 0.5, 0.7], "position": [0, 0, 0]}],
         "joints": [{"name": "pad", "type": "bushing", "body1": "ground", "body2": "block", "point1": [0, 0, 0],
                     "point2": [0, 0, 0], "stiffness": [800, 1800, 3200, 30, 80, 140],
                     "damping": [4, 1, 1, 0.1, 0.1, 0.1]}]}

PENDULUM = {"name": "pendulum", "gravity": [0, -9.81, 0],
            "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.02, 0.02, 0.02], "position": [1, 0, 0]}],
            "joints": [{"name": "pivot", "type": "revolute", "body1": "ground", "body2": "bob", "point1": [0, 0, 0],
                        "point2": [-1, 0, 0], "axis1": [0, 0, 1]}]}


def test_linearize_gives_sparse_mass_damping_stiffness():
    lm = mbsflow.linearize(mbsflow.Model.from_dict(MOUNT), at="initial")
    assert lm.M.shape == (6, 6) and lm.K.shape == (6, 6) and lm.C.shape == (0, 6)
    assert np.allclose(lm.K.diagonal(), [800, 1800, 3200, 30, 80, 140])
    assert np.allclose(lm.D.diagonal(), [4, 1, 1, 0.1, 0.1, 0.1])
    assert np.allclose(lm.M.diagonal(), [2, 2, 2, 0.3, 0.5, 0.7])


def test_the_pendulum_hangs_and_swings_at_its_closed_form_frequency():
    m = mbsflow.modes(mbsflow.Model.from_dict(PENDULUM), n=5)
    assert len(m.frequency) == 1
    assert math.isclose(m.frequency[0], math.sqrt(9.81 / 1.02) / (2 * math.pi), rel_tol=1e-9)
    assert m.shape.shape == (1, 1, 6)
    assert abs(m.state[1] + 1.0) < 1e-8  # the bob below the pivot


def test_frf_of_a_damped_oscillator():
    f = np.array([0.5, 2.0, 8.0])
    h = mbsflow.frf(mbsflow.Model.from_dict(MOUNT), "block:fx", ["block:x", "block:vx"], f, at="initial")
    w = 2 * np.pi * f
    exact = 1 / (800 - 2 * w ** 2 + 4j * w)
    assert h.shape == (3, 2, 1)
    assert np.allclose(h[:, 0, 0], exact, rtol=1e-10)
    assert np.allclose(h[:, 1, 0], 1j * w * exact, rtol=1e-10)


def test_a_cantilever_beam_from_python_bends_at_its_closed_form_frequency():
    """A model with a beam reads from a dict, its nodes are bodies, and its first bending
    mode converges to 1.8751^2 sqrt(E I / (rho A L^4))."""
    e, rho, a, i = 2.1e11, 7850.0, 1e-4, 8e-10
    cantilever = {"name": "cantilever", "bodies": [],
                  "beams": [{"name": "b", "from": [0, 0, 0], "to": [1, 0, 0], "up": [0, 1, 0], "elements": 40,
                             "E": e, "G": 8.1e10, "density": rho,
                             "section": {"area": a, "Iy": 2 * i, "Iz": i, "J": 1.2e-9}}],
                  "joints": [{"name": "clamp", "type": "fixed", "body1": "ground", "body2": "b.0"}]}
    model = mbsflow.Model.from_dict(cantilever)
    m = mbsflow.modes(model, n=1, at="initial")
    exact = 1.8751041 ** 2 * math.sqrt(e * i / (rho * a)) / (2 * math.pi)
    assert m.shape.shape[1] == 41  # the 41 nodes
    assert math.isclose(m.frequency[0], exact, rel_tol=1e-3)


def test_modes_of_a_flexible_body_reduced_from_matrix_market_files(tmp_path):
    """A spring lattice written as Matrix Market files, reduced by `mbsflow reduce` and used
    as a flexible body: free, its modes are six rigid-body motions and then the reduced
    part's own free frequencies; its interface nodes are bodies whose shapes follow; held
    there by rigid joints, the fixed-interface frequencies."""
    import os
    import subprocess
    import scipy.linalg
    nodes = [(0.2 * i, 0.1 * j, 0.1 * k) for i in range(4) for j in range(2) for k in range(2)]
    n = 3 * len(nodes)
    stiffness, mass = np.zeros((n, n)), np.diag(np.repeat(np.linspace(0.5, 1.5, len(nodes)), 3))
    for a in range(len(nodes)):
        for b in range(a + 1, len(nodes)):
            d = np.subtract(nodes[b], nodes[a])
            if np.linalg.norm(d) > 0.26:
                continue
            block = 2e5 / np.linalg.norm(d) ** 3 * np.outer(d, d)
            for p, q, s in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                stiffness[3 * p:3 * p + 3, 3 * q:3 * q + 3] += s * block
    for name, matrix in (("K.mtx", stiffness), ("M.mtx", mass)):
        rows, cols = np.nonzero(matrix)
        with open(tmp_path / name, "w") as f:
            f.write(f"%%MatrixMarket matrix coordinate real general\n{n} {n} {len(rows)}\n")
            f.writelines(f"{r + 1} {c + 1} {matrix[r, c]!r}\n" for r, c in zip(rows, cols))
    (tmp_path / "part.dof").write_text("".join(f"{i + 1}.{e + 1}\n" for i in range(len(nodes)) for e in range(3)))
    (tmp_path / "part.inp").write_text("*NODE\n" + "".join(f"{i + 1}, {x}, {y}, {z}\n" for i, (x, y, z) in enumerate(nodes)))
    subprocess.run([os.environ["MBSFLOW_EXE"], "reduce", "part.inp", "--stiffness", "K.mtx", "--mass", "M.mtx", "--dofs",
                    "part.dof", "--interface", "1-4", "--modes", "4", "-o", "part.h5", "-q"], cwd=tmp_path, check=True)
    import h5py
    with h5py.File(tmp_path / "part.h5", "r") as h5:
        reduced = np.sqrt(np.abs(scipy.linalg.eigh(h5["reduced/stiffness"][:], h5["reduced/mass"][:], eigvals_only=True)))
    model = mbsflow.Model.from_dict({"name": "lattice", "gravity": [0, 0, 0], "joints": [],
                                     "bodies": [{"name": "part", "type": "flexible", "file": str(tmp_path / "part.h5")}]})
    m = mbsflow.modes(model, n=12, at="initial", damped=False)
    assert list(m.rigid_body) == [True] * 6 + [False] * 6
    assert np.allclose(m.frequency[6:], reduced[6:12] / (2 * np.pi), rtol=1e-7)
    assert m.shape.shape == (12, 5, 6)  # the frame and its four interface nodes
    assert np.abs(m.shape[6, 1:, :3]).max() > 0.1 * np.abs(m.shape[6, 0, :3]).max()
    lm = mbsflow.linearize(model, at="initial")
    assert lm.bodies == [0] and lm.start == [0, 6 + 12 + 4 - 6]
    # Held at its interface nodes by rigid spherical joints: the fixed-interface modes the
    # reduction kept, those of its matrices with the interface coordinates held.
    pins = [{"name": f"pin{i}", "type": "spherical", "body1": "ground", "body2": f"part@{i}", "point1": list(nodes[i - 1])}
            for i in range(1, 5)]
    held = mbsflow.Model.from_dict({"name": "lattice", "gravity": [0, 0, 0], "joints": pins,
                                    "bodies": [{"name": "part", "type": "flexible", "file": str(tmp_path / "part.h5")}]})
    with h5py.File(tmp_path / "part.h5", "r") as h5:
        k, mm = h5["reduced/stiffness"][:], h5["reduced/mass"][:]
    fixed = np.sqrt(scipy.linalg.eigh(k[12:, 12:], mm[12:, 12:], eigvals_only=True)) / (2 * np.pi)
    assert np.allclose(mbsflow.modes(held, n=4, at="initial", damped=False).frequency, fixed, rtol=1e-6)
    # Run from Python, set vibrating in its first elastic mode: its modal coordinates in the
    # results, the frame's centre still (the modes do not move it), the first mode's
    # coordinate back where it began after one period.
    model = mbsflow.Model.from_dict({"name": "lattice", "gravity": [0, 0, 0], "joints": [],
                                     "bodies": [{"name": "part", "type": "flexible", "file": str(tmp_path / "part.h5"),
                                                 "modal_coordinates": [1e-4]}]})
    period = 1 / m.frequency[6]
    r = mbsflow.run(model, t_end=period, method="rk4", step=period / 2000, output_every=2000)
    eta = r.read("/flexible/modal_coordinates")
    assert eta.shape == (2, 10) and math.isclose(eta[-1, 0], 1e-4, rel_tol=1e-6)
    centre = r.read("/bodies/position")[:, 0]
    assert np.abs(centre - centre[0]).max() < 1e-12
    too_many = {"name": "part", "type": "flexible", "file": str(tmp_path / "part.h5"), "modal_rates": [0.0] * 11}
    try:
        mbsflow.Model.from_dict({"name": "lattice", "bodies": [too_many]})
        assert False, "11 modal rates for 10 modes were taken"
    except mbsflow.InputError as e:
        assert "modal_rates: has 11 values; the part has 10 modes" in str(e)
