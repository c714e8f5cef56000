#!/usr/bin/python3
"""Plot an mbsflow results file: body trajectories and energies, or (for a file from
mbsflow ode) the solution, its error and the step-size diagram (seed 001, figs. 5-7).

usage: scripts/plot.py FILE.h5 [--bodies a,b,...] [-o plot.png] [--follow [--interval S]]

A file that a run is still writing is read in HDF5's SWMR mode; --follow redraws the
picture every S seconds while the run goes, and once more when it has ended.

Uses Debian's python3-h5py and python3-matplotlib (run it with /usr/bin/python3).
"""
import argparse
import os
import sys
import time

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def pick_bodies(names, wanted):
    if wanted:
        missing = [w for w in wanted if w not in names]
        if missing:
            sys.exit(f"plot.py: no body {', '.join(missing)} in the file")
        return [names.index(w) for w in wanted]
    n = len(names)
    count = min(n, 5)
    return sorted({round(i * (n - 1) / max(count - 1, 1)) for i in range(count)})


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def plot_ode(f, path, out):
    """Solution, error and step sizes of an mbsflow ode run."""
    t = f["solution/time"][:]
    values = f["solution/values"][:]
    comps = f["solution/components"][:]
    has_error = "solution/error" in f
    fig, axes = plt.subplots(1, 3 if has_error else 2, figsize=(16 if has_error else 11, 4.5))
    ax = axes[0]
    for j, c in enumerate(comps):
        ax.plot(t, values[:, j], label=f"x{c + 1}")
    ax.set(xlabel="t", ylabel="x", title="solution")
    if len(comps) <= 9:
        ax.legend(fontsize="small")
    if has_error:
        ax = axes[1]
        ax.semilogy(t, f["solution/error"][:])
        ax.set(xlabel="t", ylabel="max |x - exact|", title="error")
    ax = axes[-1]
    st, tau, taken = f["steps/t"][:], f["steps/tau"][:], f["steps/taken"][:]
    s = int(f.attrs.get("s", 0))
    method = text(f.attrs.get("method", "colloc"))
    if method == "tirk":  # Runge-Kutta steps: accepted (taken = stages) or rejected
        marks = [(taken > 0, "o", "accepted step"), (taken == 0, "x", "rejected")]
        what = f"tirk {text(f.attrs.get('tableau', ''))}, {text(f.attrs.get('iteration', ''))}"
    else:
        marks = [(taken == s + 1, "o", f"{s + 1}-point block taken"), (taken == s, "s", f"{s}-point block taken"),
                 (taken == 0, "x", "rejected")]
        what = f"colloc s = {s}"
    for mask, style, label in marks:
        if mask.any():
            ax.semilogy(st[mask], tau[mask], style, markersize=3, label=label)
    ax.set(xlabel="t", ylabel="step" if method == "tirk" else "point spacing tau", title="step sizes")
    ax.legend(fontsize="small")
    fig.suptitle(f"{text(f.attrs.get('problem', ''))}: N = {int(f.attrs.get('n', 0))}, {what}, "
                 f"tol {f.attrs.get('tol', 0):g}  ({path})")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_joints(f, t, rows, ax):
    """Reaction force magnitude of up to 5 joints (written with --fields joint_force),
    and the effort of the motors among them."""
    force = f["joints/force"]
    joint_names = [text(n) for n in f["joints/names"][:]]
    effort = f["joints/motor_effort"][:rows, :, 0] if "joints/motor_effort" in f else None
    for j in pick_bodies(joint_names, []):
        (line,) = ax.plot(t, (force[:rows, j, :3] ** 2).sum(axis=1) ** 0.5, label=f"{joint_names[j]} |F|")
        if effort is not None and (effort[:, j] != 0).any():
            ax.plot(t, effort[:, j], "--", color=line.get_color(), label=f"{joint_names[j]} motor")
    ax.set(xlabel="t [s]", ylabel="N (motor: N or N m)", title="joint reactions")
    ax.legend(fontsize="small")


def open_results(path, patience=30.0):
    """The file, and whether a run is still writing it: then it is in SWMR mode, and HDF5
    lets in only readers that ask for SWMR. A run that is ending holds the file alone for
    a moment (it adds what SWMR readers must not see made): wait for it."""
    waited = 0.0
    while True:
        try:
            return h5py.File(path, "r"), False
        except OSError:
            pass
        try:
            return h5py.File(path, "r", swmr=True), True
        except OSError:
            if waited >= patience:
                raise
        time.sleep(0.2)
        waited += 0.2


def plot_run(f, path, out, wanted):
    """Trajectories, heights, energies and joint reactions of an mbsflow run."""
    t = f["time"][:]
    rows = len(t)  # the series are at least as long: the time is written last
    names = [n.decode() if isinstance(n, bytes) else n for n in f["bodies/names"][:]]
    chosen = pick_bodies(names, wanted)
    has_pos = "bodies/position" in f
    has_energy = "energy" in f
    has_joints = "joints/force" in f
    if not has_pos and not has_energy:
        sys.exit("plot.py: the file holds neither positions nor energies")
    panels = int(has_pos) * 2 + int(has_energy) + int(has_joints)
    fig, axes = plt.subplots(1, panels, figsize=(5.5 * panels, 4.5), squeeze=False)
    axes = list(axes[0])
    title = f.attrs.get("model_name", "")
    if has_pos:
        pos = f["bodies/position"]
        ax_xy, ax_t = axes.pop(0), axes.pop(0)
        for i in chosen:
            p = pos[:rows, i, :]
            ax_xy.plot(p[:, 0], p[:, 1], label=names[i])
            ax_t.plot(t, p[:, 1], label=names[i])
        ax_xy.set(xlabel="x [m]", ylabel="y [m]", title="trajectories")
        ax_xy.axis("equal")
        ax_t.set(xlabel="t [s]", ylabel="y [m]", title="height over time")
        ax_xy.legend(fontsize="small")
    if has_energy:
        e = f["energy"][:rows]
        ax = axes.pop(0)
        for k, label in enumerate(["kinetic", "gravity", "elastic"]):
            ax.plot(t, e[:, k], label=label)
        ax.plot(t, e.sum(axis=1), "k--", label="total")
        ax.set(xlabel="t [s]", ylabel="energy [J]", title="energy")
        ax.legend(fontsize="small")
    if has_joints:
        plot_joints(f, t, rows, axes.pop(0))
    fig.suptitle(f"{title}  ({path})")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return f"{rows} snapshots" + (f", t = {t[-1]:g} s" if rows else "")


def draw(path, out, wanted):
    """One picture of the file as it is now; returns what it showed and whether the run goes on."""
    f, live = open_results(path)
    with f:
        if "solution" in f:
            plot_ode(f, path, out)
            return "ODE solution", live
        return plot_run(f, path, out, wanted), live


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("--bodies", default="", help="comma-separated body names (default: up to 5 spread over the model)")
    parser.add_argument("-o", "--output", default="", help="PNG to write (default: FILE.png)")
    parser.add_argument("--follow", action="store_true", help="redraw while a run writes the file, until it ends")
    parser.add_argument("--interval", type=float, default=2.0, help="--follow: seconds between pictures (default 2)")
    args = parser.parse_args()
    out = args.output or (args.file.rsplit(".", 1)[0] + ".png")
    wanted = [b for b in args.bodies.split(",") if b]
    while True:
        partial = out + ".part.png"  # renamed into place: a viewer never sees half a picture
        shown, live = draw(args.file, partial, wanted)
        os.replace(partial, out)
        if not args.follow:
            print(out)
            return
        print(f"{out}: {shown}" + (" (run going)" if live else " (run ended)"), flush=True)
        if not live:
            return
        time.sleep(args.interval)


if __name__ == "__main__":
    try:
        main()
    except (OSError, KeyError, ValueError) as e:  # one line, as mbsflow's other commands say it
        sys.exit(f"mbsflow plot: {e}")
