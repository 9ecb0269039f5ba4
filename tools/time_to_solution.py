#!/usr/bin/python3
"""time_to_solution.py - wall time to the same solution, euler against rkl2.

A benchmark, never a test.  Runs `sandslide run` on two workloads with each
integrator of `[time] integrator` (doc/model.md#rkl2-super-steps), interleaved
(A B, then B A, ... over --rounds), and prints per workload and size the
median wall time, steps, stencil evaluations, the simulated end time, the
volume balance error and how far each integrator's heights are from the
first one's (euler), in units of tan(repose angle) * min(dx, dy):

  door  cases/door.ini (1.5 m x 1.0 m, walls in metres) at 60x40, 120x80,
        240x160, 480x320 cells (dx = dy = 1.5/nx), end 1000 s, snapshots
        every 10 s.
  cone  cases/cone.ini at 256^2 (dx = 2.43/256) until steady, steady_tol
        1e-7 m/s; also the apex height and the flank angle (mean |grad h|
        over flow cells with 0.2 H < h < 0.8 H) of each end state.

Euler at 480x320 takes hours: --skip-euler-above 240 (the default) leaves it
out and prints an *estimated* euler wall, wall(n0) * (n/n0)^4 from the
largest euler door run n0 (4x the cells and 4x the steps per doubling; the
skipping of settled tiles makes the real cost grow more slowly).
The exact command lines come first; outputs go to a temporary folder,
removed at the end unless --keep DIR.  Examples:

  tools/time_to_solution.py --json tts.json                 # everything
  tools/time_to_solution.py --integrators euler --door 60 --door-end 50
  tools/time_to_solution.py --door 60,120 --rounds 3 --rkl2-set time.rkl2_max_stages=64
  tools/time_to_solution.py --dry                           # print the commands only

--compare-cfl C (a debug aid) compares euler with euler at cfl = C in place
of rkl2, to exercise the comparison without a second integrator.
"""
import argparse
import configparser
import json
import math
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse_args(argv):
    """The command line; see the module docstring."""
    ints = lambda s: [int(v) for v in s.split(",") if v]
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", default=os.path.join(ROOT, "build", "sandslide"))
    p.add_argument("--workloads", default="door,cone", help="door,cone (default both)")
    p.add_argument("--integrators", default="euler,rkl2", help="default euler,rkl2")
    p.add_argument("--door", type=ints, default=[60, 120, 240, 480], help="door nx list")
    p.add_argument("--door-end", type=float, default=1000.0, help="s (default 1000)")
    p.add_argument("--door-output-every", type=float, default=10.0, help="s (default 10)")
    p.add_argument("--cone", type=int, default=256, help="cone nx = ny (default 256)")
    p.add_argument("--cone-tol", type=float, default=1e-7, help="steady_tol, m/s")
    p.add_argument("--cone-max-time", type=float, help="raise the case's max_time (300 s)")
    p.add_argument("--skip-euler-above", type=int, default=240,
                   help="no euler run for door nx > N (default 240; 0 runs all)")
    p.add_argument("--rounds", type=int, default=1, help="runs per integrator, ABBA")
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="K=V",
                   help="passed to every run")
    p.add_argument("--rkl2-set", action="append", default=[], metavar="K=V",
                   help="passed to rkl2 runs only")
    p.add_argument("--compare-cfl", type=float, help=argparse.SUPPRESS)
    p.add_argument("--json", metavar="FILE", help="write every number to FILE")
    p.add_argument("--keep", metavar="DIR", help="keep the outputs in DIR")
    p.add_argument("--dry", action="store_true", help="print the commands, run nothing")
    args = p.parse_args(argv)
    if not set(args.workloads.split(",")) <= {"door", "cone"}:
        p.error(f"--workloads {args.workloads}: expected door, cone or door,cone")
    return args


def variants(args):
    """[(name, integrator, sets)]: the reference (euler) first, then the others."""
    if args.compare_cfl is not None:
        return [("euler", "euler", ["time.integrator=euler"]),
                (f"euler-cfl{args.compare_cfl:g}", "euler",
                 ["time.integrator=euler", f"time.cfl={args.compare_cfl!r}"])]
    out = []
    for name in args.integrators.split(","):
        # always named: the case's default (auto) is rkl2
        sets = [f"time.integrator={name}"]
        out.append((name, name, sets + (args.rkl2_set if name == "rkl2" else [])))
    return out


def read_case(path):
    """The case file as a ConfigParser (inline comments after ';')."""
    c = configparser.ConfigParser(inline_comment_prefixes=(";",), strict=False)
    if not c.read(path):
        sys.exit(f"time_to_solution: cannot read {path}")
    return c


def scaled_grid(case, path, nx):
    """--set values for nx cells west to east over the case's own extent (dx = dy),
    so that its origin and the shapes given in metres stay where they are."""
    g = case["grid"]
    dx0 = float(g["dx"])
    width, height = int(g["nx"]) * dx0, int(g["ny"]) * float(g.get("dy", dx0))
    dx = width / nx
    ny = round(height / dx)
    if abs(ny * dx - height) > 1e-9 * height:
        sys.exit(f"time_to_solution: {path}: nx = {nx} gives no whole ny for the "
                 f"{width:g} m x {height:g} m grid with dx = dy")
    return ny, [f"grid.nx={nx}", f"grid.ny={ny}", f"grid.dx={dx!r}", f"grid.dy={dx!r}"]


def plan(args):
    """The jobs: one per workload and size, each with its case and --set list."""
    jobs = []
    wl = args.workloads.split(",")
    if "door" in wl:
        path = os.path.join(ROOT, "cases", "door.ini")
        case = read_case(path)
        for n in sorted(set(args.door)):
            ny, sets = scaled_grid(case, path, n)
            jobs.append(dict(workload="door", nx=n, ny=ny, case=path, sets=sets + [
                f"time.end={args.door_end!r}", f"time.output_every={args.door_output_every!r}"]))
    if "cone" in wl:
        path = os.path.join(ROOT, "cases", "cone.ini")
        case = read_case(path)
        ny, sets = scaled_grid(case, path, args.cone)
        sets += ["time.end=steady", f"time.steady_tol={args.cone_tol!r}"]
        max_time = case["time"].getfloat("max_time")
        if args.cone_max_time is not None:
            max_time = args.cone_max_time
            sets.append(f"time.max_time={max_time!r}")
        jobs.append(dict(workload="cone", nx=args.cone, ny=ny, case=path, sets=sets,
                         max_time=max_time))
    return jobs


def command(args, job, variant, out, extra=()):
    """The sandslide command line of one run."""
    cmd = [args.bin, "run", job["case"], "-o", out, "--quiet", "--force",
           "--threads", str(args.threads)]
    for s in job["sets"] + args.sets + variant[2] + list(extra):
        cmd += ["--set", s]
    return cmd


def run(cmd, what=""):
    """Run cmd; its wall seconds (time.monotonic).  On failure print its stderr, exit 1."""
    t0 = time.monotonic()
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.monotonic() - t0
    if r.returncode != 0:
        sys.stderr.write(f"time_to_solution: {what}failed (exit {r.returncode}): {shlex.join(cmd)}\n"
                         f"{r.stderr}")
        sys.exit(1)
    return wall


def read_output(path):
    """The scalars of one output, and the file's path for the heights."""
    with h5py.File(path, "r", locking=False) as f:
        t = f["time"][...]
        steps = float(f["steps"][-1])
        evals = float(f["stencil_evaluations"][-1]) if "stencil_evaluations" in f else None
        v, qin, qout = (f[n][...] for n in ("volume", "inflow", "outflow"))
        net = (qin[-1] - qin[0]) - (qout[-1] - qout[0])
        denom = max(v[-1], qin[-1])
        r = dict(path=path, time=t, t_end=float(t[-1]), steps=steps, evaluations=evals,
                 volume_error=float(abs(v[-1] - v[0] - net) / denom) if denom > 0 else None,
                 cell_type=f["cell_type"][...], repose=float(f.attrs["repose_angle_deg"]),
                 dx=float(f.attrs["dx"]), dy=float(f.attrs["dy"]))
        r["apex"], r["flank_deg"] = flank(f["height"][-1], r["cell_type"], r["dx"], r["dy"])
    return r


def flank(h, cell_type, dx, dy):
    """Apex height H and the mean slope angle (deg) of flow cells with 0.2 H < h < 0.8 H."""
    flow = cell_type == 0
    apex = float(h[flow].max())
    gy, gx = np.gradient(h, dy, dx)
    sel = flow & (h > 0.2 * apex) & (h < 0.8 * apex)
    if not sel.any():
        return apex, None
    return apex, math.degrees(math.atan(float(np.hypot(gx, gy)[sel].mean())))


def compare(a, b):
    """Max over flow cells of |h_b - h_a| / (tan(a_cr) min(dx, dy)) at every snapshot time
    common to a and b (relative tolerance 1e-9): worst, when, last common, end states."""
    unit = math.tan(math.radians(a["repose"])) * min(a["dx"], a["dy"])
    flow = a["cell_type"] == 0
    pairs = [(i, j) for i, ta in enumerate(a["time"]) for j, tb in enumerate(b["time"])
             if abs(ta - tb) <= 1e-9 * max(abs(ta), abs(tb))]
    pairs.append((len(a["time"]) - 1, len(b["time"]) - 1))
    diffs = []
    with h5py.File(a["path"], "r", locking=False) as fa, \
            h5py.File(b["path"], "r", locking=False) as fb:
        for i, j in pairs:
            d = np.abs(fb["height"][j] - fa["height"][i])[flow]
            diffs.append(float(d.max()) / unit if d.size else 0.0)
    common, end = diffs[:-1], diffs[-1]
    r = dict(common_snapshots=len(common), end_state=end,
             end_times=[a["t_end"], b["t_end"]], apex_rel_diff=(b["apex"] - a["apex"]) / a["apex"],
             flank_diff_deg=(b["flank_deg"] - a["flank_deg"]
                             if a["flank_deg"] is not None and b["flank_deg"] is not None else None))
    if common:
        k = int(np.argmax(common))
        r.update(worst=common[k], worst_t=float(a["time"][pairs[k][0]]),
                 last=common[-1], last_t=float(a["time"][pairs[len(common) - 1][0]]))
    return r


def fmt(x, spec=".4g", none="-"):
    """x formatted, or `none` for None."""
    return none if x is None else format(x, spec)


def print_table(results, ref_name):
    """One line per workload x size x integrator."""
    cols = (f"{'workload':8} {'cells':>9} {'integrator':14} {'wall s':>9} {'steps':>10} "
            f"{'evals':>10} {'t_end':>9} {'vol err':>8} {'max diff':>9} {'at t':>7} "
            f"{'last':>9} {'ratio':>7}")
    print(f"\nwall: median over rounds; diff: max |h - h_{ref_name}| over flow cells in "
          f"tan(a) min(dx,dy); ratio: {ref_name}/integrator of median walls")
    print(cols + "\n" + "-" * len(cols))
    for res in results:
        cells = f"{res['nx']}x{res['ny']}"
        for name, v in res["variants"].items():
            c = res["comparison"].get(name, {})
            if v.get("not_run"):
                est = v.get("estimated_wall")
                how = f" = wall({v['from']}) x ({res['nx']}/{v['from'].split('x')[0]})^4" if est else ""
                print(f"{res['workload']:8} {cells:>9} {name:14} {'not run':>9}  "
                      f"estimated wall {fmt(est, '.0f', '?')} s{how} (estimated, not measured)")
                continue
            print(f"{res['workload']:8} {cells:>9} {name:14} {v['wall_median']:9.2f} "
                  f"{v['steps']:10.0f} {fmt(v['evaluations'], '.0f'):>10} {v['t_end']:9.6g} "
                  f"{fmt(v['volume_error'], '.1e'):>8} {fmt(c.get('worst'), '.3g'):>9} "
                  f"{fmt(c.get('worst_t'), '.5g'):>7} {fmt(c.get('last'), '.3g'):>9} "
                  f"{fmt(c.get('ratio'), '.3g'):>7}"
                  + (" (est)" if c.get("ratio_estimated") else ""))
        if res["workload"] == "cone":
            for name, v in res["variants"].items():
                if not v.get("not_run"):
                    print(f"  cone {name}: end t = {v['t_end']:.6g} s, apex {v['apex']:.6g} m, "
                          f"flank {fmt(v['flank_deg'], '.4f')} deg"
                          + ("  (stopped at max_time: not steady)" if res["max_time"]
                             and v["t_end"] >= res["max_time"] * (1 - 1e-12) else ""))
            for name, c in res["comparison"].items():
                print(f"  cone {name} - {ref_name}: end states differ by "
                      f"{c['end_state']:.3g} tan(a) dx, apex {c['apex_rel_diff']:+.3e} relative, "
                      f"flank {fmt(c['flank_diff_deg'], '+.2e')} deg")


def main(argv):
    """Plan, print the commands, run them, compare, print the table and the JSON."""
    args = parse_args(argv)
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"time_to_solution: no sandslide binary at {args.bin} (make, or give --bin)")
    outdir = args.keep or tempfile.mkdtemp(prefix="time_to_solution.")
    os.makedirs(outdir, exist_ok=True)
    try:
        return benchmark(args, argv, outdir)
    finally:
        if not args.keep:
            shutil.rmtree(outdir)


def benchmark(args, argv, outdir):
    """Everything but the output folder's life: see main."""
    vs, jobs = variants(args), plan(args)
    skip = lambda job, v: (v[0] == "euler" and job["workload"] == "door"
                           and 0 < args.skip_euler_above < job["nx"])
    runs = []  # (job index, variant, round, output, command), in the order they run
    for k, job in enumerate(jobs):
        todo = [v for v in vs if not skip(job, v)]
        for r in range(args.rounds):
            for v in (todo if r % 2 == 0 else todo[::-1]):
                out = os.path.join(outdir, f"{job['workload']}-{job['nx']}x{job['ny']}-{v[0]}-r{r}.h5")
                runs.append((k, v, r, out, command(args, job, v, out)))
    load = os.getloadavg()[0]
    if load > 0.5:
        print(f"# warning: load average {load:.2f} before the first run: the wall times will "
              f"be noisy" + (", with --threads > 1 maybe far too long" if args.threads > 1 else ""))
    print("# commands, in the order they run:")
    for run_ in runs:
        print(shlex.join(run_[4]))
    sys.stdout.flush()
    if args.dry:
        return 0
    # a one-step run of each integrator first, so a rejected --set fails at once
    for job in jobs[:1]:
        tiny = (["time.max_time=0.001"] if job["workload"] == "cone" else
                ["time.end=0.001", "time.output_every=0.001"])
        for v in vs:
            run(command(args, job, v, os.path.join(outdir, "preflight.h5"), tiny),
                "one-step check of the options: ")
    for name in ("preflight.h5", "preflight.xmf"):
        if os.path.exists(os.path.join(outdir, name)):
            os.remove(os.path.join(outdir, name))
    walls, outputs = {}, {}
    for k, v, r, out, cmd in runs:
        walls.setdefault((k, v[0]), []).append(run(cmd))
        print(f"# {jobs[k]['workload']} {jobs[k]['nx']}x{jobs[k]['ny']} {v[0]} round {r}: "
              f"{walls[(k, v[0])][-1]:.2f} s", file=sys.stderr)
        if r == 0:
            outputs[(k, v[0])] = read_output(out)
        elif not args.keep:
            os.remove(out)
    results = collect(vs, jobs, runs, walls, outputs)
    print_table(results, vs[0][0])
    if args.json:
        with open(args.json, "w") as f:
            json.dump(dict(argv=argv, bin=args.bin, threads=args.threads, rounds=args.rounds,
                           load_average_before=load, load_average_after=os.getloadavg()[0],
                           outputs=outdir if args.keep else None, results=results), f, indent=1)
    return 0


def collect(vs, jobs, runs, walls, outputs):
    """Per job: each integrator's numbers (or not_run and an estimated wall for euler),
    and the comparison of each with the reference vs[0]."""
    ref = vs[0][0]
    results, euler_door = [], None  # euler_door: (label, nx, median wall) of the largest run
    for k, job in enumerate(jobs):
        res = dict(workload=job["workload"], nx=job["nx"], ny=job["ny"],
                   max_time=job.get("max_time"), variants={}, comparison={}, commands=[
                       shlex.join(x[4]) for x in runs if x[0] == k])
        for v in vs:
            if (k, v[0]) not in outputs:
                res["variants"][v[0]] = dict(not_run=True)
                continue
            o = outputs[(k, v[0])]
            res["variants"][v[0]] = dict(
                walls=walls[(k, v[0])], wall_median=statistics.median(walls[(k, v[0])]),
                **{n: o[n] for n in ("steps", "evaluations", "t_end", "volume_error") +
                   (("apex", "flank_deg") if job["workload"] == "cone" else ())})
            if v[1] == "euler" and o["evaluations"] is None:
                res["variants"][v[0]]["evaluations"] = o["steps"]
        er = res["variants"].get(ref, {})
        if job["workload"] == "door" and "wall_median" in er:
            euler_door = (f"{job['nx']}x{job['ny']}", job["nx"], er["wall_median"])
        elif er.get("not_run") and euler_door:
            er["estimated_wall"] = euler_door[2] * (job["nx"] / euler_door[1]) ** 4
            er["from"] = euler_door[0]
        for v in vs[1:]:
            b = res["variants"][v[0]]
            if b.get("not_run"):
                continue
            if "wall_median" in er:
                c = compare(outputs[(k, ref)], outputs[(k, v[0])])
                c["ratio"] = er["wall_median"] / b["wall_median"]
            elif "estimated_wall" in er:
                c = dict(ratio=er["estimated_wall"] / b["wall_median"], ratio_estimated=True)
            else:
                continue
            res["comparison"][v[0]] = c
        results.append(res)
    return results


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
