# SPDX-License-Identifier: MIT
# A package, not a script beside the examples, so that the examples glob (python/CMakeLists.txt)
# does not run it as an example.
"""What the plotting examples share: matplotlib without a display (or exit code 77, "skipped",
when it is missing), their common command line (--out, --small) and writing the figure."""
import argparse
import os
import sys


def pyplot():
    """matplotlib.pyplot on the file-only Agg backend; exits 77 (skipped) without matplotlib."""
    try:
        import matplotlib
        matplotlib.use("Agg")  # files only, no display needed
        import matplotlib.pyplot as plt
    except ImportError:
        print("skipped: matplotlib is not installed (Debian: python3-matplotlib)")
        sys.exit(77)
    return plt


def parser(doc, default_out, small_help):
    """An argument parser described by the first line of `doc`, with --out and --small; add more
    options before parse_args()."""
    result = argparse.ArgumentParser(description=doc.splitlines()[0])
    result.add_argument("--out", default=default_out, help="the figure (PNG)")
    result.add_argument("--small", action="store_true", help=small_help)
    return result


def save(figure, out):
    """Writes `figure` to `out` (PNG), creating its folder."""
    figure.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    figure.savefig(out, dpi=100)
