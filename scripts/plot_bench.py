#!/usr/bin/python3
"""Plot the CSV of `mbsflow bench parallel`: speedup and efficiency over threads and
processes, with the efficiency `mbsflow plan` predicts (thin dotted lines).

usage: scripts/plot_bench.py bench_parallel.csv [-o bench_parallel.png]
"""
from collections import defaultdict

from bench_csv import plt, read_rows, save


def main():
    rows, out = read_rows(__doc__)
    series = defaultdict(list)
    for row in rows:
        if row["executor"] == "sequential":
            continue
        series[(int(row["bodies"]), row["executor"])].append(
            (int(row["threads"]), float(row["speedup"]), float(row["efficiency"]),
             float(row.get("predicted_efficiency") or "nan")))
    fig, (ax_s, ax_e) = plt.subplots(1, 2, figsize=(11, 4.5))
    for (bodies, executor), points in sorted(series.items()):
        points.sort()
        threads = [p[0] for p in points]
        style = {"flow": "-o", "barrier": "--s"}.get(executor, "-.^")
        lines = ax_s.plot(threads, [p[1] for p in points], style, label=f"{bodies} bodies, {executor}")
        ax_e.plot(threads, [p[2] for p in points], style, color=lines[0].get_color(), label=f"{bodies} bodies, {executor}")
        if executor != "barrier":  # the barrier rows share the flow rows' prediction
            ax_e.plot(threads, [p[3] for p in points], ":", lw=0.8, color=lines[0].get_color())
    top = max((p[0] for pts in series.values() for p in pts), default=1)
    ax_s.plot([1, top], [1, top], "k:", label="ideal")
    ax_s.set(xlabel="threads or processes", ylabel="speedup over the sequential run", title="speedup")
    ax_e.axhline(0.9, color="grey", lw=0.8)
    ax_e.set(xlabel="threads or processes", ylabel="efficiency", title="parallel efficiency (dotted: predicted)", ylim=(0, 1.1))
    ax_s.legend(fontsize="small")
    save(fig, out)


if __name__ == "__main__":
    main()
