#!/usr/bin/python3
"""Benchmarks of the Python package (docs/python.md): prints tables and writes CSV.

1. Stepping: a Python `while sim.step()` loop (and one that also reads the state and
   sets a load every step, a controller's loop) against the same steps in one C++ call
   (`sim.advance_to`), on a 100-body chain. The overhead is the ratio minus one.
2. solve_ivp on Van der Pol, mu = 1000 (Hairer's scaling, on [0, 2], where the Test Set
   for IVP Solvers gives the end value), against scipy's Radau at equal error: each
   solver over a range of tolerances, the error at the end, the wall time (best of
   --repeat), and mbsflow's speed-up over scipy at the same error (scipy's time
   interpolated log-log between its two neighbouring errors).

usage: PYTHONPATH=build/release/python scripts/bench_python.py [--csv DIR] [--quick]
"""
import argparse
import csv
import ctypes
import math
import os
import subprocess
import tempfile
import time

import numpy as np
import scipy.integrate

import mbsflow

VDP_END = np.array([0.1706167732170483e1, -0.8928097010247975e0])  # Test Set for IVP Solvers, VDPOL
EPS = 1e-6  # 1 / mu^2


def best_time(fn, repeat):
    best, out = math.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def stepping(repeat, bodies, t_end):
    model = mbsflow.generate.chain(n=bodies, t_end=t_end)
    rows = []
    for method in ("rk4", "dopri5", "tirk"):
        def cxx():
            sim = mbsflow.Simulation(model, method=method)
            sim.advance_to(t_end)
            return sim.stats["accepted"]

        def python_loop():
            sim = mbsflow.Simulation(model, method=method)
            while sim.step():
                pass
            return sim.stats["accepted"]

        def controller_loop():
            sim = mbsflow.Simulation(model, method=method)
            zero = np.zeros(3)
            while sim.t < t_end:
                p = sim.positions
                sim.set_load(bodies - 1, [0.0, -0.01 * p[-1, 1], 0.0], zero)
                if not sim.step():
                    break
            return sim.stats["accepted"]
        # interleaved, so that a change in the machine's load hits all three
        times = {"cxx": math.inf, "python": math.inf, "controller": math.inf}
        steps = {}
        for _ in range(repeat):
            for name, fn in (("cxx", cxx), ("python", python_loop), ("controller", controller_loop)):
                t, steps[name] = best_time(fn, 1)
                times[name] = min(times[name], t)
        rows.append(dict(method=method, bodies=bodies, steps=steps["cxx"], cxx_s=times["cxx"],
                         python_loop_s=times["python"], controller_loop_s=times["controller"],
                         overhead_pct=100 * (times["python"] / times["cxx"] - 1),
                         controller_overhead_pct=100 * (times["controller"] / times["cxx"] - 1),
                         us_per_step_cxx=1e6 * times["cxx"] / steps["cxx"]))
    return rows


def vdp(t, y):
    return [y[1], ((1 - y[0] * y[0]) * y[1] - y[0]) / EPS]


def vdp_jac(t, y):
    return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / EPS, (1 - y[0] * y[0]) / EPS]]


def compiled_vdp(folder):
    """The same right-hand side in C, built with the system's cc (None without one)."""
    src = os.path.join(folder, "vdp.c")
    with open(src, "w") as f:
        f.write("void vdp(double t, const double* y, double* dy) {\n  (void)t;\n"
                f"  dy[0] = y[1]; dy[1] = ((1 - y[0] * y[0]) * y[1] - y[0]) / {EPS!r};\n}}\n")
    try:
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", os.path.join(folder, "vdp.so"), src], check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    return ctypes.CDLL(os.path.join(folder, "vdp.so"))


def work_precision(repeat, tolerances):
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        lib = compiled_vdp(folder)
        def ours(method, fun=vdp, jac=vdp_jac, variant=""):
            return lambda tol: mbsflow.solve_ivp(fun, (0, 2), [2, 0], method=method, rtol=tol, atol=tol, jac=jac,
                                                 variant=variant)
        solvers = [
            ("scipy Radau", lambda tol: scipy.integrate.solve_ivp(vdp, (0, 2), [2, 0], method="Radau", rtol=tol,
                                                                   atol=tol, jac=vdp_jac)),
            ("mbsflow Radau", ours("Radau")),  # tirk radau3: scipy's method (RADAU5's)
            ("mbsflow Radau, no jac", ours("Radau", jac=None)),
            ("mbsflow tirk radau5", ours("tirk", variant="radau5")),  # 5 stages, order 9
            ("mbsflow colloc", ours("colloc")),
        ]
        if lib is not None:
            rhs = mbsflow.CompiledRhs(lib.vdp)
            solvers.append(("mbsflow Radau, compiled", ours("Radau", fun=rhs, jac=None)))
            solvers.append(("mbsflow radau5, compiled", ours("tirk", fun=rhs, jac=None, variant="radau5")))
        for name, solve in solvers:
            for tol in tolerances:
                wall, r = best_time(lambda: solve(tol), repeat)
                err = float(np.max(np.abs(r.y[:, -1] - VDP_END) / np.abs(VDP_END)))
                rows.append(dict(solver=name, tol=tol, error=err, wall_s=wall, nfev=r.nfev, njev=r.njev, nlu=r.nlu,
                                 success=r.success))
    scipy_points = sorted((r["error"], r["wall_s"]) for r in rows if r["solver"] == "scipy Radau")
    for r in rows:
        r["speedup_at_equal_error"] = speedup(r, scipy_points) if r["solver"] != "scipy Radau" else ""
    return rows


def speedup(row, scipy_points):
    """scipy's time at this row's error (log-log between its neighbours) / this row's time;
    empty outside scipy's range of errors."""
    e = row["error"]
    for (e0, t0), (e1, t1) in zip(scipy_points, scipy_points[1:]):
        if e0 <= e <= e1 and e1 > e0:
            w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))) / row["wall_s"]
    return ""


def print_table(title, rows, columns):
    print(title)
    print("  " + "  ".join(f"{c:>22}" for c in columns))
    for r in rows:
        cells = []
        for c in columns:
            v = r[c]
            cells.append(f"{v:>22.4g}" if isinstance(v, float) else f"{str(v):>22}")
        print("  " + "  ".join(cells))
    print()


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--csv", default=".", help="folder for bench_python_stepping.csv and bench_python_ivp.csv")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="a short run (to check that it works)")
    a = ap.parse_args()
    repeat = 1 if a.quick else a.repeat
    steps = stepping(repeat, 100, 0.01 if a.quick else 0.5)
    print_table("Stepping a 100-body chain: Python loop vs one C++ call (best of %d)" % repeat, steps,
                ["method", "steps", "us_per_step_cxx", "overhead_pct", "controller_overhead_pct"])
    tols = [1e-4, 1e-6] if a.quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
    ivp = work_precision(repeat, tols)
    print_table("Van der Pol mu = 1000 on [0, 2]: error at the end vs wall time (best of %d)" % repeat, ivp,
                ["solver", "tol", "error", "wall_s", "nfev", "nlu", "speedup_at_equal_error"])
    os.makedirs(a.csv, exist_ok=True)
    write_csv(os.path.join(a.csv, "bench_python_stepping.csv"), steps)
    write_csv(os.path.join(a.csv, "bench_python_ivp.csv"), ivp)
    print("CSV: %s, %s" % (os.path.join(a.csv, "bench_python_stepping.csv"), os.path.join(a.csv, "bench_python_ivp.csv")))


if __name__ == "__main__":
    main()
