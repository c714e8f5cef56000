"""solve_ivp in scipy's shape on mbsflow's methods: a scipy user switches by changing the
import. Methods: "tirk" (triangularised implicit Runge-Kutta, by default the 3-stage
Radau IIA method of order 5 that scipy's Radau is; so also under the name "Radau";
variant="radau5" for 5 stages, order 9), "colloc" (collocation block methods), "dopri5" (also "RK45",
scipy's default) and "rk4" (fixed steps of first_step)."""
import ctypes
import warnings

import numpy as np

from . import _core
from ._core import InputError

# scipy's names for the methods mbsflow has under its own: RK45 is Dormand-Prince 5(4),
# Radau the 3-stage Radau IIA method of order 5, RADAU5's (tirk's default tableau, radau3).
_ALIASES = {"RK45": ("dopri5", ""), "Radau": ("tirk", "")}
_NOT_HERE = ("RK23", "DOP853", "BDF", "LSODA")


class OdeResult(dict):
    """scipy's fields: t, y (n x points), sol, t_events, y_events, nfev, njev, nlu, status,
    message, success; also as attributes. Beyond scipy: naccepted, nrejected."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__

    def __repr__(self):
        return "\n".join(f"{k:>9}: {v!r}" for k, v in self.items())


class OdeSolution:
    """The continuous solution: the method's dense output in every step, sampled at 8
    Chebyshev points and interpolated there (exact for dense outputs of degree up to 7,
    which includes every method's default). sol(t) for a scalar t gives (n,), for an array
    (n, len(t)), as scipy's."""

    def __init__(self, ts, y0, nodes):
        self.ts = np.asarray(ts)
        self.t_min, self.t_max = min(ts[0], ts[-1]), max(ts[0], ts[-1])
        k = nodes.shape[1]  # nodes per step beyond its start
        self._x = 0.5 - 0.5 * np.cos(np.pi * np.arange(k + 1) / k)  # on [0, 1]
        w = (-1.0) ** np.arange(k + 1)
        w[0] *= 0.5
        w[-1] *= 0.5
        self._w = w
        starts = np.concatenate([np.asarray(y0)[None, :], nodes[:-1, -1, :]], axis=0)
        self._values = np.concatenate([starts[:, None, :], nodes], axis=1)  # steps x (k+1) x n

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        scalar = t.ndim == 0
        t = np.atleast_1d(t)
        forward = self.ts[-1] >= self.ts[0]
        ts = self.ts if forward else -self.ts
        s = t if forward else -t
        i = np.clip(np.searchsorted(ts, s, side="right") - 1, 0, len(ts) - 2)
        x = (s - ts[i]) / (ts[i + 1] - ts[i])
        out = np.empty((len(t), self._values.shape[2]))
        for j in range(len(t)):
            d = x[j] - self._x
            hit = np.flatnonzero(d == 0.0)
            if hit.size:
                out[j] = self._values[i[j], hit[0]]
            else:
                c = self._w / d
                out[j] = c @ self._values[i[j]] / c.sum()
        return out[0] if scalar else out.T


class CompiledRhs:
    """A right-hand side compiled to machine code: the address of a C function
    void f(double t, const double* y, double* dydt). Called without Python in between, so
    the implicit methods may also evaluate it on several threads. From ctypes
    (`CompiledRhs(ctypes_function)`) or numba (`CompiledRhs(cfunc.address)`); keep the
    compiled object alive while it is used."""

    def __init__(self, function):
        if isinstance(function, int):
            self.address = function
        elif hasattr(function, "address"):  # numba cfunc
            self.address = int(function.address)
        else:  # a ctypes function pointer
            self.address = ctypes.cast(function, ctypes.c_void_p).value
        self._keep = function
        if not self.address:
            raise InputError("CompiledRhs: a null function address")


def _event_tuple(event, args):
    g = event if not args else (lambda t, y, e=event: e(t, y, *args))
    direction = getattr(event, "direction", 0)
    direction = 0 if direction == 0 else (1 if direction > 0 else -1)
    terminal = bool(getattr(event, "terminal", False))
    return (g, direction, terminal)


def solve_ivp(fun, t_span, y0, method="RK45", t_eval=None, dense_output=False, events=None, vectorized=False,
              args=None, *, rtol=1e-3, atol=1e-6, first_step=None, max_step=None, jac=None, jac_sparsity=None,
              variant="", linear_solver="auto", threads=1, **options):
    """Solves y' = fun(t, y) on t_span from y0, as scipy.integrate.solve_ivp does (its
    arguments and result fields), with mbsflow's methods in C++. fun may be a CompiledRhs
    for speed. jac: a callable jac(t, y) or a constant matrix, dense or scipy sparse; with
    jac_sparsity (or a sparse constant jac) the Newton matrices are sparse (KLU). variant,
    linear_solver and threads are mbsflow's (threads: for a CompiledRhs on a large system,
    the stages on several threads; a Python fun always runs on one). vectorized is accepted and not used (mbsflow calls fun one
    point at a time). Ctrl-C stops the integration (KeyboardInterrupt)."""
    if options:
        raise InputError("solve_ivp: unknown option(s) " + ", ".join(sorted(options)))
    if method in _NOT_HERE:
        raise InputError(f"method={method}: not in mbsflow; use 'tirk' (or 'Radau'), 'colloc', 'dopri5' (or 'RK45') "
                         "or 'rk4'")
    if max_step is not None and np.isfinite(max_step):
        raise InputError("max_step: not supported (the methods control their steps by the tolerances)")
    name, alias_variant = _ALIASES.get(method, (method, ""))
    variant = variant or alias_variant
    t0, t1 = (float(v) for v in t_span)
    if t1 == t0:
        raise InputError("t_span: the two ends must differ")
    y0 = np.array(y0, dtype=float).reshape(-1)
    compiled = 0
    if isinstance(fun, CompiledRhs):
        compiled, py_fun = fun.address, None
    else:
        if not callable(fun):
            raise InputError("fun: must be callable or a CompiledRhs")
        py_fun = fun if not args else (lambda t, y: fun(t, y, *args))
    if callable(jac) and args:
        jac_fun = jac
        jac = lambda t, y: jac_fun(t, y, *args)  # noqa: E731
    direction = 1.0 if t1 > t0 else -1.0
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float).reshape(-1)
        if np.any(direction * np.diff(t_eval) < 0):
            raise InputError("t_eval: must be sorted in the direction of integration")
        lo, hi = min(t0, t1), max(t0, t1)
        if np.any((t_eval < lo) | (t_eval > hi)):
            raise InputError("t_eval: must lie within t_span")
    if events is None:
        events = []
    elif callable(events):
        events = [events]
    out = _core._solve_ivp(py_fun, compiled, t0, t1, y0, name, np.atleast_1d(np.asarray(rtol, dtype=float)),
                           np.atleast_1d(np.asarray(atol, dtype=float)), float(first_step or 0.0),
                           [] if t_eval is None else list(t_eval), bool(dense_output),
                           [_event_tuple(e, args) for e in events], jac, jac_sparsity, variant, linear_solver, threads)
    result = OdeResult(t=out["t"], y=out["y"].T.copy(), sol=None,
                       t_events=out["t_events"] if events else None,
                       y_events=out["y_events"] if events else None,
                       nfev=out["nfev"], njev=out["njev"], nlu=out["nlu"], status=out["status"],
                       message=out["message"], success=out["status"] >= 0,
                       naccepted=out["accepted"], nrejected=out["rejected"])
    if dense_output:
        result["sol"] = OdeSolution(out["dense_t"], y0, out["dense_y"])
    if out["warning"]:  # a component held to atol only (methods/uncontrolled.hpp)
        warnings.warn(out["warning"], RuntimeWarning, stacklevel=2)
    return result
