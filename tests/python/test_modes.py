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
