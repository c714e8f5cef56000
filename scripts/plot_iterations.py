#!/usr/bin/python3
"""Iteration error of the tirk schemes after 1, 2, ... iterations (`mbsflow bench
iterations`): one row of panels per problem, one panel per step (as a multiple of the
Jacobi contraction bound), one line per scheme.

usage: scripts/plot_iterations.py bench_iterations.csv [-o bench_iterations.png]
"""
import math
from collections import defaultdict

from bench_csv import plt, read_rows, save


def main():
    rows, out = read_rows(__doc__)
    data = defaultdict(lambda: defaultdict(list))  # (problem, factor) -> scheme -> [(nu, error)]
    problems, factors = [], defaultdict(list)
    for row in rows:
        p, k = f"{row['problem']} N={row['n']}", float(row["tau_over_jacobi_bound"])
        if p not in problems:
            problems.append(p)
        if k not in factors[p]:
            factors[p].append(k)
        e = float(row["error"])
        data[(p, k)][row["scheme"]].append((int(row["iteration"]), e if math.isfinite(e) else float("nan")))
    cols = max(len(v) for v in factors.values())
    fig, axes = plt.subplots(len(problems), cols, figsize=(3.2 * cols, 2.8 * len(problems)), squeeze=False)
    for r, p in enumerate(problems):
        for c in range(cols):
            ax = axes[r][c]
            if c >= len(factors[p]):
                ax.axis("off")
                continue
            k = factors[p][c]
            for scheme, pts in data[(p, k)].items():
                pts = [(n, max(e, 1e-18)) for n, e in pts if e == e]
                if pts:
                    ax.semilogy(*zip(*pts), marker="o", ms=3, label=scheme)
            ax.set_ylim(1e-18, 1e3)
            ax.set_title(f"{p}, tau = {k:g} x bound", fontsize=8)
            ax.set_xlabel("iteration")
            if c == 0:
                ax.set_ylabel("error to converged stages")
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=6)
    save(fig, out)


if __name__ == "__main__":
    main()
