# SPDX-License-Identifier: BSD-3-Clause
"""bench --device cuda on a GPU (doc/gpu.md): the table and the JSON say
the device, its bandwidth and each case's rate; the room and materials
are refused or left out with the reason; the other commands say that their
loop is not on the GPU yet.  Skipped, with the reason, without a GPU
(`make CUDA=1 test-cuda`; tools/gpu_check.sh runs it on the GPU machine).
"""
import json
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SANDSLIDE = os.environ.get("SANDSLIDE", os.path.join(ROOT, "build-cuda", "sandslide"))
VERSION = subprocess.run([SANDSLIDE, "--version"], capture_output=True, text=True).stdout
GPU = re.search(r"^  cuda:0: (.*)$", VERSION, re.M)
NONE = re.search(r"^  cuda: none \((.*)\)$", VERSION, re.M)
pytestmark = pytest.mark.skipif(
    not GPU, reason=f"no GPU: {NONE.group(1) if NONE else VERSION.strip()}")


def run(args, timeout=300):
    return subprocess.run([SANDSLIDE] + args, capture_output=True, text=True, timeout=timeout)


BENCH = ["bench", "--device", "cuda", "--nx", "2048", "--ny", "2048", "--repeats", "2",
         "--closure", "coulomb"]


def test_bench_on_the_gpu_says_the_device_and_its_roofline():
    r = run(BENCH + ["--surface", "all"])
    assert r.returncode == 0, r.stderr
    assert f"device cuda:0: {GPU.group(1)}" in r.stdout, r.stdout
    assert "device-to-device copy" in r.stdout and "note: the room" in r.stdout, r.stdout
    rows = [l.split() for l in r.stdout.splitlines() if l.split()[:1] in
            (["supercritical"], ["subcritical"], ["patch"])]
    assert len(rows) == 3 and all(row[2] == "gpu" for row in rows), r.stdout
    for row in rows:
        assert float(row[3]) > 1e8, f"{row[0]}: {row[3]} cell-updates/s"
        assert row[-2] == "26.00", f"{row[0]}: {row[-2]} B per cell-update, expected 26"


def test_bench_json_on_the_gpu():
    r = run(BENCH + ["--surface", "supercritical", "--json"])
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["device"].startswith("cuda:0: "), report
    assert report["bandwidth_bytes_per_s"]["gpu"] > 1e11, report
    case = report["cases"][0]
    assert case["threads"] == 0 and case["cell_updates_per_s"]["median"] > 0, case


def test_materials_are_refused_on_the_gpu():
    r = run(BENCH + ["--surface", "supercritical", "--angles", "3"])
    assert r.returncode == 2 and "materials do not run on the GPU yet" in r.stderr, r.stderr


def test_the_other_commands_say_their_loop_is_not_on_the_gpu(tmp_path):
    with open(os.path.join(ROOT, "tests", "base.ini")) as f:
        (tmp_path / "base.ini").write_text(f.read())
    r = run(["run", str(tmp_path / "base.ini"), "-o", str(tmp_path / "o.h5"), "--device", "cuda"])
    assert r.returncode == 2 and "run does not run on a GPU yet, only bench does" in r.stderr, \
        r.stderr
    r = run(["bench", "--device", "cuda:63", "--nx", "600", "--ny", "600"])
    assert r.returncode == 2 and "this machine has" in r.stderr, r.stderr
