"""A model stepped from Python: the run's numbers when left alone, a controller in the loop,
and the state as numpy views of the integrator's memory."""
import math

import numpy as np
import pytest

import mbsflow

PENDULUM = {
    "name": "pendulum",
    "gravity": [0, -9.81, 0],
    "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.01, 0.01, 0.01, 0, 0, 0], "position": [0, -1, 0]}],
    "joints": [{"name": "pivot", "type": "bushing", "body1": "ground", "body2": "bob", "point2": [0, 1, 0],
                "stiffness": [1e6, 1e6, 1e6, 0, 0, 0], "damping": [2e2, 2e2, 2e2, 0, 0, 0]}],
    "simulation": {"t_end": 6.0, "method": "dopri5", "rtol": 1e-8, "atol": 1e-10},
}


def angle(p):
    return math.atan2(p[0], -p[1])  # from hanging straight down, counterclockwise about z


def test_a_pd_controller_brings_the_pendulum_to_its_set_point():
    sim = mbsflow.Simulation(mbsflow.Model.from_dict(PENDULUM))
    target, kp, kd, m, g, length = 0.6, 40.0, 12.0, 1.0, 9.81, 1.0
    angles = []
    while sim.t < 6.0 - 1e-12:
        p = sim.positions[0]
        w = sim.body(0)["angular_velocity"][2]
        theta = angle(p)
        # PD on the angle, plus the gravity torque about the pivot held off
        tau = kp * (target - theta) - kd * w + m * g * length * math.sin(theta)
        sim.set_load(0, [0, 0, 0], [0, 0, tau])
        sim.step(0.01)
        angles.append(theta)
    assert max(angles) > 0.3  # it did swing up
    assert abs(angle(sim.positions[0]) - target) < 1e-3
    assert abs(sim.body(0)["angular_velocity"][2]) < 1e-3


def test_stepped_to_the_end_it_is_the_run():
    model = mbsflow.generate.chain(n=30, t_end=0.05)
    sim = mbsflow.Simulation(model, method="dopri5")
    steps = 0
    while sim.step():
        steps += 1
    r = mbsflow.run(model, method="dopri5", threads=1)
    assert steps == r.summary["steps"] > 10
    assert np.array_equal(sim.state, r.summary["final_state"])
    assert sim.stats["accepted"] == steps


def test_the_state_views_share_the_integrators_memory():
    sim = mbsflow.Simulation(mbsflow.generate.chain(n=5), method="rk4")
    p, v, q, w, y = sim.positions, sim.velocities, sim.orientations, sim.angular_velocities, sim.state
    assert p.shape == (5, 3) and q.shape == (5, 4) and y.shape == (65,)
    assert np.shares_memory(p, y) and np.shares_memory(w, y)
    before = p.copy()
    sim.step(0.01)
    assert not np.array_equal(p, before)  # the same view sees the new state
    assert np.array_equal(p, sim.positions) and np.array_equal(v[2], sim.body(2)["velocity"])
    with pytest.raises(ValueError):
        p[0, 0] = 1.0  # read-only: writes go through set_state, so the method restarts
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)


def test_set_state_and_bad_arguments():
    sim = mbsflow.Simulation(mbsflow.generate.chain(n=3), method="dopri5")
    y = sim.state.copy()
    y[0] += 0.01  # move the first body
    sim.set_state(y)
    assert sim.positions[0, 0] == pytest.approx(y[0])
    with pytest.raises(mbsflow.InputError, match="set_state: 3 values where 39 are needed"):
        sim.set_state([1, 2, 3])
    with pytest.raises(mbsflow.InputError, match="body index 7 out of range"):
        sim.set_load(7, [0, 0, 1])
    with pytest.raises(mbsflow.InputError, match="advance_to"):
        sim.advance_to(-1.0)
    with pytest.raises(mbsflow.InputError, match="method=bdf: unknown method"):
        mbsflow.Simulation(mbsflow.generate.chain(n=3), method="bdf")


def test_ctrl_c_stops_stepping_and_solve_ivp():
    import os
    import subprocess
    import sys
    import textwrap
    script = textwrap.dedent("""
        import os, signal, threading, mbsflow
        def interrupt_soon():
            threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        sim = mbsflow.Simulation(mbsflow.generate.chain(n=2000, t_end=1000.0), method="rk4")
        interrupt_soon()
        try:
            sim.advance_to(1000.0)
        except KeyboardInterrupt:
            print("advance_to interrupted", sim.t > 0, sim.t < 1000.0)
        interrupt_soon()
        try:
            mbsflow.solve_ivp(lambda t, y: [y[1], -y[0]], (0, 1e9), [1.0, 0.0], method="dopri5", rtol=1e-10)
        except KeyboardInterrupt:
            print("solve_ivp interrupted")
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=dict(os.environ))
    assert p.returncode == 0, p.stderr
    assert p.stdout.split("\n")[:2] == ["advance_to interrupted True True", "solve_ivp interrupted"]


def test_the_keywords_are_the_declared_settings_of_a_simulation_each_checked_as_declared(tmp_path):
    import inspect
    declared = [k for k, _, _ in mbsflow._core._run_settings("simulation")]
    assert set(declared) <= {k for k, _, _ in mbsflow._core._run_settings()}  # mbsflow.run's names
    params = inspect.signature(mbsflow.Simulation).parameters
    assert set(params) == set(declared) | {"model"}
    assert params["threads"].default == 1 and params["linear_solver"].default == "auto" and params["step"].default is None
    assert "rtol" in mbsflow.Simulation.__doc__
    model = mbsflow.Model.from_dict(PENDULUM)
    with pytest.raises(mbsflow.InputError, match=r"rtol=-1: must be > 0"):
        mbsflow.Simulation(model, rtol=-1)
    with pytest.raises(mbsflow.InputError, match=r"linear_solver=lu: unknown linear solver"):
        mbsflow.Simulation(model, linear_solver="lu")
    with pytest.raises(mbsflow.InputError, match=r"threads=1.5: must be an integer"):
        mbsflow.Simulation(model, threads=1.5)
    with pytest.raises(TypeError):
        mbsflow.Simulation(model, coupling="loose")  # a setting of runs, not of a stepped model
    # Positional as before, None the default, a model file as mbsflow.run takes it.
    a = mbsflow.Simulation(model, "rk4", 1e-4, None, None, 0.01)
    path = tmp_path / "pendulum.json"
    model.save(str(path))
    b = mbsflow.Simulation(path, method="rk4", step=1e-4, t_end=0.01, threads=None)
    while a.step():
        pass
    while b.step():
        pass
    assert a.t == b.t == 0.01 and np.array_equal(a.state, b.state)
