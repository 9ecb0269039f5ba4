#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""mpi_overhead.py - the cost of MPI on one machine, measured side by side.

    tools/mpi_overhead.py [--n 4096] [--steps 150] [--rounds 3]

Runs the cone case scaled to N x N cells (forward Euler, a fixed number of
steps, two snapshots) four ways on the same cores, interleaved round by
round in ABBA order so that a drift of the machine's load cancels:

    serial   build/sandslide --threads 1     against  mpirun -np 1 --threads 1
    serial   build/sandslide --threads 2     against  mpirun -np 2 --threads 1

and prints, per way, the median over rounds of the wall time, of the
kernel time (slope + sweep), of the output and of rank 0's time in MPI
calls, as the run's summary line gives them, and the ratios.  MPI_IO=NAME
in the environment picks Open MPI's MPI-IO component (OMPI_MCA_io: ompio,
its default, or romio321).  Every run's heights are checked
to be the serial run's bits.  Needs build/sandslide and build-mpi/sandslide
(make, make MPI=1) and writes to a temporary folder.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import h5py

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SERIAL = os.path.join(ROOT, "build", "sandslide")
MPI = os.path.join(ROOT, "build-mpi", "sandslide")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_pml="ob1",
           OMPI_MCA_btl="self,vader", OMPI_MCA_btl_base_warn_component_unused="0")
if os.environ.get("MPI_IO"):
    ENV["OMPI_MCA_io"] = os.environ["MPI_IO"]

CASE = """[grid]
nx = {n}
ny = {n}
dx = {dx!r}
origin = -1.215 -1.215
[model]
closure = coulomb
repose_angle = 35
nu = 0.1
[time]
end = {end!r}
output_every = {end!r}
integrator = euler
[boundary]
west = wall
east = wall
south = wall
north = wall
[initial]
type = cone
center = 0 0
radius = 0.8
angle = 50
height = 0
"""

SUMMARY = re.compile(r"wall ([0-9.]+) s: slope ([0-9.]+) s, sweep ([0-9.]+) s, "
                     r"output ([0-9.]+) s(?:, mpi ([0-9.]+) s)?; (\d+) stencil")


def run(way, case, out):
    kind, count = way
    if kind == "serial":
        cmd = [SERIAL, "run", case, "-o", out, "--force", "--threads", str(count)]
    else:
        cmd = ["mpirun.openmpi", "-np", str(count), "--bind-to", "none", MPI, "run", case,
               "-o", out, "--force", "--threads", "1"]
    r = subprocess.run(cmd, capture_output=True, text=True, env=ENV)
    m = SUMMARY.search(r.stdout)
    if r.returncode != 0 or not m:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stdout}{r.stderr}")
    wall, slope, sweep, output, mpi, evals = m.groups()
    return dict(wall=float(wall), kernel=float(slope) + float(sweep), output=float(output),
                mpi=float(mpi or 0.0), evaluations=int(evals))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=4096)
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    dx = 2.43 / a.n
    dt = 0.9 * dx * dx / (4 * 0.1)        # forward Euler's step for Lambda = 1
    d = tempfile.mkdtemp(prefix="mpi_overhead.")
    case = os.path.join(d, "cone.ini")
    with open(case, "w") as f:
        f.write(CASE.format(n=a.n, dx=dx, end=a.steps * dt))
    pairs = [(("serial", 1), ("mpi", 1)), (("serial", 2), ("mpi", 2))]
    results = {w: [] for p in pairs for w in p}
    reference = None
    for r in range(a.rounds):
        for pair in pairs:
            for way in (pair if r % 2 == 0 else pair[::-1]):
                out = os.path.join(d, f"{way[0]}{way[1]}.h5")
                results[way].append(run(way, case, out))
                with h5py.File(out, "r") as f:
                    h = f["height"][-1].tobytes()
                if reference is None:
                    reference = h
                elif h != reference:
                    sys.exit(f"{way}: heights differ from the first run's")
                os.remove(out)
    print(f"cone {a.n} x {a.n}, forward Euler, {results[pairs[0][0]][0]['evaluations']} steps, "
          f"{a.rounds} rounds interleaved; medians, s")
    print(f"{'way':22s} {'wall':>8s} {'kernel':>8s} {'output':>8s} {'mpi':>8s}")
    med = {}
    for way, rs in results.items():
        med[way] = {k: statistics.median(x[k] for x in rs)
                    for k in ("wall", "kernel", "output", "mpi")}
        name = f"serial --threads {way[1]}" if way[0] == "serial" else \
               f"mpirun -np {way[1]} --threads 1"
        print(f"{name:22s} {med[way]['wall']:8.3f} {med[way]['kernel']:8.3f} "
              f"{med[way]['output']:8.3f} {med[way]['mpi']:8.3f}")
    for s, m in pairs:
        print(f"np {m[1]} / serial {s[1]} thread(s): wall {med[m]['wall'] / med[s]['wall']:.3f}, "
              f"kernel {med[m]['kernel'] / med[s]['kernel']:.3f}, output "
              f"{med[m]['output'] / med[s]['output']:.3f}; mpi share of rank 0's "
              f"wall {med[m]['mpi'] / med[m]['wall']:.3f}, per step "
              f"{1e6 * med[m]['mpi'] / results[m][0]['evaluations']:.0f} us")
    print("(every run's final heights: the same bits)")


if __name__ == "__main__":
    main()
