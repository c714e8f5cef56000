"""mbsflow.solve_ivp against exact solutions and scipy's Radau, with scipy's arguments and
result fields."""
import ctypes
import math
import subprocess

import numpy as np
import pytest
import scipy.integrate
import scipy.sparse

import mbsflow


def vdp(eps):
    def f(t, y):  # y[0] * y[0], not y[0] ** 2: numpy's power rounds otherwise in about 1 case in 1000
        return [y[1], ((1 - y[0] * y[0]) * y[1] - y[0]) / eps]

    def jac(t, y):
        return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / eps, (1 - y[0] ** 2) / eps]]
    return f, jac


def hnw(t, x):  # the seed's eq. 10 (Hairer, Norsett, Wanner)
    return [2 * t * x[1] ** 0.2 * x[3], 10 * t * math.exp(5 * (x[2] - 1)) * x[3], 2 * t * x[3], -2 * t * math.log(x[0])]


def hnw_exact(t):
    s = math.sin(t * t)
    return np.array([math.exp(s), math.exp(5 * s), s + 1, math.cos(t * t)])


def b1(t, x):  # DETEST B1, the seed's eq. 11
    return [-x[0] + x[1], -100 * x[0] - x[1], -100 * x[2] + x[3], -1e4 * x[2] - 100 * x[3]]


def heat(n):  # the seed's eq. 12, with its exact solution
    h2, w = (n + 1.0) ** 2, math.pi / (n + 1)
    i = np.arange(1, n + 1)
    s1, s2 = np.sin(i * w), np.sin(2 * i * w)
    l1, l2 = 2 * h2 * (1 - math.cos(w)), 2 * h2 * (1 - math.cos(2 * w))
    a = scipy.sparse.diags([np.ones(n - 1), -2 * np.ones(n), np.ones(n - 1)], [-1, 0, 1]) * h2

    def f(t, x):
        return a @ x + (l1 - 1) * math.exp(-t) * s1 + (l2 - 2) * math.exp(-2 * t) * s2
    return f, a.tocsc(), s1 + s2, lambda t: math.exp(-t) * s1 + math.exp(-2 * t) * s2


@pytest.mark.parametrize("method", ["tirk", "colloc", "Radau"])
def test_van_der_pol_agrees_with_scipy_radau(method):
    f, jac = vdp(1e-6)  # mu = 1000 in Hairer's scaling, on [0, 2]
    ref = scipy.integrate.solve_ivp(f, (0, 2), [2, 0], method="Radau", rtol=1e-10, atol=1e-10, jac=jac)
    got = mbsflow.solve_ivp(f, (0, 2), [2, 0], method=method, rtol=1e-8, atol=1e-8, jac=jac)
    assert got.success and got.status == 0 and got.y.shape == (2, len(got.t))
    exact = [0.1706167732170483e1, -0.8928097010247975e0]  # Test Set for IVP Solvers, VDPOL
    assert np.allclose(ref.y[:, -1], exact, rtol=1e-6)
    assert np.allclose(got.y[:, -1], exact, rtol=1e-5), got.y[:, -1]
    assert got.njev > 0 and got.nlu > 0 and got.nfev > 0


@pytest.mark.parametrize("method", ["tirk", "colloc", "dopri5"])
def test_the_seed_problems_meet_their_exact_solutions_as_scipy_does(method):
    t = np.linspace(0, 2.5, 11)
    ref = scipy.integrate.solve_ivp(hnw, (0, 2.5), np.ones(4), method="Radau", rtol=1e-8, atol=1e-10, t_eval=t)
    got = mbsflow.solve_ivp(hnw, (0, 2.5), np.ones(4), method=method, rtol=1e-8, atol=1e-10, t_eval=t)
    exact = np.array([hnw_exact(s) for s in t]).T
    assert np.array_equal(got.t, t)
    scale = np.abs(exact).max(axis=1, keepdims=True)
    assert np.abs(got.y - exact).max() / scale.max() < 1e-5
    assert np.abs(got.y - ref.y).max() / scale.max() < 1e-5
    b = mbsflow.solve_ivp(b1, (0, 20), [1, 0, 1, 0], method=method, rtol=1e-9, atol=1e-12)
    rb = scipy.integrate.solve_ivp(b1, (0, 20), [1, 0, 1, 0], method="Radau", rtol=1e-9, atol=1e-12)
    assert np.allclose(b.y[:, -1], rb.y[:, -1], rtol=1e-6, atol=1e-11)


def test_a_sparse_system_with_its_pattern():
    n = 60
    f, a, y0, exact = heat(n)
    got = mbsflow.solve_ivp(f, (0, 4), y0, method="tirk", rtol=1e-8, atol=1e-10, jac=lambda t, y: a, jac_sparsity=a,
                            linear_solver="klu")
    assert got.success and np.abs(got.y[:, -1] - exact(4.0)).max() < 1e-7
    # and a constant sparse Jacobian gives the pattern itself
    again = mbsflow.solve_ivp(f, (0, 4), y0, method="tirk", rtol=1e-8, atol=1e-10, jac=a)
    assert np.abs(again.y[:, -1] - exact(4.0)).max() < 1e-7


def test_events_dense_output_backwards_and_args():
    g = 9.81

    def fall(t, y, gravity):
        return [y[1], -gravity]

    def ground(t, y, gravity):
        return y[0]
    ground.terminal = True
    ground.direction = -1
    r = mbsflow.solve_ivp(fall, (0, 10), [10.0, 0.0], method="dopri5", events=ground, args=(g,), dense_output=True,
                          rtol=1e-10, atol=1e-12)
    assert r.status == 1 and r.message == "A termination event occurred."
    assert r.t_events[0][0] == pytest.approx(math.sqrt(2 * 10 / g), abs=1e-9)
    assert r.y_events[0].shape == (1, 2) and abs(r.y_events[0][0, 0]) < 1e-9
    assert r.t[-1] == r.t_events[0][0]
    ts = np.linspace(0, r.t[-1], 7)
    assert np.allclose(r.sol(ts)[0], 10 - 0.5 * g * ts ** 2, atol=1e-9)  # dense output: exact for a parabola
    assert r.sol(1.0).shape == (2,)
    back = mbsflow.solve_ivp(lambda t, y: y, (1.0, 0.0), [math.e], method="tirk", rtol=1e-10, atol=1e-12,
                             dense_output=True)
    assert back.t[0] == 1.0 and back.t[-1] == 0.0 and back.y[0, -1] == pytest.approx(1.0, rel=1e-8)
    assert back.sol(0.5)[0] == pytest.approx(math.exp(0.5), rel=1e-7)


def test_rising_and_falling_events_are_all_found():
    def osc(t, y):
        return [y[1], -y[0]]
    zero = lambda t, y: y[0]  # noqa: E731
    r = mbsflow.solve_ivp(osc, (0, 10), [1.0, 0.0], method="tirk", events=[zero], rtol=1e-10, atol=1e-12)
    assert np.allclose(r.t_events[0], [math.pi / 2 + k * math.pi for k in range(3)], atol=1e-7)
    assert r.status == 0 and r.t[-1] == 10


def test_a_compiled_right_hand_side(tmp_path):
    source = tmp_path / "vdp.c"
    source.write_text("void vdp(double t, const double* y, double* dy) {\n"
                      "  (void)t; dy[0] = y[1]; dy[1] = ((1 - y[0] * y[0]) * y[1] - y[0]) / 1e-6;\n}\n")
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(tmp_path / "vdp.so"), str(source)], check=True)
    lib = ctypes.CDLL(str(tmp_path / "vdp.so"))
    f, jac = vdp(1e-6)
    compiled = mbsflow.solve_ivp(mbsflow.CompiledRhs(lib.vdp), (0, 2), [2, 0], method="tirk", rtol=1e-7, atol=1e-7)
    python = mbsflow.solve_ivp(f, (0, 2), [2, 0], method="tirk", rtol=1e-7, atol=1e-7)
    assert np.array_equal(compiled.y, python.y)  # the same numbers, only faster
    # a ctypes callback is a compiled address too
    cb = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double))

    def rhs(t, y, dy):
        dy[0], dy[1] = y[1], -y[0]
    fn = cb(rhs)
    r = mbsflow.solve_ivp(mbsflow.CompiledRhs(fn), (0, math.pi), [0, 1], method="dopri5", rtol=1e-10, atol=1e-12)
    assert abs(r.y[0, -1]) < 1e-8


def test_errors_raise_with_their_message():
    with pytest.raises(mbsflow.InputError, match="method=BDF: not in mbsflow"):
        mbsflow.solve_ivp(lambda t, y: y, (0, 1), [1.0], method="BDF")
    with pytest.raises(mbsflow.InputError, match="fun returned 2 values where 1 are needed"):
        mbsflow.solve_ivp(lambda t, y: [1.0, 2.0], (0, 1), [1.0])

    def boom(t, y):
        raise ZeroDivisionError("from the user's function")
    with pytest.raises(ZeroDivisionError, match="from the user's function"):
        mbsflow.solve_ivp(boom, (0, 1), [1.0], method="tirk")
    with pytest.raises(mbsflow.InputError, match="atol"):
        mbsflow.solve_ivp(lambda t, y: y, (0, 1), [1.0, 2.0], method="dopri5", atol=[1e-6, 1e-8])
    # a step-size collapse is a failed result, as in scipy
    r = mbsflow.solve_ivp(lambda t, y: [1 / (1 - t)], (0, 2), [0.0], method="dopri5")
    assert r.status == -1 and not r.success and r.message


def robertson(t, y):
    return [-0.04 * y[0] + 1e4 * y[1] * y[2], 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1], 3e7 * y[1] * y[1]]


def test_a_component_below_its_absolute_tolerance_is_warned_about():
    # One atol = 1e-4 leaves Robertson's second component (at most 3.65e-5) without control.
    with pytest.warns(RuntimeWarning, match=r"y\[1\] never exceeded its absolute tolerance 0.0001 \(largest \|y\| 3.6") as w:
        mbsflow.solve_ivp(robertson, (0, 40), [1, 0, 0], method="tirk", rtol=1e-4, atol=1e-4)
    assert "atol=[A1, A2, ...]" in str(w[0].message)  # the keyword as Python takes it
    # Per component, each below its size: no warning.
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = mbsflow.solve_ivp(robertson, (0, 40), [1, 0, 0], method="tirk", rtol=1e-4, atol=[1e-8, 1e-14, 1e-6])
    assert r.success
