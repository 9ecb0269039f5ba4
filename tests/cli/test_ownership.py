# SPDX-License-Identifier: BSD-3-Clause
"""One run owns its output (issue 12): a run or relaxation aimed at an
output (or its .partial) that a live run is writing is refused with exit 2,
--force or not; it never deletes or replaces a file it did not create; of
two runs started together exactly one proceeds; the claim of a killed run
is taken over.  The claim is a lock file beside the output (src/io/output.h).
"""
import os
import signal
import subprocess

import numpy as np

from conftest import SANDSLIDE, SANDSLIDE_PAUSE, h5open, hook_binary, run, wait_for
from test_reliability import snapshots, write_cliff
from test_run import slow_case

EVERY = 0.02
LONG = slow_case(1000, EVERY)      # a cone that slides for a long time


def start(args, cwd, pause_step=None):
    """sandslide with args; with pause_step, sandslide-pause, which waits
    after that substep for the stop signal: a run that lasts until it is
    stopped, however fast the machine and the method."""
    if pause_step is None:
        return subprocess.Popen([SANDSLIDE] + args, cwd=cwd, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
    env = dict(os.environ, SANDSLIDE_TEST_PAUSE_STEP=str(pause_step))
    return subprocess.Popen([hook_binary(SANDSLIDE_PAUSE)] + args, cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def count(path):
    try:
        return len(snapshots(path))
    except Exception:      # not there yet, or being written
        return 0


def stop(p, sig=signal.SIGINT):
    p.send_signal(sig)
    out, err = p.communicate(timeout=60)
    return p.returncode, err


def assert_refused(r, holder=None):
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "being written by another sandslide run" in r.stderr, r.stderr
    assert len(r.stderr.splitlines()) == 1, r.stderr
    if holder is not None:
        assert f"process {holder.pid}" in r.stderr, r.stderr


def assert_whole(path, at_least, interrupted=True):
    """Every snapshot readable, one every EVERY seconds (and the last one at
    the interruption)."""
    with h5open(path) as f:
        t = f["time"][:]
        assert len(t) >= at_least and f["height"].shape[0] == len(t)
        regular = t[:-1] if interrupted else t
        np.testing.assert_allclose(regular, EVERY * np.arange(len(regular)), rtol=1e-12,
                                   atol=0)
        assert np.all(np.diff(t) > 0)
        assert np.isfinite(f["height"][:]).all()


def test_two_runs_started_together_exactly_one_proceeds(tmp_path):
    (tmp_path / "case.ini").write_text(LONG)
    a = start(["run", "case.ini", "-o", "o.h5", "-q"], tmp_path)
    b = start(["run", "case.ini", "-o", "o.h5", "-q"], tmp_path)
    try:
        assert wait_for(lambda: a.poll() is not None or b.poll() is not None, 60), \
            "neither run was refused"
        loser, winner = (a, b) if a.poll() is not None else (b, a)
        out, err = loser.communicate(timeout=10)
        assert_refused(subprocess.CompletedProcess(loser.args, loser.returncode, out, err),
                       winner)
        assert wait_for(lambda: count(tmp_path / "o.h5") >= 3 or winner.poll() is not None,
                        60), "the run that proceeded wrote nothing"
        assert winner.poll() is None, winner.communicate()
    finally:
        for p in (a, b):
            if p.poll() is None:
                code, err = stop(p)
                assert code == 130, (code, err)
    assert_whole(tmp_path / "o.h5", 3)
    assert not (tmp_path / "o.h5.partial").exists()
    assert not (tmp_path / ".o.h5.lock").exists(), "the claim was not given up"


def test_force_restart_and_partial_do_not_touch_a_live_run(tmp_path):
    (tmp_path / "case.ini").write_text(LONG)
    a = start(["run", "case.ini", "-o", "o.h5", "-q"], tmp_path)
    try:
        assert wait_for(lambda: count(tmp_path / "o.h5") >= 3 or a.poll() is not None, 60)
        assert a.poll() is None, a.communicate()
        inode = os.stat(tmp_path / "o.h5").st_ino
        seen = count(tmp_path / "o.h5")
        for args in (["run", "case.ini", "-o", "o.h5", "-q", "--force"],
                     ["run", "--restart", "o.h5", "-q"],
                     ["run", "case.ini", "-o", "o.h5.partial", "-q", "--force"]):
            assert_refused(run(args, cwd=tmp_path), a)
        assert a.poll() is None, "the first run stopped"
        assert os.stat(tmp_path / "o.h5").st_ino == inode, "the output was replaced"
    finally:
        code, err = stop(a)
    assert code == 130, (code, err)
    assert_whole(tmp_path / "o.h5", seen + 1)
    assert not (tmp_path / "o.h5.partial").exists()
    assert not (tmp_path / "o.h5.partial.partial").exists()


def test_the_claim_of_a_killed_run_is_taken_over(tmp_path):
    (tmp_path / "case.ini").write_text(LONG)
    a = start(["run", "case.ini", "-o", "o.h5", "-q"], tmp_path)
    assert wait_for(lambda: count(tmp_path / "o.h5") >= 1 or a.poll() is not None, 60)
    code, _ = stop(a, signal.SIGKILL)
    assert code == -signal.SIGKILL
    assert (tmp_path / ".o.h5.lock").exists(), "a killed run cannot remove its lock file"
    short = LONG.replace("end = 1000", "end = 0.04")
    assert short != LONG
    (tmp_path / "short.ini").write_text(short)
    r = run(["run", "short.ini", "-o", "o.h5", "-q", "--force"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert_whole(tmp_path / "o.h5", 3, interrupted=False)
    assert not (tmp_path / ".o.h5.lock").exists()


def test_relax_claims_its_output_too(tmp_path):
    write_cliff(tmp_path / "cliff.asc", 160, 120)
    # relax comes to rest in seconds: paused after substep 60, a few
    # snapshots in, until stopped
    a = start(["relax", "cliff.asc", "-o", "r.h5", "--output-every", "0.02", "-q"], tmp_path,
              pause_step=60)
    try:
        assert wait_for(lambda: count(tmp_path / "r.h5") >= 2 or a.poll() is not None, 60)
        assert a.poll() is None, a.communicate()
        assert_refused(run(["relax", "cliff.asc", "-o", "r.h5", "-q", "--force"],
                           cwd=tmp_path), a)
        assert_refused(run(["run", "--restart", "r.h5", "-q"], cwd=tmp_path), a)
    finally:
        code, err = stop(a)
    assert code == 130, (code, err)
    assert count(tmp_path / "r.h5") >= 2
