# SPDX-License-Identifier: BSD-3-Clause
"""--device on run, relax, bench and fit (doc/gpu.md), in any build.

A GPU that cannot be had is bad input, exit 2, one line with the reason:
this build has no CUDA (the default build), the machine has no GPU (a CUDA
build here), or, on a GPU, that the command's loop is not on the device
yet (only bench is).  --device cpu is the default and changes no bit;
--version lists the devices.  What runs on a GPU is tests/gpu/'s.
"""
import os
import re
import subprocess

import numpy as np
import pytest

from conftest import BASE, CASES, SANDSLIDE, asc_text, run, run_ok

VERSION = subprocess.run([SANDSLIDE, "--version"], capture_output=True, text=True).stdout
CUDA_BUILD = "CUDA: on" in VERSION
# the reason a GPU is refused on this machine: the build, the driver, or
# (with a GPU) that only bench runs there
if not CUDA_BUILD:
    REASON = "this build has no CUDA: make CUDA=1 builds one"
elif re.search(r"^  cuda:0: ", VERSION, re.M):
    REASON = "does not run on a GPU yet"
else:
    REASON = "GPU"


def pile(tmp_path):
    """A small steep pile as an .asc."""
    h = np.zeros((12, 14))
    h[4:8, 5:9] = 0.3
    path = tmp_path / "pile.asc"
    path.write_text(asc_text(h, cellsize=0.1))
    return path


def commands(tmp_path):
    """Each command that takes --device, with what it needs to start."""
    (tmp_path / "base.ini").write_text(BASE)
    return {
        "run": ["run", str(tmp_path / "base.ini"), "-o", str(tmp_path / "r.h5")],
        "relax": ["relax", str(pile(tmp_path)), "-o", str(tmp_path / "out.asc")],
        "bench": ["bench", "--nx", "600", "--ny", "600", "--repeats", "1", "--steps", "1",
                  "--surface", "supercritical", "--closure", "coulomb"],
        "fit": ["fit", str(tmp_path / "base.ini"), str(tmp_path / "obs.h5"),
                "--param", "nu=0.01:1"],
    }


@pytest.mark.parametrize("command", ["run", "relax", "bench", "fit"])
@pytest.mark.parametrize("device", ["cuda", "cuda:3"])
def test_a_gpu_that_cannot_be_had_is_bad_input(tmp_path, command, device):
    args = commands(tmp_path)[command] + ["--device", device]
    if CUDA_BUILD and command == "bench" and "cuda:0" in VERSION and device == "cuda":
        pytest.skip("this machine has a GPU: bench runs on it (tests/gpu/)")
    r = run(args)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, f"{command} --device {device}: exit {r.returncode}, {r.stderr!r}"
    assert len(lines) == 1 and lines[0].startswith(f"sandslide: --device {device if ':' in device else 'cuda:0'}: "), \
        f"{command} --device {device}: not one line naming the device: {r.stderr!r}"
    if device == "cuda":
        assert REASON in lines[0], f"{command}: the reason is not given: {lines[0]!r}"
    assert not os.path.exists(tmp_path / "r.h5") and not os.path.exists(tmp_path / "out.asc"), \
        f"{command} --device {device} wrote an output"


@pytest.mark.parametrize("word", ["gpu", "cuda:", "cuda:-1", "cuda:01", "cuda:64", "CPU", "cuda0"])
def test_a_device_that_is_not_a_name_is_refused(tmp_path, word):
    r = run(commands(tmp_path)["relax"] + ["--device", word])
    assert r.returncode == 2 and "expected cpu, cuda or cuda:N" in r.stderr, \
        f"--device {word!r}: exit {r.returncode}, {r.stderr!r}"


def test_cpu_is_the_default_and_changes_no_bit(tmp_path):
    src = pile(tmp_path)
    run_ok(["relax", str(src), "-o", str(tmp_path / "a.asc")])
    run_ok(["relax", str(src), "-o", str(tmp_path / "b.asc"), "--device", "cpu"])
    assert (tmp_path / "a.asc").read_bytes() == (tmp_path / "b.asc").read_bytes(), \
        "--device cpu gives other bits than no --device"
    (tmp_path / "base.ini").write_text(BASE)
    r = run_ok(["bench", "--nx", "600", "--ny", "600", "--repeats", "1", "--steps", "1",
                "--surface", "subcritical", "--closure", "coulomb", "--threads", "1",
                "--device", "cpu"])
    assert "subcritical" in r.stdout, r.stdout


def test_version_lists_the_devices():
    assert re.search(r"CUDA: (on|off);", VERSION), VERSION
    lines = VERSION.splitlines()
    assert "devices (--device):" in lines, VERSION
    assert any(re.match(r"  cpu: (generic|avx2|avx512), \d+ threads$", l) for l in lines), VERSION
    cuda = [l for l in lines if l.startswith("  cuda")]
    assert cuda, f"--version says nothing of CUDA: {VERSION}"
    if not CUDA_BUILD:
        assert cuda == ["  cuda: none (this build has no CUDA: make CUDA=1 builds one (doc/gpu.md))"], cuda


def test_help_and_man_page_name_the_option():
    for command in ("run", "relax", "bench", "fit"):
        r = run_ok([command, "--help"])
        assert "--device cpu|cuda[:N]" in r.stdout, f"{command} --help: no --device"
