"""The thread count without --threads: OMP_NUM_THREADS when set (what a
batch system grants the job), else the CPUs this process may run on
(sched_getaffinity: taskset, a cpuset), not every processor of the
machine; --threads wins over both.  The summary lines say the count."""
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


def test_without_omp_num_threads_the_cpus_this_process_may_use(case, tmp_path):
    assert threads_used(case, tmp_path) == cpus(), "not the CPUs of the affinity mask"
    if not shutil.which("taskset"):
        pytest.skip("taskset not on PATH (Debian package util-linux): cannot narrow the mask")
    if cpus() < 2:
        pytest.skip(f"this process may use {cpus()} CPU: no mask to narrow")
    one = str(sorted(os.sched_getaffinity(0))[0])
    assert threads_used(case, tmp_path, prefix=("taskset", "-c", one)) == 1, \
        "taskset -c to one CPU: still more threads"


def test_relax_and_render_say_and_follow_it(tmp_path):
    rows = [[5.0 if 3 <= i < 6 and 2 <= j < 5 else 0.0 for i in range(10)] for j in range(8)]
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    assert threads_used(["relax", "dem.asc", "-o", "r.h5"], tmp_path,
                        {"OMP_NUM_THREADS": "1"}) == 1
    assert threads_used(["render", "r.h5", "-o", "frames", "--frames", "-1"], tmp_path,
                        {"OMP_NUM_THREADS": "1"}) == 1
