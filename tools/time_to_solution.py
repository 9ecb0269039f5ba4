#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
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

  relax  `sandslide relax DEM -o OUT.h5 --report R.json` on DEMs (only with
        --workloads relax; not in the default door,cone).  --dems DIR_OR_FILE,...
        (a folder gives its *.asc, *.tif and *.png) or by default the real DEMs
        of tools/real_dems.py (Debian packages: `make deps-bench`), written into
        the output folder, and cases/dem/terrain.asc; --fractal 2048,4096 adds
        terrains of cases/fractal_dem.py of those sizes.  The variants are
        --integrators (each as `--integrator NAME`; `default` passes none, so
        the binary's own default) and --variant 'NAME:OPTIONS' (any relax
        options); --relax-opt OPTIONS goes to every run.  --bin-b B runs every
        variant with a second binary too (interleaved A B B A), e.g. an older
        commit's build against the new one.  Per DEM and variant: the median
        wall (measured here; the report's own wall beside it in the JSON),
        steps, stencil evaluations, whether it ended steady, the steepest face
        left (the report's max_slope_after_deg, and tan of it less tan(angle)),
        the volume change relative to the volume, the largest difference of
        the end state to the first variant's over cells with data, in metres
        and in tan(angle) min(dx, dy), and the first variant's wall / this
        one's.  --timeout S stops a run after S s of wall (SIGTERM: relax
        writes what it has) and drops that variant's later rounds.

  tools/time_to_solution.py --workloads relax --threads 1 --timeout 120
  tools/time_to_solution.py --workloads relax --dems out/dems --integrators default \
      --bin OLD/build/sandslide --bin-b build/sandslide --rounds 2
  tools/time_to_solution.py --workloads relax --dems cases/dem/terrain.asc \
      --integrators euler --variant 'rkl2-tol3:--integrator rkl2 --rkl2-tol 3'
  tools/time_to_solution.py --workloads relax --dems none --fractal 2048,4096
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
    p.add_argument("--bin-b", help="relax: a second binary, every variant run with both")
    p.add_argument("--workloads", default="door,cone",
                   help="door,cone,relax (default door,cone)")
    p.add_argument("--integrators", help="default euler,rkl2 (relax: none if --variant "
                   "is given; `default`: no --integrator)")
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
    p.add_argument("--dems", help="relax: DEM files or folders, comma-separated (default: "
                   "tools/real_dems.py's set and cases/dem/terrain.asc; `none`: no DEM)")
    p.add_argument("--fractal", type=ints, default=[],
                   help="relax: add cases/fractal_dem.py terrains of these sizes")
    p.add_argument("--variant", action="append", default=[], metavar="NAME:OPTIONS",
                   help="relax: a variant with these relax options")
    p.add_argument("--relax-opt", action="append", default=[], metavar="OPTIONS",
                   help="relax: options passed to every run")
    p.add_argument("--timeout", type=float, help="relax: stop a run after this many s")
    p.add_argument("--compare-cfl", type=float, help=argparse.SUPPRESS)
    p.add_argument("--json", metavar="FILE", help="write every number to FILE")
    p.add_argument("--keep", metavar="DIR", help="keep the outputs in DIR")
    p.add_argument("--dry", action="store_true", help="print the commands, run nothing")
    args = p.parse_args(argv)
    wl = args.workloads.split(",")
    if not set(wl) <= {"door", "cone", "relax"}:
        p.error(f"--workloads {args.workloads}: expected a list of door, cone, relax")
    if "relax" not in wl and (args.bin_b or args.dems or args.fractal or args.variant
                              or args.relax_opt or args.timeout):
        p.error("--bin-b, --dems, --fractal, --variant, --relax-opt and --timeout are for "
                "--workloads relax")
    if args.integrators is None:
        args.integrators = "" if args.variant and wl == ["relax"] else "euler,rkl2"
    for v in args.variant:
        if ":" not in v or not v.split(":", 1)[0]:
            p.error(f"--variant {v!r}: expected NAME:OPTIONS")
    return args


def variants(args):
    """[(name, integrator, sets)]: the reference (euler) first, then the others."""
    if args.compare_cfl is not None:
        return [("euler", "euler", ["time.integrator=euler"]),
                (f"euler-cfl{args.compare_cfl:g}", "euler",
                 ["time.integrator=euler", f"time.cfl={args.compare_cfl!r}"])]
    out = []
    for name in [n for n in args.integrators.split(",") if n]:
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
    for b in [args.bin] + ([args.bin_b] if args.bin_b else []):
        if not os.access(b, os.X_OK):
            sys.exit(f"time_to_solution: no sandslide binary at {b} (make, or give --bin)")
    outdir = args.keep or tempfile.mkdtemp(prefix="time_to_solution.")
    os.makedirs(outdir, exist_ok=True)
    try:
        return benchmark(args, argv, outdir)
    finally:
        if not args.keep:
            shutil.rmtree(outdir)


def warn_load(args):
    """The load average before the first run, with a warning when it is high."""
    load = os.getloadavg()[0]
    if load > 0.5:
        print(f"# warning: load average {load:.2f} before the first run: the wall times will "
              f"be noisy" + (", with --threads > 1 maybe far too long" if args.threads > 1 else ""))
    return load


def benchmark(args, argv, outdir):
    """Everything but the output folder's life: see main."""
    wl = args.workloads.split(",")
    load = warn_load(args)
    results = benchmark_run(args, outdir) if {"door", "cone"} & set(wl) else []
    relax = benchmark_relax(args, outdir) if "relax" in wl else []
    if args.json and not args.dry:
        with open(args.json, "w") as f:
            json.dump(dict(argv=argv, bin=args.bin, bin_b=args.bin_b, threads=args.threads,
                           rounds=args.rounds, load_average_before=load,
                           load_average_after=os.getloadavg()[0],
                           outputs=outdir if args.keep else None, results=results,
                           relax=relax), f, indent=1)
    return 0


def print_commands(commands):
    """The command lines, in the order they run, before any runs."""
    print("# commands, in the order they run:")
    for cmd in commands:
        print(shlex.join(cmd))
    sys.stdout.flush()


def benchmark_run(args, outdir):
    """door and cone: `sandslide run` per job and integrator; the results (none if --dry)."""
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
    print_commands(run_[4] for run_ in runs)
    if args.dry:
        return []
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
    return results


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


# ---- relax: `sandslide relax` on DEMs ---------------------------------------

def relax_variants(args):
    """[(name, relax options)]: --integrators, then --variant NAME:OPTIONS; the first is
    the reference."""
    out = [(n, [] if n == "default" else ["--integrator", n])
           for n in args.integrators.split(",") if n]
    out += [(v.split(":", 1)[0], shlex.split(v.split(":", 1)[1])) for v in args.variant]
    names = [n for n, _ in out]
    if not out or len(set(names)) != len(names):
        sys.exit(f"time_to_solution: relax variants {names}: need at least one, each "
                 f"name once (--integrators, --variant)")
    return out


def relax_dems(args, outdir):
    """The DEMs [(name, path)] and the commands that make them [(what, command)]: --dems,
    or tools/real_dems.py's default set written into outdir/dems and cases/dem/terrain.asc;
    then --fractal's terrains."""
    dems, makers = [], []
    if args.dems is None:
        folder = os.path.join(outdir, "dems")
        makers.append(("real DEMs (Debian packages, make deps-bench)",
                       [sys.executable, os.path.join(ROOT, "tools", "real_dems.py"), folder]))
        sys.path.insert(0, os.path.join(ROOT, "tools"))
        import real_dems
        dems += [os.path.join(folder, d["name"] + ".asc") for d in real_dems.CATALOGUE
                 if not d.get("gentle")]
        dems.append(os.path.join(ROOT, "cases", "dem", "terrain.asc"))
    else:
        for item in [x for x in args.dems.split(",") if x and x != "none"]:
            if os.path.isdir(item):
                found = sorted(os.path.join(item, f) for f in os.listdir(item)
                               if f.lower().endswith((".asc", ".tif", ".tiff", ".png")))
                if not found:
                    sys.exit(f"time_to_solution: --dems {item}: no .asc, .tif or .png in it")
                dems += found
            elif os.path.isfile(item):
                dems.append(item)
            else:
                sys.exit(f"time_to_solution: --dems {item}: no such file or folder")
    for n in args.fractal:
        path = os.path.join(outdir, f"fractal-{n}.asc")
        makers.append((f"fractal terrain {n}^2",
                       [sys.executable, os.path.join(ROOT, "cases", "fractal_dem.py"), str(n), path]))
        dems.append(path)
    named, seen = [], {}
    for path in dems:
        name = os.path.splitext(os.path.basename(path))[0]
        seen[name] = seen.get(name, 0) + 1
        named.append((name if seen[name] == 1 else f"{name}-{seen[name]}", path))
    if not named:
        sys.exit("time_to_solution: no DEM to relax (--dems, --fractal)")
    return named, makers


def relax_command(args, binary, dem, opts, out, report):
    """The sandslide relax command line of one run."""
    cmd = [binary, "relax", dem, "-o", out, "--report", report, "--force", "--quiet",
           "--threads", str(args.threads)]
    for o in args.relax_opt:
        cmd += shlex.split(o)
    return cmd + opts


def run_stoppable(cmd, timeout):
    """Run cmd; (wall seconds, stopped).  Past timeout s it gets SIGTERM (relax then
    writes the surface it has) and counts as stopped.  On failure print its stderr,
    exit 1."""
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        err = p.communicate(timeout=timeout)[1]
        stopped = False
    except subprocess.TimeoutExpired:
        p.terminate()
        err = p.communicate()[1]
        stopped = True
    wall = time.monotonic() - t0
    if p.returncode != 0 and not stopped:
        sys.stderr.write(f"time_to_solution: failed (exit {p.returncode}): {shlex.join(cmd)}\n"
                         f"{err}")
        sys.exit(1)
    return wall, stopped


def read_relax(out, report):
    """The report's numbers, and the output's path for the end state."""
    with open(report) as f:
        r = json.load(f)
    r["path"] = out
    return r


def compare_relax(a, b):
    """The largest |h_b - h_a| of the end states over cells with data of both: in metres and
    in tan(angle) min(dx, dy)."""
    with h5py.File(a["path"], "r", locking=False) as fa, \
            h5py.File(b["path"], "r", locking=False) as fb:
        ha, hb = fa["height"][-1], fb["height"][-1]
        cells = (fa["cell_type"][...] == 0) & (fb["cell_type"][...] == 0)
    if ha.shape != hb.shape:
        return dict(diff_m=None, diff_unit=None)
    d = np.abs(hb - ha)[cells & np.isfinite(ha) & np.isfinite(hb)]
    m = float(d.max()) if d.size else 0.0
    unit = math.tan(math.radians(a["repose_angle_deg"])) * min(a["dx"], a["dy"])
    return dict(diff_m=m, diff_unit=m / unit)


def benchmark_relax(args, outdir):
    """relax: make the DEMs, run every (DEM, variant, binary) --rounds times interleaved,
    compare, print the table; the results (none if --dry)."""
    vs = relax_variants(args)
    bins = [("A", args.bin)] + ([("B", args.bin_b)] if args.bin_b else [])
    label = lambda v, b: v[0] + (f" {b[0]}" if args.bin_b else "")
    dems, makers = relax_dems(args, outdir)
    runs = []  # (dem index, label, round, output, report, command), in the order they run
    for k, (name, path) in enumerate(dems):
        todo = [(v, b) for v in vs for b in bins]
        for r in range(args.rounds):
            for v, b in (todo if r % 2 == 0 else todo[::-1]):
                stem = os.path.join(outdir, f"relax-{name}-{label(v, b).replace(' ', '-')}-r{r}")
                runs.append((k, label(v, b), r, stem + ".h5", stem + ".json",
                             relax_command(args, b[1], path, v[1], stem + ".h5", stem + ".json")))
    if args.bin_b:
        print(f"# A = {args.bin}\n# B = {args.bin_b}")
    if makers:
        print("# the DEMs:")
    for what, cmd in makers:
        print(f"{shlex.join(cmd)}   # {what}")
    print_commands(run_[5] for run_ in runs)
    if args.dry:
        return []
    for what, cmd in makers:
        sys.stdout.flush()
        if subprocess.run(cmd).returncode != 0:
            sys.exit(f"time_to_solution: making the {what} failed: {shlex.join(cmd)}")
    # a short run of each variant and binary first, so a rejected option fails at once
    smallest = min((p for _, p in dems), key=os.path.getsize)
    for v in vs:
        for b in bins:
            run(relax_command(args, b[1], smallest, v[1], os.path.join(outdir, "preflight.asc"),
                              os.path.join(outdir, "preflight.json")) + ["--max-time", "0.001"],
                "short check of the options: ")
    walls, outputs, stopped = {}, {}, set()
    for k, lab, r, out, report, cmd in runs:
        if (k, lab) in stopped:
            continue
        wall, stop = run_stoppable(cmd, args.timeout)
        walls.setdefault((k, lab), []).append(wall)
        print(f"# relax {dems[k][0]} {lab} round {r}: {wall:.2f} s"
              + (f" (stopped at --timeout {args.timeout:g} s)" if stop else ""), file=sys.stderr)
        if stop:
            stopped.add((k, lab))
        if r == 0:
            outputs[(k, lab)] = read_relax(out, report)
            outputs[(k, lab)]["stopped"] = stop
        elif not args.keep:
            os.remove(out)
    labels = [label(v, b) for v in vs for b in bins]
    results = []
    for k, (name, path) in enumerate(dems):
        ref = outputs[(k, labels[0])]
        res = dict(dem=name, path=path, nx=ref["nx"], ny=ref["ny"], dx=ref["dx"], dy=ref["dy"],
                   repose_angle_deg=ref["repose_angle_deg"],
                   max_slope_before_deg=ref["max_slope_before_deg"], variants={},
                   commands=[shlex.join(x[5]) for x in runs if x[0] == k])
        for lab in labels:
            o = outputs[(k, lab)]
            vol = o["volume_before"]
            res["variants"][lab] = dict(
                walls=walls[(k, lab)], wall_median=statistics.median(walls[(k, lab)]),
                stopped=o["stopped"], report_wall=o["wall_seconds"], steps=o["steps"],
                evaluations=o.get("stencil_evaluations", o["steps"]), time=o["time"],
                end=o.get("end", "steady" if o.get("steady") else "not steady"),  # fc0c21b: no "end"
                steady=o.get("steady"),
                cells_moved=o["cells_moved"], volume_moved=o["volume_moved"],
                max_slope_after_deg=o["max_slope_after_deg"],
                face_excess=(math.tan(math.radians(o["max_slope_after_deg"])) -
                             math.tan(math.radians(o["repose_angle_deg"]))),
                volume_change=((o["volume_after"] - vol - (o["inflow"] - o["outflow"])) / vol
                               if vol else None),
                **compare_relax(ref, o),
                ratio=statistics.median(walls[(k, labels[0])]) / statistics.median(walls[(k, lab)]))
        results.append(res)
    print_relax_table(results, labels[0])
    return results


def print_relax_table(results, ref_name):
    """One line per DEM x variant."""
    cols = (f"{'DEM':20} {'cells':>9} {'cell m':>11} {'variant':14} {'wall s':>8} {'steps':>7} "
            f"{'evals':>7} {'end':>8} {'worst face':>12} {'tan - tan a':>11} {'vol change':>10} "
            f"{'diff m':>8} {'diff t*dx':>9} {'ratio':>6}")
    print(f"\nwall: median over rounds; worst face: the steepest sand face left (deg); "
          f"diff: max |h - h_{ref_name}| of the end states over cells with data, in m and in "
          f"t*dx = tan(a) min(dx,dy); ratio: {ref_name}/variant of median walls")
    print(cols + "\n" + "-" * len(cols))
    for res in results:
        cells = f"{res['nx']}x{res['ny']}"
        cell = (f"{res['dx']:.4g}" if res["dx"] == res["dy"]
                else f"{res['dx']:.4g}x{res['dy']:.4g}")
        for name, v in res["variants"].items():
            end = "stopped" if v["stopped"] else v["end"]
            print(f"{res['dem']:20} {cells:>9} {cell:>11} {name:14} {v['wall_median']:8.2f} "
                  f"{v['steps']:7.0f} {v['evaluations']:7.0f} {end:>8} "
                  f"{v['max_slope_after_deg']:12.7f} {v['face_excess']:11.1e} "
                  f"{fmt(v['volume_change'], '.1e'):>10} {fmt(v['diff_m'], '.2e'):>8} "
                  f"{fmt(v['diff_unit'], '.2e'):>9} {fmt(v['ratio'], '.3g'):>6}")



if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
