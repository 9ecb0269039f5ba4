#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""mpi_outflow.py - what folding the outflow once a batch, not once an
evaluation, saves: two MPI builds side by side on cases with open sides.

    tools/mpi_outflow.py OLD NEW [--np 2 4] [--rounds 3]

OLD and NEW are two builds of build-mpi/sandslide (OLD, say, a checkout
from before the batch, built with make MPI=1).  Each runs, under
mpirun -np N --threads 1 for each N given:

    door     cases/door.ini (RKL2, 60 x 40 cells, 39066 evaluations,
             101 snapshots; open south, north and east sides)
    terrain  cases/dem.ini with open sides, forward Euler, to t = 2000 s
             (96 x 96 cells, 7288 evaluations, 11 snapshots)

interleaved round by round in ABBA order (old, new, new, old, ...) so that
a drift of the machine's load cancels, and prints per case and rank count
the median over rounds of the wall time and of rank 0's time in MPI calls
(the run's summary line), new / old, and the MPI time saved per stencil
evaluation.  Every run's /height and /outflow
are checked to be the same bits for both builds.  Writes to a temporary
folder.  For timing, OMP_WAIT_POLICY=passive is set and Open MPI gets the
settings of doc/cluster.md#open-mpi-as-root-on-a-small-machine.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_pml="ob1",
           OMPI_MCA_btl="self,vader", OMPI_MCA_btl_base_warn_component_unused="0",
           OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
OPEN = ["--set", "boundary.west=open", "--set", "boundary.east=open",
        "--set", "boundary.south=open", "--set", "boundary.north=open"]
CASES = {
    "door": [os.path.join(ROOT, "cases", "door.ini")],
    "terrain": [os.path.join(ROOT, "cases", "dem.ini"), *OPEN, "--set", "time.end=2000",
                "--set", "time.integrator=euler"],
}


def run(binary, ranks, case, out):
    cmd = (["mpirun", "-np", str(ranks), "--bind-to", "none", binary, "run"] + CASES[case]
           + ["-o", out, "--force", "--threads", "1"])
    r = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} exited {r.returncode}:\n{r.stderr}")
    wall = re.search(r"wall ([0-9.]+) s", r.stdout)
    mpi = re.search(r"mpi ([0-9.]+) s", r.stdout)
    ev = re.search(r"(\d+) stencil evaluations", r.stdout)
    if not wall or not mpi or not ev:
        sys.exit(f"no wall, mpi or evaluations in the summary of {' '.join(cmd)}:\n{r.stdout}")
    return float(wall.group(1)), float(mpi.group(1)), int(ev.group(1))


def same(a, b):
    with h5py.File(a) as f, h5py.File(b) as g:
        return all(np.array_equal(f[n][()].view(np.uint64), g[n][()].view(np.uint64))
                   for n in ("height", "outflow"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--np", type=int, nargs="+", default=[2, 4])
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    print(f"{'case':8s} {'np':>3s} {'wall old':>9s} {'wall new':>9s} {'new/old':>8s} "
          f"{'mpi old':>9s} {'mpi new':>9s} {'new/old':>8s} {'saved/ev':>9s}")
    with tempfile.TemporaryDirectory() as tmp:
        for ranks in a.np:
            for case in CASES:
                times = {"old": [], "new": []}
                for k in range(a.rounds):
                    order = ("old", "new") if k % 2 == 0 else ("new", "old")
                    for which in order:
                        out = os.path.join(tmp, f"{which}.h5")
                        times[which].append(run(getattr(a, which), ranks, case, out))
                    if not same(os.path.join(tmp, "old.h5"), os.path.join(tmp, "new.h5")):
                        sys.exit(f"{case} under np = {ranks}: /height or /outflow differ")
                med = {w: [statistics.median(t[i] for t in times[w]) for i in (0, 1)]
                       for w in times}
                evaluations = times["new"][0][2]
                saved = (med["old"][1] - med["new"][1]) / evaluations
                print(f"{case:8s} {ranks:3d} {med['old'][0]:8.2f}s {med['new'][0]:8.2f}s "
                      f"{med['new'][0] / med['old'][0]:8.2f} {med['old'][1]:8.2f}s "
                      f"{med['new'][1]:8.2f}s {med['new'][1] / med['old'][1]:8.2f} "
                      f"{saved * 1e6:7.1f}us",
                      flush=True)
    print("medians over rounds; wall and mpi: the run's summary line on rank 0; the "
          "same bits checked")


if __name__ == "__main__":
    main()
