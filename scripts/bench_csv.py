"""What the plot scripts of `mbsflow bench` share: their command line, the CSV rows, and
saving the figure (next to the CSV unless -o says where)."""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the scripts take plt from here, with Agg set)

__all__ = ["plt", "read_rows", "save"]


def read_rows(doc):
    """Parses `SCRIPT FILE.csv [-o FILE.png]` (doc: the script's docstring, whose first
    line is the help text); returns the CSV rows as dicts and the figure's path."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("csv")
    parser.add_argument("-o", "--output", default="")
    args = parser.parse_args()
    with open(args.csv) as f:
        rows = list(csv.DictReader(f))
    return rows, args.output or args.csv.rsplit(".", 1)[0] + ".png"


def save(fig, out):
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(out)
