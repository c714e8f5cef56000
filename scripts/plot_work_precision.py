#!/usr/bin/python3
"""Work-precision plot of `mbsflow bench ode`: seconds against achieved maximum error,
one panel per problem, one line per solver and thread count.

usage: scripts/plot_work_precision.py bench_ode.csv [-o bench_ode.png]
"""
from collections import defaultdict

from bench_csv import plt, read_rows, save


def main():
    rows, out = read_rows(__doc__)
    series = defaultdict(list)
    problems = []
    for row in rows:
        key = f"{row['problem']} N={row['n']}"
        if key not in problems:
            problems.append(key)
        if row["ok"] == "1" and float(row["max_error"]) > 0:
            series[(key, f"{row['solver']} x{row['threads']}")].append((float(row["max_error"]), float(row["seconds"])))
    fig, axes = plt.subplots(1, len(problems), figsize=(5 * len(problems), 4.5), squeeze=False)
    for ax, problem in zip(axes[0], problems):
        for (p, label), points in sorted(series.items()):
            if p != problem:
                continue
            points.sort()
            ax.loglog([e for e, _ in points], [s for _, s in points], "o-", markersize=3, label=label)
        ax.set(xlabel="max error", ylabel="seconds", title=problem)
        ax.invert_xaxis()
        ax.legend(fontsize="x-small")
    save(fig, out)


if __name__ == "__main__":
    main()
