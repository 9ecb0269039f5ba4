# SPDX-License-Identifier: BSD-3-Clause
"""pip install . into a fresh virtual environment, and the module it installs.

Issue 27, item 5: in a virtual environment made as doc/python.md says
(`--system-site-packages`: Debian's numpy), `python -m pip install
--no-build-isolation --no-index CHECKOUT` with Debian's build tools and no
network installs a module that stands on its own.  Imported from outside
the checkout, without SANDSLIDE_LIBRARY, PYTHONPATH or LD_LIBRARY_PATH,
it is the venv's and maps the venv's copy of the library and no other;
relax gives the same bits as the checkout's module over
build/libsandslide.so.0; the wheel is for this platform, not
py3-none-any.  The install leaves the checkout as it was (setuptools'
folders go to build/setuptools/), and `pip uninstall -y sandslide`
leaves nothing of it in the venv.

pip (23) builds in the checkout itself, not in a copy: setup.py's `make
lib` finds build/ up to date and compiles nothing, so the test takes
about 12 s (5 s of them the venv's own pip) once `make` has run; on a
checkout never built it first builds the library (about a minute on
2 cores).  pip runs with no configuration file and no cache, so neither
the user's settings nor an old wheel get in.  Skipped, saying why, when
venv, pip, setuptools or wheel are missing (`make deps-test` installs
python3-venv, python3-pip, python3-setuptools, python3-wheel).
"""
import importlib.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SONAME = "libsandslide.so.0"
BUILD_LIB = os.path.join(ROOT, "build", SONAME)
# What a stray setuptools build would leave in the checkout.
STRAYS = ["python/sandslide.egg-info", "sandslide.egg-info", "build/lib",
          "build/bdist.linux-x86_64", "python/build"]

# Run in a fresh process: relax a small DEM that is not symmetric, save
# the result, and say which module and which library files are in use.
PROBE = r"""
import json, sys
import numpy as np
import sandslide
r, c = np.mgrid[0:18, 0:23]
dem = 0.1 * (17 - r) + np.where((abs(c - 14) < 4) & (abs(r - 5) < 3), 3.0, 0.0)
relaxed, report = sandslide.relax(dem, dx=1.0, threads=1)
np.save(sys.argv[1], relaxed)
with open("/proc/self/maps") as f:
    maps = sorted({l.split()[-1] for l in f if "libsandslide" in l})
print(json.dumps({"file": sandslide.__file__, "library": sandslide._native.lib._name,
                  "maps": maps, "steps": report["steps"]}))
"""


def clean_env(**extra):
    """The environment with nothing that points at the checkout or its
    build, and no parent make's flags or sanitizer preloads."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("SANDSLIDE_LIBRARY", "PYTHONPATH", "PYTHONHOME", "LD_LIBRARY_PATH",
                        "LD_PRELOAD", "ASAN_OPTIONS", "UBSAN_OPTIONS", "MAKEFLAGS", "MFLAGS",
                        "MAKELEVEL")
           and not k.startswith("PIP_")}
    env.update(PIP_CONFIG_FILE=os.devnull, PIP_DISABLE_PIP_VERSION_CHECK="1",
               PYTHONNOUSERSITE="1", **extra)
    return env


def run(cmd, cwd, env, what, timeout=600):
    r = subprocess.run([str(a) for a in cmd], cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=timeout)
    assert r.returncode == 0, f"{what} failed (exit {r.returncode}):\n{r.stdout}\n{r.stderr}"
    return r.stdout


def checkout_state():
    """git's view of the checkout, ignored files included (None: no git)."""
    try:
        r = subprocess.run(["git", "status", "--porcelain", "--ignored"], cwd=ROOT,
                           capture_output=True, text=True, timeout=60)
    except OSError:
        return None
    return r.stdout if r.returncode == 0 else None


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    """(venv folder, its python, its site-packages, checkout state before
    and after the install) after pip install of the checkout."""
    missing = [m for m in ("venv", "pip", "setuptools", "wheel")
               if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(f"{sys.executable} lacks {', '.join(missing)}: install Debian packages "
                    f"python3-venv python3-pip python3-setuptools python3-wheel "
                    f"(make deps-test)")
    tmp = tmp_path_factory.mktemp("pip")
    venv = tmp / "venv"
    r = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", venv],
                       cwd=tmp, env=clean_env(), capture_output=True, text=True, timeout=300)
    if r.returncode != 0 and "ensurepip" in r.stdout + r.stderr:
        pytest.skip(f"{sys.executable} -m venv cannot put pip into a venv (no ensurepip): "
                    f"install Debian package python3-venv")
    assert r.returncode == 0, f"python -m venv failed:\n{r.stdout}\n{r.stderr}"
    python = venv / "bin" / "python"
    site = run([python, "-c", "import sysconfig; print(sysconfig.get_path('platlib'))"], tmp,
               clean_env(), "asking the venv's python for its site-packages").strip()
    assert site.startswith(str(venv)), f"the venv's site-packages {site} is not in {venv}"
    strays_before = [s for s in STRAYS if os.path.exists(os.path.join(ROOT, s))]
    before = checkout_state()
    run([python, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir",
         ROOT], tmp, clean_env(), "pip install --no-build-isolation --no-index CHECKOUT")
    return {"venv": str(venv), "python": str(python), "site": site, "tmp": tmp,
            "before": before, "after": checkout_state(), "strays_before": strays_before}


def probe(python, tmp, env, name):
    """Run PROBE in a fresh process in tmp: (what it says, the relaxed array)."""
    out = tmp / f"{name}.npy"
    said = json.loads(run([python, "-c", PROBE, out], tmp, env, f"import and relax ({name})"))
    return said, np.load(out)


def test_install_leaves_the_checkout_as_it_was(venv):
    new = [s for s in STRAYS if os.path.exists(os.path.join(ROOT, s))
           and s not in venv["strays_before"]]
    assert not new, f"pip install left {', '.join(new)} in the checkout (setup.py sends " \
                    f"setuptools' folders to build/setuptools/)"
    if venv["before"] is not None:
        assert venv["after"] == venv["before"], \
            f"pip install changed the checkout (git status --ignored):\nbefore:\n" \
            f"{venv['before']}\nafter:\n{venv['after']}"


def test_the_wheel_is_for_this_platform(venv):
    dist = [d for d in os.listdir(venv["site"]) if d.startswith("sandslide-")
            and d.endswith(".dist-info")]
    assert len(dist) == 1, f"expected one sandslide-*.dist-info in the venv, found {dist}"
    with open(os.path.join(venv["site"], dist[0], "WHEEL")) as f:
        wheel = f.read()
    assert "Root-Is-Purelib: false" in wheel, f"the wheel is marked pure Python:\n{wheel}"
    tags = [line.split(":", 1)[1].strip() for line in wheel.splitlines()
            if line.startswith("Tag:")]
    assert tags and all(not t.endswith("-any") for t in tags), \
        f"the wheel carries a binary but its tags {tags} claim any platform"
    lib = os.path.join(venv["site"], "sandslide", SONAME)
    assert os.path.isfile(lib) and not os.path.islink(lib), \
        f"the wheel did not put the library into the package as a file: {lib}"
    with open(os.path.join(venv["site"], dist[0], "RECORD")) as f:
        held = sorted(line.split(",")[0] for line in f
                      if line.startswith("sandslide/") and "__pycache__" not in line)
    expect = sorted([f"sandslide/{n}" for n in os.listdir(os.path.join(ROOT, "python", "sandslide"))
                     if n.endswith(".py")] + [f"sandslide/{SONAME}"])
    assert held == expect, f"the wheel holds {held}, expected the checkout's module and " \
                           f"the library: {expect}"


def test_the_installed_module_stands_on_its_own(venv):
    """From outside the checkout, with no path to it in the environment:
    the venv's module and the venv's library, and relax gives the bits of
    the checkout's module over build/libsandslide.so.0."""
    tmp = venv["tmp"]
    said, relaxed = probe(venv["python"], tmp, clean_env(), "venv")
    pkg = os.path.join(venv["site"], "sandslide")
    assert os.path.dirname(said["file"]) == pkg, \
        f"import sandslide found {said['file']}, not the venv's package in {pkg}"
    lib = os.path.join(pkg, SONAME)
    assert said["library"] == lib, \
        f"the installed module loaded {said['library']}, not the wheel's copy {lib}"
    assert said["maps"] == [os.path.realpath(lib)], \
        f"the process maps {said['maps']}, expected the wheel's copy {lib} alone"

    ref, expect = probe(sys.executable, tmp,
                        clean_env(PYTHONPATH=os.path.join(ROOT, "python"),
                                  SANDSLIDE_LIBRARY=BUILD_LIB), "checkout")
    assert ref["maps"] == [os.path.realpath(BUILD_LIB)], \
        f"the reference run maps {ref['maps']}, not the checkout's {BUILD_LIB}"
    assert relaxed.shape == expect.shape and \
        np.array_equal(relaxed.view(np.uint64), expect.view(np.uint64)), \
        f"relax through the installed module differs from the checkout's build " \
        f"(largest difference {np.nanmax(np.abs(relaxed - expect))})"
    assert said["steps"] == ref["steps"], \
        f"relax took {said['steps']} steps installed, {ref['steps']} from the checkout"


def test_uninstall_leaves_nothing(venv):
    tmp = venv["tmp"]
    run([venv["python"], "-m", "pip", "uninstall", "-y", "sandslide"], tmp, clean_env(),
        "pip uninstall -y sandslide")
    left = [os.path.join(d, n) for d, dirs, files in os.walk(venv["venv"])
            for n in dirs + files if "sandslide" in n.lower()]
    assert not left, f"pip uninstall left in the venv: {left}"
    spec = run([venv["python"], "-c", "import importlib.util as u; "
                "s = u.find_spec('sandslide'); print(s.origin if s else '')"],
               tmp, clean_env(), "looking for sandslide after the uninstall").strip()
    assert not spec.startswith(venv["venv"]), \
        f"after pip uninstall the venv's python still imports sandslide from {spec}"
