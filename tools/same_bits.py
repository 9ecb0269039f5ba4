#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""same_bits.py OLD NEW - do two sandslide builds give the same bits?

Runs the same workloads with two builds of sandslide and compares what
they write: every snapshot of every dataset of an .h5 output but the wall
clock (tools/compare_outputs.py), raster outputs byte for byte, and the
JSON reports of relax and fit key by key but their timings, the fields
NEW adds and the values a later issue changed on purpose
(CHANGED_ON_PURPOSE).  What a
refactor promises (issue 34) and what a change that keeps a path's bits
must keep:

  cases     every shipped case (cases/*.ini), shortened, on the default
            kernel and the reference kernel, Euler and RKL2, 1 and 2
            threads, and on each kernel path this processor runs
            (SANDSLIDE_CPU=generic|avx2|avx512)
  relax     cases/dem/terrain.asc with forward Euler, the path both
            builds have (issue 35): raster and report, a series (.h5),
            poured sand, open nodata and sides, a bedrock; --dems DIR adds
            every DIR/*.asc (tools/real_dems.py)
  fit       a cone twin (nu free), the report
  python    the README's relax example and python/examples/
            wind_deposition.py (the BMI), each build's module and library
  mpi       with --mpi OLD_MPI NEW_MPI: the door and the terrain under
            mpirun -np 1, 2 and 3 with each MPI build, against the serial
            NEW (the distributed build must give the serial bits)

OLD and NEW are build folders (holding sandslide, libsandslide.so.0) of
checkouts whose python/ folder sits two levels up (BUILD/../python).
Prints one line per workload; exits 1 if any differs.

    tools/same_bits.py ../ref/build build            # everything
    tools/same_bits.py ../ref/build build --quick    # a subset, a minute
    tools/same_bits.py ../ref/build build --only relax,fit
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(HERE)
CASES = os.path.join(TOP, "cases")
# keys of the reports that are wall clock or memory, not results
TIMING = {"wall_seconds", "read_seconds", "write_seconds", "seconds", "seconds_per_run",
          "memory_peak_bytes", "measure_seconds", "sweep_seconds", "output_seconds",
          "comm_seconds", "output"}
# What a later change altered on purpose, by output: the paths of report
# values that may differ from OLD's.  A key only NEW's report has is an
# added field, not a difference (reports may gain fields); one only OLD's
# has still differs.
#   issue 36 item 5: fit's interval counts the forward model's own error
#   (doc/fit.md#how-sure): 2 more forward runs per closure, wider intervals
#   issue 35: relax's default became forward Euler with the approach to
#   rest (doc/model.md#the-approach-to-rest), which steady runs take too,
#   and RKL2 no longer polishes near rest: the paths kept are compared, by
#   running relax with --integrator euler in both builds and giving a NEW
#   that has the approach `rest off` (Runner.sandslide)
#   issue 39: RKL2's super-steps that pour have their own tolerance
#   (rkl2_pouring_tol, doc/model.md#accuracy-rule): NEW gets the one the
#   rest of the run has, which OLD used for both (Runner.rest_off)
CHANGED_ON_PURPOSE = {
    "fit.json": re.compile(r"\.forward_runs|\.closures\[\d+\]\.(evaluations|"
                           r"uncertainty\.\w+\.(std|low|high))"),
}
H5_NAMES = ["height", "time", "cell_type", "x", "y", "volume", "inflow", "outflow",
            "external", "max_height", "max_slope_deg", "steps", "stencil_evaluations",
            "active_fraction", "bedrock"]
# each case shortened: (case, overrides) that run in about a second
SHORT = {
    "columns.ini": ["time.end=60"],
    "cone.ini": ["time.max_time=4"],
    "dem.ini": ["time.max_time=2000"],
    "door.ini": ["time.end=60"],
    "reference.ini": [],
    "table.ini": ["time.max_time=20"],
    "wind_wall.ini": ["time.end=20"],
}
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_mpi_yield_when_idle": "1",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "OMPI_MCA_pml": "ob1",
           "OMPI_MCA_btl": "self,vader", "OMPI_MCA_btl_base_warn_component_unused": "0",
           "OMP_NUM_THREADS": "1"}


def h5_differences(a_path, b_path):
    """Names of the datasets that differ (shape or bytes) between two outputs."""
    with h5py.File(a_path, "r", locking=False) as a, h5py.File(b_path, "r", locking=False) as b:
        bad = []
        for n in H5_NAMES:
            if n not in a and n not in b:
                continue
            if n not in a or n not in b or a[n].shape != b[n].shape or \
               not np.array_equal(a[n][...].view(np.uint8), b[n][...].view(np.uint8)):
                bad.append("/" + n)
        return bad


def json_differences(a, b, where=""):
    """Paths of the values that differ between two reports, timings aside."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            if k in TIMING:
                continue
            if k not in a:
                out.append(f"{where}.{k} (only in the new)")
            elif k not in b:
                out.append(f"{where}.{k} (only in the old)")
            else:
                out += json_differences(a[k], b[k], f"{where}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{where} (length {len(a)} vs {len(b)})"]
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in json_differences(x, y, f"{where}[{k}]")]
    same = a == b or (isinstance(a, float) and isinstance(b, float) and a != a and b != b)
    return [] if same else [f"{where}: {a!r} vs {b!r}"]


def file_differences(a_path, b_path):
    if a_path.endswith(".h5"):
        return h5_differences(a_path, b_path)
    if a_path.endswith(".json"):
        # the paths in a report are each run's own folder
        a_text = open(a_path).read().replace(os.path.dirname(a_path), "DIR")
        b_text = open(b_path).read().replace(os.path.dirname(b_path), "DIR")
        return json_differences(json.loads(a_text), json.loads(b_text))
    return [] if open(a_path, "rb").read() == open(b_path, "rb").read() else ["bytes"]


class Runner:
    def __init__(self, builds, work, verbose):
        self.builds = builds        # {"old": folder, "new": folder, ...}
        self.work = work
        self.verbose = verbose
        self.results = []
        self.has_rest = {}          # build -> its relax takes --rest

    def rest_off(self, which, args):
        """args, with the approach to rest off where the build has one, and
        the pouring tolerance that of the rest where it has its own."""
        build = self.builds[which]
        if build not in self.has_rest:
            h = subprocess.run([os.path.join(build, "sandslide"), "help", "relax"],
                               capture_output=True, text=True).stdout
            self.has_rest[build] = ("--rest " in h, "--rkl2-pouring-tol" in h)
        rest, pouring = self.has_rest[build]
        if "--restart" in args:
            return list(args)
        out = list(args)
        tol = next((a.split("=", 1)[1] for a in args if a.startswith("time.rkl2_tol=")), None)
        if args[0] == "relax":
            if "--rkl2-tol" in args:
                tol = args[args.index("--rkl2-tol") + 1]
            out += ["--rest", "off"] if rest else []
            out += ["--rkl2-pouring-tol", tol or "0.1"] if pouring else []
        elif args[0] == "run":
            out += ["--set", "time.rest=off"] if rest else []
            out += ["--set", f"time.rkl2_pouring_tol={tol or 0.1}"] if pouring else []
        return out

    def has_option(self, which, option):
        """Whether the build's `sandslide help relax` names option."""
        build = self.builds[which]
        h = subprocess.run([os.path.join(build, "sandslide"), "help", "relax"],
                           capture_output=True, text=True).stdout
        return option in h

    def known_keys(self, which, args):
        """args, with a case file that sets keys the build predates (they
        are at their defaults there: reference.ini lists every key) copied
        without them into the work folder; its files are found beside the
        original only if it names none, as reference.ini does not."""
        rest, pouring = self.has_rest.get(self.builds[which], (True, True))
        unknown = ([] if rest else ["rest"]) + ([] if pouring else ["rkl2_pouring_tol"])
        out = list(args)
        for k, a in enumerate(args):
            if not (a.endswith(".ini") and os.path.isfile(a) and unknown):
                continue
            lines = open(a).read().splitlines()
            kept = [ln for ln in lines if ln.split("=")[0].strip() not in unknown]
            if len(kept) < len(lines):
                copy = os.path.join(self.work, f"{which}-{os.path.basename(a)}")
                with open(copy, "w") as f:
                    f.write("\n".join(kept) + "\n")
                out[k] = copy
        return out

    def sandslide(self, which, args, env=None, mpi=0):
        build = self.builds[which]
        args = self.rest_off(which, args)
        cmd = [os.path.join(build, "sandslide")] + self.known_keys(which, args)
        # threads that spin in a busy machine's barriers lose their core for
        # ages (doc/running.md); waiting passively changes no bit
        e = dict(os.environ, OMP_WAIT_POLICY="passive", **(env or {}))
        if mpi:
            cmd = ["mpirun.openmpi", "-np", str(mpi), "--bind-to", "none"] + cmd
            e.update(MPI_ENV)
        r = subprocess.run(cmd, env=e, capture_output=True, text=True, cwd=TOP)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
        return r.stdout

    def compare(self, name, produce, outputs):
        """produce(which, folder) writes the outputs (names in that folder)
        with build `which`; each output of "old" is compared with "new"'s."""
        folders = {}
        try:
            for which in ("old", "new"):
                folders[which] = os.path.join(self.work, which, name.replace(" ", "_")
                                              .replace("/", "_"))
                os.makedirs(folders[which], exist_ok=True)
                produce(which, folders[which])
            bad = []
            for out in outputs:
                d = file_differences(os.path.join(folders["old"], out),
                                     os.path.join(folders["new"], out))
                meant = CHANGED_ON_PURPOSE.get(out)
                d = [x for x in d if not x.endswith("(only in the new)") and
                     not (meant and meant.fullmatch(x.split(":")[0]))]
                bad += [f"{out}: {x}" for x in d]
        except (RuntimeError, OSError) as e:
            bad = [f"failed: {e}"]
        self.results.append((name, bad))
        print(f"{'same bits' if not bad else 'DIFFERS  '}  {name}", flush=True)
        for line in bad[:8] if self.verbose or bad else []:
            print(f"           {line}")


def cpu_paths():
    flags = set()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                break
    except OSError:
        pass
    paths = ["generic"]
    if "avx2" in flags:
        paths.append("avx2")
    if {"avx512f", "avx512vl", "avx512bw", "avx512dq", "avx512cd"} <= flags:
        paths.append("avx512")
    return paths


def run_cases(r, quick):
    names = sorted(SHORT) if not quick else ["door.ini", "cone.ini", "dem.ini"]
    variants = [("", [], {})]
    if not quick:
        variants += [
            ("1 thread", ["--threads", "1"], {}),
            ("reference kernel", ["--reference-kernel"], {}),
            ("euler", ["--set", "time.integrator=euler"], {}),
            ("rkl2 tile 16x8", ["--set", "time.integrator=rkl2", "--tile", "16x8"], {}),
        ]
        variants += [(f"SANDSLIDE_CPU={p}", [], {"SANDSLIDE_CPU": p}) for p in cpu_paths()]
    for case in names:
        for label, extra, env in variants:
            args = ["run", os.path.join(CASES, case), "-q", "--threads", "2"]
            for s in SHORT[case]:
                args += ["--set", s]

            def produce(which, d, args=args, extra=extra, env=env):
                r.sandslide(which, args + extra + ["-o", os.path.join(d, "out.h5")], env)
            r.compare(f"run {case} {label}".strip(), produce, ["out.h5"])


def write_bedrock(dem, path, depth):
    """The DEM lowered by depth m (no data kept) as an ESRI ASCII grid."""
    lines = open(dem).read().splitlines()
    head = [ln for ln in lines[:6] if ln.split()[0].lower() in
            ("ncols", "nrows", "xllcorner", "yllcorner", "xllcenter", "yllcenter",
             "cellsize", "nodata_value")]
    nodata = next((float(ln.split()[1]) for ln in head if ln.lower().startswith("nodata")),
                  None)
    body = np.loadtxt(lines[len(head):], ndmin=2)
    low = np.where(body == nodata, body, body - depth) if nodata is not None else body - depth
    with open(path, "w") as f:
        f.write("\n".join(head) + "\n")
        np.savetxt(f, low, fmt="%.17g")


def run_relax(r, quick, dems):
    terrain = os.path.join(CASES, "dem", "terrain.asc")
    variants = [("defaults", [], "out.asc")]
    if not quick:
        variants += [
            ("euler", ["--integrator", "euler"], "out.asc"),
            ("series", ["--max-time", "3000"], "out.h5"),
            ("add-sand", ["--add-sand", "disk=40,40,8", "--sand-rate", "0.01",
                          "--sand-duration", "100"], "out.asc"),
            ("open nodata and sides", ["--nodata", "open", "--sides", "open",
                                       "--angle", "30"], "out.asc"),
            ("bedrock", ["--bedrock", "BEDROCK", "--max-time", "3000"], "out.asc"),
            ("2 threads tile 32x16", ["--threads", "2", "--tile", "32x16"], "out.asc"),
        ]
    inputs = [("terrain.asc", terrain)]
    for name in sorted(os.listdir(dems)) if dems else []:
        if name.endswith(".asc"):
            inputs.append((name, os.path.join(dems, name)))
    for dem_name, dem in inputs:
        for label, extra, out in variants if dem == terrain else variants[:1]:
            if label == "series" and not r.has_option("old", "--rest "):
                # issue 35: relax's snapshots became samples of a run that
                # never lands on them, so a series (and a run stopped by
                # --max-time) takes other steps than a build before it
                print(f"skipped    relax {dem_name} {label}: changed on purpose by issue 35 "
                      "(OLD predates it)", flush=True)
                continue

            def produce(which, d, dem=dem, extra=extra, out=out):
                # the path both builds have (issue 35: CHANGED_ON_PURPOSE)
                ex = list(extra) if "--integrator" in extra else ["--integrator", "euler"] + extra
                if "BEDROCK" in ex:
                    rock = os.path.join(d, "rock.asc")
                    write_bedrock(dem, rock, 2.0)
                    ex[ex.index("BEDROCK")] = rock
                r.sandslide(which, ["relax", dem, "-o", os.path.join(d, out), "-q",
                                    "--report", os.path.join(d, "report.json")] + ex)
            r.compare(f"relax {dem_name} {label}", produce, [out, "report.json"])


def cone_twin_case(path, end=6):
    text = open(os.path.join(CASES, "cone.ini")).read()
    text = text.replace("nx = 81", "nx = 41").replace("ny = 81", "ny = 41")
    text = text.replace("dx = 0.03 ", "dx = 0.06 ")
    text = text.replace("origin = -1.215 -1.215", "origin = -1.23 -1.23")
    text = "\n".join(ln for ln in text.splitlines()
                     if not ln.startswith(("end =", "steady_tol", "max_time", "output_every")))
    text = text.replace("[time]\n", f"[time]\nend = {end}\noutput_every = 1\n")
    open(path, "w").write(text + "\n")


def run_fit(r, quick):
    def produce(which, d):
        case = os.path.join(d, "cone.ini")
        cone_twin_case(case)
        obs = os.path.join(d, "obs.h5")
        r.sandslide(which, ["run", case, "-o", obs, "-q", "--set", "model.nu=0.13",
                            "--set", "model.closure=casson"])
        r.sandslide(which, ["fit", case, obs, "--param", "nu=0.02:1:log", "-q",
                            "--closures", "casson" if quick else "casson,bingham",
                            "-o", os.path.join(d, "fit.json"), "--threads", "2"])
    r.compare("fit cone twin (nu)", produce, ["fit.json"])


README_RELAX = """
import json, sys
import numpy as np
import sandslide
y, x = np.mgrid[0:60, 0:60] + 0.5
pile = np.maximum(20 - np.hypot(x - 30, y - 30), 0)
relaxed, report = sandslide.relax(pile, dx=1.0, angle=33, **json.loads(sys.argv[3]))
np.save(sys.argv[1], relaxed)
json.dump(report, open(sys.argv[2], "w"))
"""


def run_python(r, quick):
    def env_of(which):
        build = os.path.abspath(r.builds[which])
        return dict(os.environ, OMP_WAIT_POLICY="passive",
                    PYTHONPATH=os.path.join(os.path.dirname(build), "python"),
                    SANDSLIDE_LIBRARY=os.path.join(build, "libsandslide.so.0"))

    def relax(which, d):
        # the path both builds have (issue 35: CHANGED_ON_PURPOSE)
        options = {"integrator": "euler"}
        if r.rest_off(which, ["relax"]) != ["relax"]:
            options["rest"] = "off"
        subprocess.run([sys.executable, "-c", README_RELAX, os.path.join(d, "relaxed.npy"),
                        os.path.join(d, "report.json"), json.dumps(options)],
                       env=env_of(which), check=True, capture_output=True)
    r.compare("python relax (README)", relax, ["relaxed.npy", "report.json"])
    if quick:
        return

    def wind(which, d):
        build = os.path.abspath(r.builds[which])
        example = os.path.join(os.path.dirname(build), "python", "examples",
                               "wind_deposition.py")
        out = subprocess.run([sys.executable, example], env=env_of(which), check=True,
                             capture_output=True, text=True).stdout
        open(os.path.join(d, "stdout.txt"), "w").write(out)
    r.compare("python BMI wind_deposition.py", wind, ["stdout.txt"])


def run_mpi(r, quick):
    terrain = os.path.join(CASES, "dem", "terrain.asc")
    work = [("door", ["run", os.path.join(CASES, "door.ini"), "-q", "--set", "time.end=40",
                      "--tile", "60x8"], "out.h5"),
            ("terrain", ["relax", terrain, "-q", "--tile", "96x16", "--max-time", "3000",
                         "--integrator", "euler"],
             "out.h5")]
    for name, args, out in work:
        def serial(d, args=args, out=out):
            r.sandslide("new", args + ["-o", os.path.join(d, out)])
        for np_ in ([2] if quick else [1, 2, 3]):
            for which in ("old_mpi", "new_mpi"):
                def produce(w, d, args=args, out=out, which=which, np_=np_):
                    if w == "old":   # the reference: the serial new build
                        serial(d)
                    else:
                        r.sandslide(which, args + ["-o", os.path.join(d, out)], mpi=np_)
                r.compare(f"mpi {name} np {np_} {which.split('_')[0]} build vs serial",
                          produce, [out])


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("old")
    p.add_argument("new")
    p.add_argument("--mpi", nargs=2, metavar=("OLD_MPI", "NEW_MPI"))
    p.add_argument("--dems", help="also relax every .asc in this folder")
    p.add_argument("--only", help="comma-separated: cases, relax, fit, python, mpi")
    p.add_argument("--quick", action="store_true", help="a subset of each")
    p.add_argument("--keep", help="keep the outputs in this folder")
    p.add_argument("-v", "--verbose", action="store_true")
    a = p.parse_args()
    builds = {"old": a.old, "new": a.new}
    if a.mpi:
        builds.update(old_mpi=a.mpi[0], new_mpi=a.mpi[1])
    groups = a.only.split(",") if a.only else ["cases", "relax", "fit", "python"] + \
        (["mpi"] if a.mpi else [])
    work = a.keep or tempfile.mkdtemp(prefix="same_bits.")
    r = Runner(builds, work, a.verbose)
    try:
        for g in groups:
            {"cases": lambda: run_cases(r, a.quick),
             "relax": lambda: run_relax(r, a.quick, a.dems),
             "fit": lambda: run_fit(r, a.quick),
             "python": lambda: run_python(r, a.quick),
             "mpi": lambda: run_mpi(r, a.quick)}[g]()
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    bad = [n for n, b in r.results if b]
    print(f"{len(r.results) - len(bad)} workloads the same bits, {len(bad)} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
