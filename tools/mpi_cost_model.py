#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""mpi_cost_model.py - what a distributed run costs per step, 1e8 to 1e11 cells.

    tools/mpi_cost_model.py [--cells-per-rank 1e8] [--rate 3e9] [--latency 2e-6]
                            [--bandwidth 1e10] [--io 1e10] [--open] [--fold-every K]

A model, not a measurement: doc/performance.md#mpi-at-scale-the-cost-model prints its
table and says how it compares with what was measured on one machine.

What sandslide does per stencil evaluation (an Euler step or an RKL2 stage)
on P ranks, each a slab of whole tile rows of an n x n grid (comm.h):
  - halo: a row of heights to each neighbour and one back (8 stride bytes,
    stride = n + 2 rounded up to 8), then the changed edges of the edge
    tile rows (n / 256 bytes): 4 messages out, 4 in, both sides at once;
  - two MPI_Allreduce of 64 bytes (the largest slope before the sweep; the
    largest rate and the stop flag after it);
  - with open faces only: the outflow, not per evaluation but once per
    batch of K evaluations (src/core/ledger.h): each rank keeps its open faces'
    fluxes, then 2 K running sums are folded rank after rank (P - 1 hops of
    16 K bytes) and broadcast, so that every sum has the one-rank bits.
    The batch is folded when a run writes a snapshot or when it is full:
    at most 14563 evaluations, and about 393216 fluxes a rank (4 MiB), so
    K = 393216 / F + 1 when F open faces of a rank carry flux in every
    evaluation.  Assumed (--fold-every overrides it): open west and east
    sides, every face carrying flux, F = 2 n / P; an open south or north
    side gives the first or last rank n faces (K = 2 if all of them carry
    flux at once);
  - the sweep itself: n^2 / P cells at `rate` cell-updates/s per rank.
Per snapshot: 8 n^2 bytes of /height in one collective write, at `io`
bytes/s for the whole job.  Memory: 18 B per cell (Euler), 45 (RKL2).

Assumptions (the defaults): a rank is a node of a cluster, 1e8 cells each
(1.8 GB with Euler), sweeping 3e9 cell-updates/s (about half of what a
100 GB/s node can stream at 16 B per update; one core here does 3e8);
network latency 2 us per message or reduction stage, 10 GB/s per link;
10 GB/s of parallel file system for the job.  The slab decomposition
allows at most ny / tile_ny ranks (tile rows of 128 cells).
"""
import argparse
import math

BATCH_BYTES = 4 << 20   # SS_LEDGER_BATCH_BYTES (src/core/ledger.h)


def model(cells, a):
    n = math.sqrt(cells)
    ranks = max(1, round(cells / a.cells_per_rank))
    tile_rows = math.ceil(n / 128)
    stride = math.ceil((n + 2) / 8) * 8
    # sent per rank per evaluation (none with one rank)
    halo_bytes = 2 * 8 * stride + 2 * math.ceil(n / 256) if ranks > 1 else 0
    t_compute = cells / ranks / a.rate
    # the outflow batch's evaluations (ledger.c: 4 MiB, a quarter of it
    # for 72 B an evaluation, the rest and one evaluation's for fluxes)
    entries = BATCH_BYTES // 4 // 72
    fluxes = (BATCH_BYTES - 72 * entries) // 8
    faces = 2 * n / ranks
    fold_every = a.fold_every or min(entries, math.floor(fluxes / faces) + 1)
    if ranks == 1:
        t_halo = t_reduce = t_fold = 0.0
    else:
        t_halo = 2 * (a.latency + 8 * stride / a.bandwidth) + 2 * a.latency
        t_reduce = 2 * math.ceil(math.log2(ranks)) * a.latency
        hop = a.latency + 16 * fold_every / a.bandwidth
        t_fold = ((ranks - 1) + math.ceil(math.log2(ranks))) * hop / fold_every if a.open else 0.0
    t_comm = t_halo + t_reduce + t_fold
    return dict(cells=cells, n=n, ranks=ranks, tile_rows=tile_rows, halo_bytes=halo_bytes,
                messages=8 if ranks > 1 else 0, t_compute=t_compute, t_halo=t_halo,
                t_reduce=t_reduce, t_fold=t_fold, fold_every=fold_every,
                share=t_comm / (t_comm + t_compute),
                io=8 * cells / a.io, gb_per_rank=18 * cells / ranks / 1e9)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells-per-rank", type=float, default=1e8)
    ap.add_argument("--rate", type=float, default=3e9, help="cell-updates/s per rank")
    ap.add_argument("--latency", type=float, default=2e-6, help="s per message")
    ap.add_argument("--bandwidth", type=float, default=1e10, help="B/s per link")
    ap.add_argument("--io", type=float, default=1e10, help="B/s of file system")
    ap.add_argument("--open", action="store_true", help="the grid has open faces")
    ap.add_argument("--fold-every", type=int, default=0,
                    help="evaluations per fold of the outflow (default: the batch's, above)")
    a = ap.parse_args()
    print(f"{'cells':>7s} {'n':>7s} {'ranks':>6s} {'max':>6s} {'halo B':>9s} {'msgs':>5s} "
          f"{'sweep':>9s} {'halo':>9s} {'reduce':>9s} {'fold':>9s} {'K':>6s} {'comm %':>7s} "
          f"{'GB/rank':>8s} {'snapshot':>9s}")
    for cells in (1e8, 1e9, 1e10, 1e11):
        m = model(cells, a)
        print(f"{cells:7.0e} {m['n']:7.0f} {m['ranks']:6d} {m['tile_rows']:6d} "
              f"{m['halo_bytes']:9.3g} {m['messages']:5d} {m['t_compute'] * 1e3:7.2f}ms "
              f"{m['t_halo'] * 1e6:7.1f}us {m['t_reduce'] * 1e6:7.1f}us "
              f"{m['t_fold'] * 1e6:7.1f}us {m['fold_every'] if m['t_fold'] else '-':>6} "
              f"{100 * m['share']:6.2f}% "
              f"{m['gb_per_rank']:8.2f} "
              f"{m['io']:8.1f}s")
    print("per stencil evaluation and rank; 'max': the most ranks the slabs allow "
          "(tile rows); fold: the outflow's (with --open), one every K evaluations; "
          "snapshot: /height of the whole grid")


if __name__ == "__main__":
    main()
