#!/usr/bin/python3
"""Work-precision plot of `mbsflow bench ode`, `bench stiff` or `bench ivp`: seconds against achieved error
(bench ivp: against correct digits at the end), one panel per problem or model, one line per solver and thread count.

usage: scripts/plot_work_precision.py bench_ode.csv|bench_stiff.csv|bench_ivp.csv [-o FILE.png]
"""
import math
from collections import defaultdict

from bench_csv import plt, read_rows, save


def point(row):
    """(panel, line, x, seconds) of a CSV row of any of the benchmarks (x: the error, or
    for bench ivp the correct digits); None for a failed run or the reference run itself."""
    if "scd" in row:  # bench ivp
        if row["ok"] != "1":
            return None
        return f"{row['problem']} N={row['n']}", f"{row['solver']} x{row['threads']}", float(row["scd"]), float(row["seconds"])
    if "model" in row:  # bench stiff: error in m against the reference run
        error = float(row["error_m"])
        if row["method"] == "reference" or not math.isfinite(error) or error <= 0:
            return None
        return row["model"], f"{row['method']} x{row['threads']}", error, float(row["wall_s"])
    if row["ok"] != "1" or float(row["max_error"]) <= 0:
        return None
    return f"{row['problem']} N={row['n']}", f"{row['solver']} x{row['threads']}", float(row["max_error"]), float(row["seconds"])


def main():
    rows, out = read_rows(__doc__)
    series = defaultdict(list)
    panels = []
    for row in rows:
        p = point(row)
        if p is None:
            continue
        panel, label, error, seconds = p
        if panel not in panels:
            panels.append(panel)
        series[(panel, label)].append((error, seconds))
    digits = "scd" in rows[0] if rows else False
    columns = min(len(panels), 3)
    lines = (len(panels) + columns - 1) // columns
    fig, axes = plt.subplots(lines, columns, figsize=(5 * columns, 4.5 * lines), squeeze=False)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax, panel in zip(axes.flat, panels):
        for (p, label), points in sorted(series.items()):
            if p != panel:
                continue
            points.sort()
            plot = ax.semilogy if digits else ax.loglog
            plot([e for e, _ in points], [s for _, s in points], "o-", markersize=3, label=label)
        if digits:
            ax.set(xlabel="correct digits at the end (scd)", ylabel="seconds", title=panel)
        else:
            ax.set(xlabel="max error", ylabel="seconds", title=panel)
            ax.invert_xaxis()
        ax.legend(fontsize="x-small")
    save(fig, out)


if __name__ == "__main__":
    main()
