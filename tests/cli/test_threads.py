# SPDX-License-Identifier: BSD-3-Clause
"""The thread count without --threads: OMP_NUM_THREADS when set (what a
batch system grants the job), else the CPUs this process may run on
(sched_getaffinity: taskset, a cpuset), not every processor of the
machine, lowered for a small grid to one thread per 65536 cells and per
tile row; --threads wins over all of them.  The summary lines say the
count.  And OpenMP's idle threads sleep (OMP_WAIT_POLICY=passive) unless
the user set OMP_WAIT_POLICY or GOMP_SPINCOUNT."""
import os
import re
import shutil
import subprocess

import pytest

from conftest import BASE, SANDSLIDE, asc_text


def threads_used(args, cwd, env_extra=None, prefix=()):
    env = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
    env.update(env_extra or {})
    r = subprocess.run([*prefix, SANDSLIDE, *args], cwd=cwd, env=env, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    m = re.search(r"on (\d+) threads?\b", r.stdout)
    assert m, f"the summary does not say the threads:\n{r.stdout}"
    return int(m.group(1))


@pytest.fixture
def case(tmp_path):
    (tmp_path / "case.ini").write_text(BASE)
    return ["run", "case.ini", "-o", "out.h5", "--force"]


def cpus():
    return len(os.sched_getaffinity(0))


def test_omp_num_threads_sets_the_default(case, tmp_path):
    assert threads_used(case, tmp_path, {"OMP_NUM_THREADS": "1"}) == 1
    assert threads_used(case, tmp_path, {"OMP_NUM_THREADS": "3"}) == 3, \
        "OMP_NUM_THREADS=3 (a grant may exceed the CPUs seen) not taken"
    assert threads_used(case, tmp_path, {"OMP_NUM_THREADS": "2,1"}) == 2, \
        "a nested list's first entry is the count"


def test_threads_option_wins(case, tmp_path):
    assert threads_used(case + ["--threads", "2"], tmp_path, {"OMP_NUM_THREADS": "1"}) == 2


# 512 x 256 cells (8 tile rows): 2 threads' worth, by the rule of 65536
# cells per thread; a short end keeps it quick.
BIG = ["--set", "grid.nx=512", "--set", "grid.ny=256", "--set", "time.end=0.01",
       "--set", "time.output_every=0.01"]


def test_without_omp_num_threads_the_cpus_this_process_may_use(case, tmp_path):
    want = min(cpus(), 2)
    assert threads_used(case + BIG, tmp_path) == want, "not the CPUs of the affinity mask"
    if not shutil.which("taskset"):
        pytest.skip("taskset not on PATH (Debian package util-linux): cannot narrow the mask")
    if cpus() < 2:
        pytest.skip(f"this process may use {cpus()} CPU: no mask to narrow")
    one = str(sorted(os.sched_getaffinity(0))[0])
    assert threads_used(case + BIG, tmp_path, prefix=("taskset", "-c", one)) == 1, \
        "taskset -c to one CPU: still more threads"


def test_a_small_grid_runs_on_one_thread_unless_asked(case, tmp_path):
    """20 x 16 cells: a second thread would only wait at the barriers."""
    if cpus() < 2:
        pytest.skip(f"this process may use {cpus()} CPU: one thread anyway")
    assert threads_used(case, tmp_path) == 1, "a 20 x 16 grid ran on several threads"
    assert threads_used(case + ["--threads", "2"], tmp_path) == 2, "--threads 2 not kept"
    assert threads_used(case, tmp_path, {"OMP_NUM_THREADS": "2"}) == 2, \
        "OMP_NUM_THREADS=2 not kept"
    # 512 x 255 cells is one cell row short of two threads' 131072 cells
    edge = ["--set", "grid.nx=512", "--set", "grid.ny=255"] + BIG[4:]
    assert threads_used(case + edge, tmp_path) == 1
    rows = [[5.0 if 3 <= i < 6 and 2 <= j < 5 else 0.0 for i in range(10)] for j in range(8)]
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    assert threads_used(["relax", "dem.asc", "-o", "r.h5", "--force"], tmp_path) == 1, \
        "relax of a 10 x 8 DEM ran on several threads"


def omp_env(args, env_extra, tmp_path):
    """What sandslide says (`version`) and what libgomp read at start-up
    (OMP_DISPLAY_ENV=verbose prints its settings on stderr)."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OMP_DISPLAY_ENV")}
    env.update(env_extra)
    env["OMP_DISPLAY_ENV"] = "verbose"
    r = subprocess.run([SANDSLIDE, *args], cwd=tmp_path, env=env, capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    policy = re.search(r"wait policy ([^;]+);", r.stdout)
    spin = re.search(r"GOMP_SPINCOUNT = '(\d+)'", r.stderr)
    return policy.group(1) if policy else None, int(spin.group(1)) if spin else None


def test_idle_threads_sleep_unless_the_user_set_the_policy(tmp_path):
    said, spin = omp_env(["version"], {}, tmp_path)
    assert said == "passive", "`sandslide version` does not say the passive wait policy"
    if spin is None:
        pytest.skip("the OpenMP runtime is not libgomp: no GOMP_SPINCOUNT on display")
    assert spin == 0, f"libgomp spins {spin} times at a barrier: OMP_WAIT_POLICY=passive " \
                      "did not reach it"
    assert omp_env(["version"], {"OMP_WAIT_POLICY": "active"}, tmp_path) == \
        ("active", 30000000000), "the user's OMP_WAIT_POLICY=active not kept"
    assert omp_env(["version"], {"GOMP_SPINCOUNT": "1000"}, tmp_path) == \
        ("GOMP_SPINCOUNT", 1000), "the user's GOMP_SPINCOUNT not kept"


def test_relax_and_render_say_and_follow_it(tmp_path):
    rows = [[5.0 if 3 <= i < 6 and 2 <= j < 5 else 0.0 for i in range(10)] for j in range(8)]
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    assert threads_used(["relax", "dem.asc", "-o", "r.h5"], tmp_path,
                        {"OMP_NUM_THREADS": "1"}) == 1
    assert threads_used(["render", "r.h5", "-o", "frames", "--frames", "-1"], tmp_path,
                        {"OMP_NUM_THREADS": "1"}) == 1
