#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""A twin experiment for `sandslide fit` (doc/fit.md), the benchmark of
doc/performance.md#fitting-the-cone.

    tools/fit_twin.py [--closure casson] [--nu 0.13] [--angle 35] [--nx 81]
                      [--sigma 0.002] [--missing 0.2] [--times 1,2,3,5,8,12]
                      [--fit-angle] [--threads 2] [--out DIR]

Runs cases/cone.ini (at nx x nx cells over the same floor, to the last
time) with the true closure and parameters, degrades the snapshots at the
given times (Gaussian noise of sigma m, a fraction `missing` of the cells
NaN; seed 1), then fits nu (and the angle with --fit-angle) with all four
closures, and prints the summary, the truth, the relative error of nu and
the forward runs with their time.  Needs python3-h5py and python3-numpy.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--sandslide", default=os.path.join(ROOT, "build", "sandslide"))
    a.add_argument("--closure", default="casson")
    a.add_argument("--nu", type=float, default=0.13)
    a.add_argument("--angle", type=float, default=35.0)
    a.add_argument("--nx", type=int, default=81)
    a.add_argument("--sigma", type=float, default=0.002)
    a.add_argument("--missing", type=float, default=0.2)
    a.add_argument("--times", default="1,2,3,5,8,12")
    a.add_argument("--fit-angle", action="store_true")
    a.add_argument("--threads", type=int, default=2)
    a.add_argument("--out", default="out/fit_twin")
    o = a.parse_args()
    times = [float(t) for t in o.times.split(",")]
    os.makedirs(o.out, exist_ok=True)
    side = 2.43                                   # cases/cone.ini's floor, m
    text = open(os.path.join(ROOT, "cases", "cone.ini")).read()
    lines = [ln for ln in text.splitlines()
             if not ln.startswith(("nx", "ny", "dx", "origin", "end", "steady_tol",
                                   "max_time", "output_every"))]
    case = "\n".join(lines).replace(
        "[grid]\n", f"[grid]\nnx = {o.nx}\nny = {o.nx}\ndx = {side / o.nx!r}\n"
                    f"origin = {-side / 2!r} {-side / 2!r}\n").replace(
        "[time]\n", f"[time]\nend = {max(times)!r}\noutput_every = {min(times)!r}\n")
    case_path = os.path.join(o.out, "cone.ini")
    open(case_path, "w").write(case + "\n")
    truth = os.path.join(o.out, "truth.h5")
    subprocess.run([o.sandslide, "run", case_path, "-o", truth, "-q", "--force",
                    "--set", f"model.closure={o.closure}", "--set", f"model.nu={o.nu!r}",
                    "--set", f"model.repose_angle={o.angle!r}"], check=True)
    rng = np.random.default_rng(1)
    with h5py.File(truth, "r") as f:
        t, h, x, y = f["time"][:], f["height"][:], f["x"][:], f["y"][:]
    idx = [int(np.argmin(abs(t - s))) for s in times]
    hs = h[idx] + rng.normal(0.0, o.sigma, h[idx].shape)
    hs[rng.random(hs.shape) < o.missing] = np.nan
    obs = os.path.join(o.out, "scan.h5")
    with h5py.File(obs, "w") as g:
        g["time"], g["height"], g["x"], g["y"] = t[idx], hs, x, y
    cmd = [o.sandslide, "fit", case_path, obs, "--param", "nu=0.01:1:log", "--closures",
           "all", "--threads", str(o.threads), "--force", "-o",
           os.path.join(o.out, "fit.json"), "--plot", os.path.join(o.out, "fit.png")]
    if o.fit_angle:
        cmd += ["--param", "repose_angle=30:40"]
    print("$", " ".join(cmd), flush=True)
    start = time.monotonic()
    subprocess.run(cmd, check=True)
    wall = time.monotonic() - start
    r = json.load(open(os.path.join(o.out, "fit.json")))
    best = r["best"]
    print(f"truth: {o.closure}, nu = {o.nu}, angle = {o.angle}; best: {best['closure']}, "
          f"nu = {best['params']['nu']:.5g} ({best['params']['nu'] / o.nu - 1:+.2%})"
          + (f", angle = {best['params']['repose_angle']:.4g}" if o.fit_angle else ""))
    print(f"{r['forward_runs']} forward runs, {r['seconds_per_run']:.4g} s each; "
          f"{wall:.1f} s wall on {o.threads} threads; verdict: {r['verdict']}")
    return 0 if best["closure"] == o.closure else 1


if __name__ == "__main__":
    sys.exit(main())
