#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The steepest face of each snapshot of a sandslide output against time.

    python3 tools/steepest_slope.py OUT.h5 [-o FIGURE.png] [--csv FILE.csv]

Reads /time and /max_slope_deg (doc/output.md) and the case's repose and
static angles (the root attribute `case`), and draws the one against the
other with the two angles as lines: the figure of doc/model.md#hysteresis
(cases/hysteresis.ini).  Prints the avalanches it sees: each fall of the
steepest face from within 1 degree of the static angle to within 1.5
degrees of the repose angle.
"""
import argparse
import configparser
import sys

import h5py


def angles(case_text):
    c = configparser.ConfigParser(inline_comment_prefixes=(";", "#"))
    c.read_string(case_text)
    m = c["model"] if c.has_section("model") else {}
    repose = float(m.get("repose_angle", "nan"))
    return repose, float(m.get("static_angle", repose))


def avalanches(slopes, repose, static):
    """(start, end) snapshot indices of each fall from near static to near repose."""
    found, top = [], None
    for k, s in enumerate(slopes):
        if s >= static - 1.0:
            top = k if top is None or s >= slopes[top] else top
        elif top is not None and s <= repose + 1.5:
            found.append((top, k))
            top = None
    return found


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("output", help="a sandslide output (.h5)")
    p.add_argument("-o", "--figure", help="write the figure here (PNG)")
    p.add_argument("--csv", help="write time_s,max_slope_deg here")
    a = p.parse_args()
    with h5py.File(a.output, "r") as f:
        t = f["time"][:]
        s = f["max_slope_deg"][:]
        case = f.attrs["case"]
        case = case.decode() if isinstance(case, bytes) else str(case)
    repose, static = angles(case)
    found = avalanches(list(s), repose, static)
    print(f"{a.output}: {len(t)} snapshots to t = {t[-1]:g} s; repose {repose:g} deg, "
          f"static {static:g} deg; {len(found)} avalanches")
    for top, end in found:
        print(f"  t = {t[top]:7.2f} s at {s[top]:.2f} deg -> t = {t[end]:7.2f} s at "
              f"{s[end]:.2f} deg")
    if a.csv:
        with open(a.csv, "w") as out:
            out.write("time_s,max_slope_deg\n")
            for ti, si in zip(t, s):
                out.write(f"{ti!r},{si!r}\n")
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 3.2), dpi=100)
        ax.plot(t, s, color="#444444", lw=1.2, label="steepest face")
        ax.axhline(static, color="#c0392b", lw=0.8, ls="--", label=f"static angle {static:g}")
        ax.axhline(repose, color="#2471a3", lw=0.8, ls="--", label=f"repose angle {repose:g}")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("steepest face (deg)")
        ax.set_ylim(max(0.0, repose - 8.0), static + 3.0)
        ax.legend(loc="lower right", fontsize=8, frameon=False)
        ax.set_title(a.output, fontsize=9)
        fig.tight_layout()
        fig.savefig(a.figure)
        print(f"wrote {a.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
