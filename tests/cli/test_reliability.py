# SPDX-License-Identifier: BSD-3-Clause
"""Nothing lost, nothing crashes (issue 6): overwrite refusal, interrupts and
restarts bit for bit, write failures, the non-finite guard.

The interrupts are sent to sandslide-pause (tests/hooks/pause_step.c),
paused after a chosen substep: they arrive there whatever the speed of the
machine, and the run stops after the next substep."""
import contextlib
import os
import re
import resource
import signal
import subprocess
import sys

import h5py
import numpy as np
import pytest

import conftest
from conftest import (BASE, SANDSLIDE, SANDSLIDE_NAN, SANDSLIDE_PAUSE, edit, h5open, hook_binary,
                      pause_env, run, wait_paused)

# 40 x 30 cells poured by a source next to an open side: about 10^4 steps
# over 40 s of simulated time, a snapshot every 2 s
POUR = edit(edit(edit(edit(BASE, "nx = 20\n", "nx = 40\n"), "ny = 16\n", "ny = 30\n"),
                 "dx = 0.1\n", "dx = 0.05\n"),
            "end = 1\noutput_every = 0.5\n", "end = 40\noutput_every = 2\n") + """
[source pour]
rect = 0.2 0.5 0.6 1.0
rate = 0.02
start = 0
stop = 30
"""

PHYSICAL = ["volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps"]


def write_case(tmp_path, text=POUR, name="pour.ini"):
    (tmp_path / name).write_text(text)
    return name


def start_paused(args, cwd, step):
    """sandslide-pause with args, paused after substep `step` until a stop
    signal comes (wait_paused waits for that)."""
    marker = cwd / "paused"
    marker.unlink(missing_ok=True)   # left by an earlier run
    p = subprocess.Popen([hook_binary(SANDSLIDE_PAUSE)] + args, cwd=cwd, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=pause_env(step, marker))
    try:
        wait_paused(p, marker, step)
    except BaseException:
        p.kill()
        p.communicate()
        raise
    return p


def snapshots(path):
    with h5open(path) as f:
        return f["time"][:].copy()


def assert_same_snapshots(a, b):
    conftest.assert_same_snapshots(a, b, PHYSICAL)


# ---- overwrite safety --------------------------------------------------------


def test_run_refuses_to_replace_an_output_without_force(tmp_path):
    write_case(tmp_path, BASE, "case.ini")
    assert run(["run", "case.ini", "-o", "o.h5", "-q"], cwd=tmp_path).returncode == 0
    before = (tmp_path / "o.h5").read_bytes()
    r = run(["run", "case.ini", "-o", "o.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 2 and "--force" in r.stderr, r.stderr
    assert (tmp_path / "o.h5").read_bytes() == before, "the refused run touched the file"
    r = run(["run", "case.ini", "-o", "o.h5", "-q", "--force"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr


def test_relax_refuses_to_replace_an_output_without_force(tmp_path):
    (tmp_path / "d.asc").write_text("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n"
                                    "cellsize 1\n0 0 0\n0 0 9\n")
    assert run(["relax", "d.asc", "-o", "r.asc", "-q"], cwd=tmp_path).returncode == 0
    r = run(["relax", "d.asc", "-o", "r.asc", "-q"], cwd=tmp_path)
    assert r.returncode == 2 and "--force" in r.stderr, r.stderr
    assert run(["relax", "d.asc", "-o", "r.asc", "-q", "--force"],
               cwd=tmp_path).returncode == 0


# ---- interrupts and restarts ---------------------------------------------------


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_mid_run_then_restart_matches_an_uninterrupted_run(tmp_path, sig, code):
    # Euler: about 290 substeps between snapshots (RKL2 cut between output
    # times and continued is test_rkl2.py's
    # test_restart_of_a_cut_rkl2_run_matches_an_uninterrupted_run)
    case = write_case(tmp_path, POUR.replace("[time]\n", "[time]\nintegrator = euler\n"))
    r = run(["run", case, "-o", "whole.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "whole.h5") as f:
        steps, times = f["steps"][:], f["time"][:]
    # the signal comes mid-interval, after 4 snapshots
    pause = int(steps[3] + steps[4]) // 2
    p = start_paused(["run", case, "-o", "cut.h5", "-q", "--threads", "2"], tmp_path, pause)
    p.send_signal(sig)
    out, err = p.communicate(timeout=60)
    assert p.returncode == code, (p.returncode, err)
    assert f"(step {pause + 1})" in err and "sandslide run --restart cut.h5" in err, err
    with h5open(tmp_path / "cut.h5") as f:
        assert list(f["steps"][:]) == list(steps[:4]) + [pause + 1], \
            f"signalled after step {pause}: snapshots after steps {list(f['steps'][:])}"
        assert times[3] < f["time"][-1] < times[4], f"the interrupt's snapshot at {f['time'][-1]}"

    r = run(["run", "--restart", "cut.h5", "-q", "--threads", "1"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert snapshots(tmp_path / "cut.h5")[-1] == 40.0
    assert_same_snapshots(tmp_path / "cut.h5", tmp_path / "whole.h5")


def test_restart_after_a_kill_while_a_snapshot_was_written(tmp_path):
    """A run killed while it flushed snapshot k leaves /height and the
    diagnostics one longer than /time, and may have written half of k's
    restart state: its attribute (restart_state_odd for odd k) is one the
    last complete snapshot does not use.  That file reads as k snapshots,
    and --restart continues it to the bits of an uninterrupted run.  The
    kill is made by hand, so that no timing decides what it hits."""
    case = write_case(tmp_path, POUR.replace("[time]\n", "[time]\nintegrator = euler\n"))
    r = run(["run", case, "-o", "whole.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "whole.h5") as f:
        steps = f["steps"][:]
    p = start_paused(["run", case, "-o", "cut.h5", "-q"], tmp_path, int(steps[3] + 10))
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=60)
    assert p.returncode == 130, p.returncode
    with h5py.File(tmp_path / "cut.h5", "r+") as f:
        k = f["time"].shape[0]
        assert k == 5, f"test set-up: the interrupted run wrote {k} snapshots, not 5"
        assert "restart_state_even" in f.attrs and "restart_state_odd" in f.attrs, \
            f"the restart state is not in two attributes: {sorted(f.attrs)}"
        for name in ["height"] + PHYSICAL + ["active_fraction", "wall_seconds",
                                             "stencil_evaluations"]:
            f[name].resize(k + 1, axis=0)
            f[name][k] = 1e9
        f.attrs["restart_state_even" if k % 2 == 0 else "restart_state_odd"] = np.full(7, 1e9)
    r = run(["info", "cut.h5"], cwd=tmp_path)
    assert r.returncode == 0 and re.search(r"snapshots +5,", r.stdout), \
        f"info does not read the 5 complete snapshots: {r.stdout}{r.stderr}"
    r = run(["run", "--restart", "cut.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert_same_snapshots(tmp_path / "cut.h5", tmp_path / "whole.h5")


def test_restart_of_a_finished_run_is_a_no_op_and_case_must_match(tmp_path):
    case = write_case(tmp_path)
    assert run(["run", case, "-o", "o.h5", "-q"], cwd=tmp_path).returncode == 0
    n = len(snapshots(tmp_path / "o.h5"))
    # the same case named explicitly is accepted; nothing is left to do
    r = run(["run", case, "--restart", "o.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert len(snapshots(tmp_path / "o.h5")) == n
    # another case is refused
    write_case(tmp_path, edit(POUR, "rate = 0.02", "rate = 0.03"), "other.ini")
    r = run(["run", "other.ini", "--restart", "o.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 2 and "not the case" in r.stderr, r.stderr
    r = run(["run", "--restart", "o.h5", "--set", "model.nu=0.2", "-q"], cwd=tmp_path)
    assert r.returncode == 2 and "--set" in r.stderr, r.stderr


def test_restart_from_another_folder_finds_the_case_files_beside_the_named_case(tmp_path):
    # a case whose initial surface is a file beside it, run from its parent
    (tmp_path / "proj").mkdir()
    (tmp_path / "elsewhere").mkdir()
    rows = "\n".join(" ".join("0.4" if i < 5 else "0.1" for i in range(20)) for _ in range(16))
    (tmp_path / "proj" / "start.asc").write_text(
        "ncols 20\nnrows 16\nxllcorner 0\nyllcorner 0\ncellsize 0.1\n" + rows + "\n")
    write_case(tmp_path / "proj", edit(BASE, "type = flat\nheight = 0.2\n",
                                       "type = file\nfile = start.asc\n"), "c.ini")
    assert run(["run", "proj/c.ini", "-o", "o.h5", "-q"], cwd=tmp_path).returncode == 0
    n = len(snapshots(tmp_path / "o.h5"))
    # 'proj/c.ini' means nothing from elsewhere/: the message says what to give
    r = run(["run", "--restart", "../o.h5", "-q"], cwd=tmp_path / "elsewhere")
    assert r.returncode == 2 and "proj/start.asc" in r.stderr, r.stderr
    assert "sandslide run --restart ../o.h5 PATH/TO/CASE.ini" in r.stderr, r.stderr
    # named, the case's files are found beside it
    r = run(["run", "--restart", "../o.h5", "../proj/c.ini", "-q"], cwd=tmp_path / "elsewhere")
    assert r.returncode == 0, r.stderr
    assert len(snapshots(tmp_path / "o.h5")) == n


@pytest.mark.parametrize("damage", ["truncated", "garbage", "relax_series", "missing"])
def test_restart_refuses_files_it_cannot_continue(tmp_path, damage):
    case = write_case(tmp_path, BASE, "case.ini")
    assert run(["run", case, "-o", "o.h5", "-q"], cwd=tmp_path).returncode == 0
    path = tmp_path / "o.h5"
    if damage == "truncated":
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 3])
    elif damage == "garbage":
        path.write_bytes(os.urandom(4096))
    elif damage == "relax_series":
        (tmp_path / "d.asc").write_text("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n"
                                        "cellsize 1\n0 0 0\n0 0 9\n")
        path.unlink()
        assert run(["relax", "d.asc", "-o", "o.h5", "-q"], cwd=tmp_path).returncode == 0
    else:
        path.unlink()
    r = run(["run", "--restart", "o.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "o.h5" in r.stderr and r.stderr.count("\n") == 1, r.stderr


# ---- write failures ------------------------------------------------------------


def test_file_size_limit_gives_exit_1_and_keeps_earlier_snapshots(tmp_path):
    case = write_case(tmp_path, edit(edit(POUR, "nx = 40\n", "nx = 200\n"),
                                     "ny = 30\n", "ny = 200\n"))
    limit = 2 * 1024 * 1024      # each snapshot adds 320 kB of heights

    def cap():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    p = subprocess.run([SANDSLIDE, "run", case, "-o", "big.h5", "-q"], cwd=tmp_path,
                       capture_output=True, text=True, preexec_fn=cap, timeout=300)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert "big.h5" in p.stderr and "large" in p.stderr.lower(), p.stderr
    t = snapshots(tmp_path / "big.h5")
    assert len(t) >= 2, f"only {len(t)} snapshots readable"
    with h5open(tmp_path / "big.h5") as f:
        h = f["height"][len(t) - 1]
        assert np.isfinite(h).all()


@contextlib.contextmanager
def small_disk(tmp_path):
    """A 3 MiB tmpfs (root only, with the right to mount; the test is
    skipped elsewhere, saying why), unmounted after."""
    disk = tmp_path / "small"
    disk.mkdir()
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(disk)],
                       capture_output=True, text=True)
    if m.returncode != 0:
        pytest.skip("cannot mount a 3 MiB tmpfs here (needs root and CAP_SYS_ADMIN): mount "
                    f"said {(m.stderr.strip().splitlines() or [''])[0]!r}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", str(disk)])


def test_full_disk_gives_exit_1_and_keeps_earlier_snapshots(tmp_path):
    """On a 3 MiB tmpfs (root only, with the right to mount; skipped
    elsewhere, saying why)."""
    with small_disk(tmp_path) as disk:
        # a steady run: its projected size is an upper bound, told but not
        # refused up front (doc/running.md#run), so the disk fills mid-run
        case = write_case(disk, edit(edit(edit(POUR, "nx = 40\n", "nx = 200\n"),
                                          "ny = 30\n", "ny = 200\n"),
                                     "end = 40\n", "end = steady\nmax_time = 40\n"))
        p = subprocess.run([SANDSLIDE, "run", case, "-o", "big.h5", "-q"], cwd=disk,
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 1, (p.returncode, p.stderr)
        assert "No space left" in p.stderr, p.stderr
        assert len(snapshots(disk / "big.h5")) >= 2


def test_a_run_larger_than_the_disk_is_refused_up_front(tmp_path):
    """On a 3 MiB tmpfs (as above): 21 snapshots of 313 KiB do not fit, so
    the run is refused before it starts (exit 2, nothing written), naming
    the output_every that fits; with that output_every it runs and fits."""
    with small_disk(tmp_path) as disk:
        case = write_case(disk, edit(edit(POUR, "nx = 40\n", "nx = 200\n"),
                                     "ny = 30\n", "ny = 200\n"))
        p = subprocess.run([SANDSLIDE, "run", case, "-o", "big.h5"], cwd=disk,
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 2, (p.returncode, p.stderr)
        assert "'big.h5' would grow by " in p.stderr and "(21 snapshots of " in p.stderr, \
            p.stderr
        every = re.search(r"--set time\.output_every=([\d.e+-]+) or more", p.stderr)
        assert every, p.stderr
        assert sorted(os.listdir(disk)) == [case], os.listdir(disk)
        p = subprocess.run([SANDSLIDE, "run", case, "-o", "big.h5", "--set",
                            f"time.output_every={every.group(1)}"], cwd=disk,
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, (p.returncode, p.stderr)
        assert len(snapshots(disk / "big.h5")) >= 2


# ---- the non-finite guard --------------------------------------------------------
# No input reaches it (the CFL bound keeps heights finite), so these tests
# run sandslide-nan, sandslide linked with the test hook tests/hooks/nan_step.c:
# with SANDSLIDE_TEST_NAN_STEP=N the middle cell's height becomes NaN after
# substep N.


def test_the_real_sandslide_has_no_test_hook(tmp_path):
    case = write_case(tmp_path, BASE, "case.ini")
    # nor the pause's: paused, it would wait 300 s for a signal
    env = dict(os.environ, SANDSLIDE_TEST_NAN_STEP="3", SANDSLIDE_TEST_PAUSE_STEP="3",
               SANDSLIDE_TEST_PAUSE_SECONDS="300")
    p = subprocess.run([SANDSLIDE, "run", case, "-o", "o.h5", "-q"], cwd=tmp_path,
                       capture_output=True, text=True, env=env, timeout=120)
    assert p.returncode == 0, (p.returncode, p.stderr)
    with h5open(tmp_path / "o.h5") as f:
        assert f["steps"][-1] > 3 and np.isfinite(f["height"][:]).all()


@pytest.mark.parametrize("integrator", ["euler", "rkl2"])
def test_non_finite_height_stops_with_exit_1_naming_cell_and_step(tmp_path, integrator):
    case = write_case(tmp_path, POUR.replace("[time]\n", f"[time]\nintegrator = {integrator}\n"))
    assert run(["run", case, "-o", "whole.h5", "-q"], cwd=tmp_path).returncode == 0
    with h5open(tmp_path / "whole.h5") as f:
        # Euler takes thousands of steps, RKL2 tens of super-steps: a step
        # between two snapshots half-way through
        nan_step = int(f["steps"][len(f["steps"]) // 2]) + 2
    env = dict(os.environ, SANDSLIDE_TEST_NAN_STEP=str(nan_step))
    p = subprocess.run([SANDSLIDE_NAN, "run", case, "-o", "nan.h5", "-q"], cwd=tmp_path,
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 1, (p.returncode, p.stderr)
    # the NaN is put into cell (20, 15) after step nan_step; it is caught by
    # the slope measure or the sweep of the next step, which may have
    # spread it to the neighbours
    m = re.search(r"cell \((\d+), (\d+)\).* in step (\d+) .*"
                  r"last good state, after step (\d+) at t = (\S+) s, is snapshot (\d+)",
                  p.stderr)
    assert m, p.stderr
    i, j, step, good_step, index = (int(m.group(k)) for k in (1, 2, 3, 4, 6))
    good_time = float(m.group(5))
    assert abs(i - 20) <= 1 and abs(j - 15) <= 1 and step in (nan_step, nan_step + 1), \
        p.stderr
    assert good_step == step - 1, p.stderr
    with h5open(tmp_path / "nan.h5") as f:
        assert np.isfinite(f["height"][:]).all(), "a non-finite snapshot was written"
        assert len(f["time"]) == index + 1, "the last good state is not the last snapshot"
        assert f["steps"][-1] == good_step, \
            f"the last snapshot is after step {f['steps'][-1]}, not {good_step}"
        assert f["time"][-1] == pytest.approx(good_time, rel=1e-8) and good_time < 40.0
    # the last good state was taken again from the snapshot before it: were
    # it off by a bit, the run continued from it would not be the
    # uninterrupted run, bit for bit
    r = run(["run", "--restart", "nan.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert_same_snapshots(tmp_path / "nan.h5", tmp_path / "whole.h5")


def test_non_finite_height_at_a_snapshot_time_is_not_written(tmp_path):
    # 4 s between snapshots and a NaN after the step that lands on t = 4:
    # the snapshot at 4 s would hold it, so the state one step earlier is
    # written instead
    case = write_case(tmp_path, edit(POUR, "output_every = 2", "output_every = 4"))
    assert run(["run", case, "-o", "whole.h5", "-q"], cwd=tmp_path).returncode == 0
    with h5open(tmp_path / "whole.h5") as f:
        landing = int(f["steps"][1])
    env = dict(os.environ, SANDSLIDE_TEST_NAN_STEP=str(landing))
    p = subprocess.run([SANDSLIDE_NAN, "run", case, "-o", "nan.h5", "-q"], cwd=tmp_path,
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert f"in step {landing} " in p.stderr and \
        f"after step {landing - 1} at" in p.stderr, p.stderr
    with h5open(tmp_path / "nan.h5") as f:
        assert list(f["steps"][:]) == [0, landing - 1], list(f["steps"][:])
        assert np.isfinite(f["height"][:]).all(), "a non-finite snapshot was written"
        assert 0 < f["time"][-1] < 4.0


# ---- relax has the same guarantees (one time loop, src/app/drive.c) ------------


def write_cliff(path, nx, ny, dx=0.1):
    """A 1.5 m plateau ending in a vertical cliff over a rough floor, as an
    ESRI ASCII grid (rows north first, %.17g)."""
    rng = np.random.default_rng(11)
    h = 0.02 * rng.random((ny, nx))
    h[:, : nx // 3] += 1.5
    rows = "\n".join(" ".join(repr(float(v)) for v in h[j]) for j in range(ny - 1, -1, -1))
    path.write_text(f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\ncellsize {dx!r}\n"
                    + rows + "\n")


def read_asc_values(path):
    tokens = path.read_text().split()
    head = dict(zip(tokens[0:10:2], tokens[1:10:2]))
    nx, ny = int(head["ncols"]), int(head["nrows"])
    return np.array([float(t) for t in tokens[10:10 + nx * ny]]).reshape(ny, nx)[::-1]


# The cliff of 40 x 30 cells takes thousands of Euler substeps to relax, a
# snapshot every 8 with --output-every 0.02: relax is signalled after
# substep 30 (4 snapshots out) or 200.  RKL2, relax's default, settles it
# in fewer super-steps than that, so these runs take Euler.


def relax_cut(tmp_path, out, pause, sig, extra=()):
    """relax cliff.asc -o out, signalled after substep `pause`: its stderr."""
    p = start_paused(["relax", "cliff.asc", "-o", out, "--integrator", "euler", *extra],
                     tmp_path, pause)
    p.send_signal(sig)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 128 + sig, (p.returncode, err)
    assert "interrupted at t = " in err and f"(step {pause + 1})" in err and out in err, err
    return err


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_relax_signal_keeps_the_input_and_every_snapshot(tmp_path, sig):
    write_cliff(tmp_path / "cliff.asc", 40, 30)
    before = (tmp_path / "cliff.asc").read_bytes()
    relax_cut(tmp_path, "cut.h5", 30, sig, ["--output-every", "0.02", "-q"])
    assert (tmp_path / "cliff.asc").read_bytes() == before, "the input was modified"
    with h5open(tmp_path / "cut.h5") as f:
        n = len(f["time"])
        assert n >= 4 and f["height"].shape[0] == n, f"{n} snapshots"
        assert f["steps"][-1] == 31 and np.all(np.diff(f["steps"][:]) > 0), f["steps"][:]
        assert np.isfinite(f["height"][:]).all()
    assert not list(tmp_path.glob(".*.lock")), "the claim of the output was left behind"


@pytest.mark.parametrize("call, evaluations", [(1, 1), (4, 0)])
def test_a_stop_inside_a_super_step_waits_at_most_one_evaluation(tmp_path, call, evaluations):
    """A stop request is answered within one evaluation of the stencil, not
    at the end of a super-step of hundreds of stages: the super-step it
    comes in is taken back, and the interrupt's snapshot is the state after
    the step before.  Paused at the end of step 3 (call 1: the stop is seen
    after stage 1 of step 4) and after stage 3 of step 4 (call 4: at once),
    with two busy processes beside it, as on a loaded machine; the latency
    is counted in evaluations (tests/hooks/pause_step.c), not seconds."""
    write_cliff(tmp_path / "cliff.asc", 60, 40)
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        marker = tmp_path / "paused"
        env = dict(pause_env(3, marker), SANDSLIDE_TEST_PAUSE_CALL=str(call))
        p = subprocess.Popen([hook_binary(SANDSLIDE_PAUSE), "relax", "cliff.asc", "-o", "cut.h5",
                              "--integrator", "rkl2", "--threads", "2"], cwd=tmp_path,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        try:
            wait_paused(p, marker, 3)
        except BaseException:
            p.kill()
            p.communicate()
            raise
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        for b in busy:
            b.kill()
            b.wait()
    assert p.returncode == 130, (p.returncode, err)
    said = re.search(r"pause hook: (\d+) evaluations after the stop signal", err)
    assert said, f"the hook saw no stop signal:\n{err}"
    assert int(said.group(1)) == evaluations, \
        f"paused at report {call} of step 3: the stop came {said.group(1)} evaluations " \
        f"after the signal, expected {evaluations}\n{err}"
    assert "(step 3)" in err, f"the super-step the stop came in was not taken back:\n{err}"
    with h5open(tmp_path / "cut.h5") as f:
        assert f["steps"][-1] == 3 and np.isfinite(f["height"][-1]).all(), f["steps"][:]


def test_relax_signal_with_a_raster_output_writes_the_surface_then(tmp_path):
    write_cliff(tmp_path / "cliff.asc", 40, 30)
    before = (tmp_path / "cliff.asc").read_bytes()
    err = relax_cut(tmp_path, "cut.asc", 200, signal.SIGTERM)
    assert "not relaxed" in err, err
    assert (tmp_path / "cliff.asc").read_bytes() == before, "the input was modified"
    h = read_asc_values(tmp_path / "cut.asc")
    assert h.shape == (30, 40) and np.isfinite(h).all()
    # "then": the surface after substep 201, as a series cut there holds it
    relax_cut(tmp_path, "cut.h5", 200, signal.SIGTERM, ["--output-every", "1", "-q"])
    with h5open(tmp_path / "cut.h5") as f:
        assert f["steps"][-1] == 201
        assert np.array_equal(h, f["height"][-1]), "the raster is not the state after step 201"


def test_relax_non_finite_height_keeps_the_last_good_state(tmp_path):
    """The guard of relax, once with a raster output (the steps taken again
    from the DEM, through the same targets) and once with a series (from its
    last snapshot): both keep the state after the step before, the same
    bits."""
    write_cliff(tmp_path / "cliff.asc", 40, 30)
    before = (tmp_path / "cliff.asc").read_bytes()
    # in forward Euler's part of the relax (471 steps in all, since issue 35)
    env = dict(os.environ, SANDSLIDE_TEST_NAN_STEP="300")
    outs = {}
    for out in ("good.asc", "good.h5"):
        p = subprocess.run([SANDSLIDE_NAN, "relax", "cliff.asc", "-o", out, "-q",
                            "--output-every", "0.05"],
                           cwd=tmp_path, capture_output=True, text=True, env=env, timeout=300)
        assert p.returncode == 1, (out, p.returncode, p.stderr)
        assert len(p.stderr.splitlines()) == 1, p.stderr
        m = re.search(r"cell \((\d+), (\d+)\).* in step (\d+) \(t = (\S+) s\); "
                      r"the last good state, after step (\d+) at t = (\S+) s, is", p.stderr)
        assert m and out in p.stderr, p.stderr
        i, j, step, good_step = (int(m.group(k)) for k in (1, 2, 3, 5))
        assert abs(i - 20) <= 1 and abs(j - 15) <= 1 and step in (300, 301), p.stderr
        assert good_step == step - 1, p.stderr
        outs[out] = good_step
    assert (tmp_path / "cliff.asc").read_bytes() == before, "the input was modified"
    h = read_asc_values(tmp_path / "good.asc")
    with h5open(tmp_path / "good.h5") as f:
        assert f["steps"][-1] == outs["good.h5"]
        assert len(f["time"]) >= 3, "the series should have snapshots before the NaN"
        last = f["height"][-1]
    assert np.isfinite(h).all()
    assert np.array_equal(h, last), "the two ways to the last good state disagree"
