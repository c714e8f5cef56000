#!/usr/bin/python3
"""Plot the CSV of `mbsflow bench parallel`: speedup and efficiency over threads.

usage: scripts/plot_bench.py bench_parallel.csv [-o bench_parallel.png]
"""
import argparse
import csv
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv")
    parser.add_argument("-o", "--output", default="")
    args = parser.parse_args()
    out = args.output or args.csv.rsplit(".", 1)[0] + ".png"
    series = defaultdict(list)
    with open(args.csv) as f:
        for row in csv.DictReader(f):
            if row["executor"] == "sequential":
                continue
            series[(int(row["bodies"]), row["executor"])].append(
                (int(row["threads"]), float(row["speedup"]), float(row["efficiency"])))
    fig, (ax_s, ax_e) = plt.subplots(1, 2, figsize=(11, 4.5))
    for (bodies, executor), points in sorted(series.items()):
        points.sort()
        threads = [p[0] for p in points]
        style = "-o" if executor == "flow" else "--s"
        ax_s.plot(threads, [p[1] for p in points], style, label=f"{bodies} bodies, {executor}")
        ax_e.plot(threads, [p[2] for p in points], style, label=f"{bodies} bodies, {executor}")
    top = max((p[0] for pts in series.values() for p in pts), default=1)
    ax_s.plot([1, top], [1, top], "k:", label="ideal")
    ax_s.set(xlabel="threads", ylabel="speedup over the sequential run", title="speedup")
    ax_e.axhline(0.9, color="grey", lw=0.8)
    ax_e.set(xlabel="threads", ylabel="efficiency", title="parallel efficiency", ylim=(0, 1.1))
    ax_s.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
