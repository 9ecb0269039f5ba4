#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The defaults on a quiet and on a busy machine (issue 36, item 1).

Runs `make demo`'s command (sandslide run cases/door.ini) and the Python
example of README.md#from-python (its code block, the relax call timed)
with the default threads and with one thread (--threads 1, threads=1),
each with and without competing busy-loop processes (`sh -c 'while :; do
:; done'`, two by default: one per core of a 2-core machine), all
interleaved round by round, and prints the median and range of each and
its ratio to one thread under the same load.  A benchmark, not a test:
nothing is asserted.

The environment's OMP_WAIT_POLICY, GOMP_SPINCOUNT and OMP_NUM_THREADS are
removed so that the defaults are what is measured (--keep-env keeps them).
--root points at another checkout (built with `make`) to measure its build,
e.g. a worktree of an older commit:

    git worktree add /tmp/old f9026b5 && make -C /tmp/old -j2
    tools/busy_bench.py --root /tmp/old

Usage: tools/busy_bench.py [--root DIR] [--rounds 3] [--busy 2] [--keep-env]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))

# Times the README's relax call in a process of its own: the example's code
# runs unchanged except that sandslide.relax is wrapped to time it and, for
# one thread, to pass threads=1.
PY_DRIVER = r"""
import sys, time
import sandslide
threads = int(sys.argv[1]) if sys.argv[1] != "default" else None
_relax = sandslide.relax
def timed(*args, **kwargs):
    if threads is not None:
        kwargs["threads"] = threads
    t0 = time.perf_counter()
    out = _relax(*args, **kwargs)
    print("SECONDS %.6f" % (time.perf_counter() - t0), file=sys.stderr)
    return out
sandslide.relax = timed
exec(compile(sys.stdin.read(), "README.md", "exec"))
"""


def readme_python(root):
    """The first ```python block under the heading of README.md#from-python."""
    with open(os.path.join(root, "README.md")) as f:
        text = f.read()
    m = re.search(r"^## From Python\n.*?```python\n(.*?)```", text, re.S | re.M)
    if not m:
        sys.exit("busy_bench: no ```python block under '## From Python' in README.md")
    return m.group(1)


def demo_command(root):
    """`make demo`'s command from the Makefile, its output in a temporary
    folder (--force: each run replaces the last)."""
    with open(os.path.join(root, "Makefile")) as f:
        text = f.read()
    m = re.search(r"^demo:.*\n(?:\t.*\n)*?\t\./\$\(BUILD\)/sandslide (run [^\n]*)$", text, re.M)
    if not m:
        sys.exit("busy_bench: no sandslide run line under 'demo:' in the Makefile")
    words = m.group(1).split()
    if "-o" in words:
        k = words.index("-o")
        del words[k:k + 2]
    return words


def clean_env(keep):
    env = dict(os.environ)
    if not keep:
        for k in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OMP_NUM_THREADS"):
            env.pop(k, None)
    return env


def run_demo(root, words, out, threads, env):
    args = [os.path.join(root, "build", "sandslide"), *words, "-o", out, "--force"]
    if threads != "default":
        args += ["--threads", str(threads)]
    t0 = time.perf_counter()
    r = subprocess.run(args, cwd=root, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit(f"busy_bench: {' '.join(args)} failed:\n{r.stderr}")
    m = re.search(r"on (\d+) threads?\b", r.stdout)
    return seconds, int(m.group(1)) if m else None


def run_python(root, code, threads, env):
    env = dict(env, PYTHONPATH=os.path.join(root, "python"))
    r = subprocess.run([sys.executable, "-c", PY_DRIVER, str(threads)], input=code, cwd=root,
                       env=env, capture_output=True, text=True)
    m = re.search(r"SECONDS ([0-9.]+)", r.stderr)
    if r.returncode != 0 or not m:
        sys.exit(f"busy_bench: the Python example of README.md#from-python failed:\n"
                 f"{r.stderr}")
    return float(m.group(1)), None


def start_busy(n):
    return [subprocess.Popen(["sh", "-c", "while :; do :; done"]) for _ in range(n)]


def stop_busy(procs):
    for p in procs:
        p.kill()
        p.wait()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", default=os.path.dirname(HERE),
                    help="the checkout whose build/ and python/ are measured (default: this one)")
    ap.add_argument("--rounds", type=int, default=3, help="runs of each (default 3): medians")
    ap.add_argument("--busy", type=int, default=2,
                    help="busy-loop processes beside a busy run (default 2)")
    ap.add_argument("--keep-env", action="store_true",
                    help="keep OMP_WAIT_POLICY, GOMP_SPINCOUNT, OMP_NUM_THREADS")
    a = ap.parse_args()
    root = os.path.abspath(a.root)
    env = clean_env(a.keep_env)
    words, code = demo_command(root), readme_python(root)
    loads = ("quiet", f"{a.busy} busy")
    variants = ("default", 1)
    times = {}      # (workload, load, threads) -> [seconds]
    used = {}       # (workload, load, threads) -> thread count the run reported
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "door.h5")
        for rnd in range(a.rounds):
            for load in loads:
                busy = start_busy(a.busy) if load != "quiet" else []
                try:
                    time.sleep(0.2 if busy else 0.0)   # let the loops take their cores
                    # alternate the order within a round so neither goes first always
                    order = variants if rnd % 2 == 0 else variants[::-1]
                    for threads in order:
                        s, n = run_demo(root, words, out, threads, env)
                        times.setdefault(("demo", load, threads), []).append(s)
                        used[("demo", load, threads)] = n
                        s, _ = run_python(root, code, threads, env)
                        times.setdefault(("python", load, threads), []).append(s)
                finally:
                    stop_busy(busy)
            print(f"round {rnd + 1} of {a.rounds} done", file=sys.stderr)

    print(f"# {root}: median of {a.rounds} interleaved runs; demo = wall time of "
          f"`sandslide {' '.join(words)}`, python = README.md#from-python's relax call")
    print(f"{'workload':8} {'load':8} {'threads':>9} {'median s':>9} {'[min, max]':>19} "
          f"{'ratio to 1 thread':>18}")
    for workload in ("demo", "python"):
        for load in loads:
            one = statistics.median(times[(workload, load, 1)])
            for threads in variants:
                t = times[(workload, load, threads)]
                med = statistics.median(t)
                label = str(threads)
                n = used.get((workload, load, threads))
                if threads == "default" and n:
                    label = f"default={n}"
                print(f"{workload:8} {load:8} {label:>9} {med:9.3f} "
                      f"[{min(t):7.3f}, {max(t):7.3f}] {med / one:18.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
