#!/usr/bin/python3
"""Work-precision plot of `mbsflow bench ode` or `mbsflow bench stiff`: seconds against achieved error,
one panel per problem or model, one line per solver and thread count.

usage: scripts/plot_work_precision.py bench_ode.csv|bench_stiff.csv [-o FILE.png]
"""
import math
from collections import defaultdict

from bench_csv import plt, read_rows, save


def point(row):
    """(panel, line, error, seconds) of a CSV row of either benchmark; None for a failed run
    or the reference run itself."""
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
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.5), squeeze=False)
    for ax, panel in zip(axes[0], panels):
        for (p, label), points in sorted(series.items()):
            if p != panel:
                continue
            points.sort()
            ax.loglog([e for e, _ in points], [s for _, s in points], "o-", markersize=3, label=label)
        ax.set(xlabel="max error", ylabel="seconds", title=panel)
        ax.invert_xaxis()
        ax.legend(fontsize="x-small")
    save(fig, out)


if __name__ == "__main__":
    main()
