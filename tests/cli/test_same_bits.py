# SPDX-License-Identifier: BSD-3-Clause
"""The same bits as before a refactor (issue 34, "one job, one concern per
file"): the commit before it, f9026b5, is built from this checkout's
history in a git worktree (under the build folder, kept between runs), and
tools/same_bits.py --quick compares what both builds write: the door, the
cone and the DEM case, relax of cases/dem/terrain.asc with its report, a
fit twin's report and the Python relax of README.md.  The full comparison
(every case on every kernel, integrator and thread count, the MPI builds)
is tools/same_bits.py without --quick.

Skipped where the checkout has no history holding f9026b5 (a tarball) or
no git, and for a sanitized build (a plain build of the old tree is what
is compared; the sanitized suite runs the same code paths elsewhere).
"""
import os
import shutil
import subprocess

import pytest

from conftest import ROOT, SANDSLIDE

REFERENCE = "f9026b5"
BUILD = os.path.dirname(SANDSLIDE)
HERE_BUILD = os.path.join(BUILD, f"same-bits-{REFERENCE}")


def git(*args, **kw):
    return subprocess.run(["git", "-C", ROOT, *args], capture_output=True, text=True, **kw)


@pytest.fixture(scope="module")
def reference_build():
    if "SANITIZE=1" in os.environ.get("SANDSLIDE_MAKEFLAGS", ""):
        pytest.skip("a sanitized build: the comparison runs in the plain `make test`")
    if not shutil.which("git") or git("cat-file", "-e", f"{REFERENCE}^{{commit}}").returncode:
        pytest.skip(f"no git history holding {REFERENCE} in this checkout")
    tree = HERE_BUILD
    binary = os.path.join(tree, "build", "sandslide")
    if not os.access(binary, os.X_OK):
        if os.path.isdir(tree):
            git("worktree", "remove", "--force", tree)
            shutil.rmtree(tree, ignore_errors=True)
        git("worktree", "prune")
        r = git("worktree", "add", "--detach", tree, REFERENCE)
        assert r.returncode == 0, f"git worktree add {REFERENCE}: {r.stderr}"
        env = dict(os.environ)
        env.pop("MAKEFLAGS", None)   # not the -j of the parent make
        r = subprocess.run(["make", "-j2", "all"], cwd=tree, env=env, capture_output=True,
                           text=True, timeout=1800)
        assert r.returncode == 0, f"building {REFERENCE} failed:\n{r.stdout[-3000:]}{r.stderr}"
    return os.path.join(tree, "build")


def test_the_same_bits_as_before_the_refactor(reference_build):
    r = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "tools", "same_bits.py"),
                        reference_build, BUILD, "--quick"], capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, f"{REFERENCE} and this build differ:\n{r.stdout}\n{r.stderr}"
    assert "0 differ" in r.stdout, r.stdout
