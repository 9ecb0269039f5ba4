#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""compare_outputs.py A.h5 B.h5 - are two sandslide outputs the same bits?

Compares /height, /time, /cell_type, /x, /y, /bedrock (if any) and every
diagnostic series but /wall_seconds, byte for byte.  Prints one line per
file pair, and each dataset that differs; exits 1 if any does.  Used to
hold a change to the outputs of the binary before it:

    OLD=../baseline/build/sandslide NEW=build/sandslide
    $OLD run cases/door.ini -o /tmp/old.h5 -q --set time.end=100
    $NEW run cases/door.ini -o /tmp/new.h5 -q --set time.end=100
    tools/compare_outputs.py /tmp/old.h5 /tmp/new.h5
"""
import sys

import h5py
import numpy as np

NAMES = ["height", "time", "cell_type", "x", "y", "volume", "inflow", "outflow",
         "max_height", "max_slope_deg", "steps", "active_fraction"]


def main(a_path, b_path):
    with h5py.File(a_path, "r", locking=False) as a, h5py.File(b_path, "r", locking=False) as b:
        names = NAMES + (["bedrock"] if "bedrock" in a or "bedrock" in b else [])
        bad = [n for n in names if n not in a or n not in b or a[n].shape != b[n].shape or
               not np.array_equal(a[n][...].view(np.uint8), b[n][...].view(np.uint8))]
        for n in bad:
            print(f"  /{n} differs")
        print(f"{a_path} vs {b_path}: "
              f"{'the same bits' if not bad else f'{len(bad)} datasets differ'} "
              f"({a['height'].shape[0]} snapshots, {int(a['steps'][-1])} steps)")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
