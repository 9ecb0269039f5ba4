# SPDX-License-Identifier: BSD-3-Clause
"""make install into a temporary DESTDIR, and a C program built against it.

What a user who installs sandslide gets: the program, the shared library
with its soname and the static one, the headers with the umbrella
sandslide/sandslide.h, sandslide.pc, the man page (the one make built),
the example cases and the Python module, all under PREFIX; and `make
uninstall` takes them away again.  tests/install/relax_dem.c is built with
`pkg-config --cflags --libs sandslide` from the staged tree (pkg-config's
prefix pointed at it) and relaxes a small DEM, against the shared library
and against the static one.

`make test` passes the build's settings (SANDSLIDE_MAKEFLAGS, SANDSLIDE_CC,
SANDSLIDE_LDFLAGS, and SANDSLIDE_PY_PRELOAD: the sanitizers' run-time
libraries python3 must load first) so that the sanitized and MPI suites
install their own build; run alone, the test installs build/.
"""
import os
import re
import shlex
import shutil
import subprocess

import pytest

from conftest import ROOT, asc_text

PREFIX = "/opt/sandslide-test"
MAKEFLAGS = shlex.split(os.environ.get("SANDSLIDE_MAKEFLAGS", ""))
CC = os.environ.get("SANDSLIDE_CC", "cc")
LDFLAGS = shlex.split(os.environ.get("SANDSLIDE_LDFLAGS", ""))


def make(*goals, destdir):
    env = dict(os.environ)
    env.pop("MAKEFLAGS", None)       # not the -j of a parent make
    env.pop("MAKELEVEL", None)
    r = subprocess.run(["make", "--no-print-directory", *MAKEFLAGS, *goals,
                        "DESTDIR=" + str(destdir), "PREFIX=" + PREFIX],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"make {' '.join(goals)} failed:\n{r.stdout}\n{r.stderr}"
    return r.stdout


def version():
    text = open(os.path.join(ROOT, "Makefile")).read()
    return re.search(r"^VERSION\s*:=\s*(\S+)", text, re.M).group(1)


@pytest.fixture(scope="module")
def staged(tmp_path_factory):
    destdir = tmp_path_factory.mktemp("destdir")
    make("install", destdir=destdir)
    return destdir, str(destdir) + PREFIX


def pkg_config(root, *args):
    env = dict(os.environ, PKG_CONFIG_PATH=os.path.join(root, "lib", "pkgconfig"))
    r = subprocess.run(["pkg-config", "--define-variable=prefix=" + root, *args,
                        "sandslide"], env=env, capture_output=True, text=True)
    assert r.returncode == 0, f"pkg-config {' '.join(args)} sandslide: {r.stderr}"
    return shlex.split(r.stdout)


def test_every_part_is_installed(staged):
    _, root = staged
    v = version()
    expect = ["bin/sandslide", f"lib/libsandslide.so.{v}", "lib/libsandslide.a",
              "include/sandslide/sandslide.h", "include/sandslide/version.h",
              "include/sandslide/relax.h", "lib/pkgconfig/sandslide.pc",
              "share/man/man1/sandslide.1", "share/sandslide/cases/door.ini",
              "share/sandslide/cases/dem/terrain.asc"]
    for rel in expect:
        assert os.path.isfile(os.path.join(root, rel)), f"make install did not install {rel}"
    headers = sorted(os.listdir(os.path.join(ROOT, "include", "sandslide")))
    assert sorted(os.listdir(os.path.join(root, "include", "sandslide"))) == headers, \
        "the installed headers differ from include/sandslide/"
    # the soname and the two links
    assert os.readlink(os.path.join(root, "lib", "libsandslide.so")) == "libsandslide.so.0"
    assert os.readlink(os.path.join(root, "lib", "libsandslide.so.0")) == f"libsandslide.so.{v}"
    dyn = subprocess.run(["readelf", "-d", os.path.join(root, "lib", f"libsandslide.so.{v}")],
                         capture_output=True, text=True).stdout
    assert "Library soname: [libsandslide.so.0]" in dyn, f"soname missing:\n{dyn}"
    # the umbrella header includes every other public header
    umbrella = open(os.path.join(root, "include", "sandslide", "sandslide.h")).read()
    for h in headers:
        if h != "sandslide.h":
            assert f'#include "sandslide/{h}"' in umbrella, f"sandslide.h does not include {h}"
    # the installed program runs and says the version
    out = subprocess.run([os.path.join(root, "bin", "sandslide"), "--version"],
                         capture_output=True, text=True).stdout
    assert out.startswith(f"sandslide {v} "), out


def test_pkg_config_file(staged):
    _, root = staged
    assert pkg_config(root, "--modversion") == [version()]
    cflags = pkg_config(root, "--cflags")
    assert "-I" + root + "/include" in cflags, cflags
    libs = pkg_config(root, "--libs")
    assert libs[:2] == ["-L" + root + "/lib", "-lsandslide"], libs
    static = pkg_config(root, "--static", "--libs")
    assert "-lhdf5_hl" in static and "-lm" in static, static


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    """A small DEM with faces steeper than 35 deg, not symmetric (the
    installed terrain.asc takes 27513 steps: minutes under the sanitizers)."""
    rows = [[(3.0 if 4 <= i < 9 and 3 <= j < 7 else 0.0) + 0.05 * i for i in range(24)]
            for j in range(18)]
    path = tmp_path_factory.mktemp("dem") / "block.asc"
    path.write_text(asc_text(rows, cellsize=1.0))
    return str(path)


def build_and_run(root, tmp_path, name, libs, env_extra, dem):
    exe = tmp_path / name
    cflags = pkg_config(root, "--cflags")
    src = os.path.join(ROOT, "tests", "install", "relax_dem.c")
    r = subprocess.run([CC, "-std=c11", "-Wall", "-Wextra", "-Werror", src, *cflags, *libs,
                        "-lm", *LDFLAGS, "-o", str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, f"building {name} against the installed tree failed:\n{r.stderr}"
    out = tmp_path / (name + ".asc")
    r = subprocess.run([str(exe), version(), dem, str(out)], env=dict(os.environ, **env_extra),
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.rstrip().endswith("6 passed, 0 failed"), \
        f"{name} failed:\n{r.stdout}\n{r.stderr}"
    return exe, out


def test_program_against_shared_library(staged, tmp_path, dem):
    _, root = staged
    libdir = os.path.join(root, "lib")
    exe, out = build_and_run(root, tmp_path, "relax_shared", pkg_config(root, "--libs"),
                             {"LD_LIBRARY_PATH": libdir}, dem)
    ldd = subprocess.run(["ldd", str(exe)], env=dict(os.environ, LD_LIBRARY_PATH=libdir),
                         capture_output=True, text=True).stdout
    assert os.path.join(libdir, "libsandslide.so.0") in ldd, \
        f"the program does not load the installed shared library:\n{ldd}"
    # the same bits as the installed command line on the same DEM
    cli = tmp_path / "cli.asc"
    subprocess.run([os.path.join(root, "bin", "sandslide"), "relax", dem, "-o", str(cli),
                    "--threads", "1", "-q"], check=True)
    assert open(out).read() == open(cli).read(), "library and CLI relax differ"


def test_program_against_static_library(staged, tmp_path, dem):
    _, root = staged
    libs = [os.path.join(root, "lib", "libsandslide.a") if a == "-lsandslide" else a
            for a in pkg_config(root, "--static", "--libs")]
    exe, _ = build_and_run(root, tmp_path, "relax_static", libs, {}, dem)
    ldd = subprocess.run(["ldd", str(exe)], capture_output=True, text=True).stdout
    assert "libsandslide" not in ldd, f"linked the shared library:\n{ldd}"


def test_python_module_finds_the_installed_library(tmp_path):
    """Installed without DESTDIR under a prefix of its own, the Python
    module loads the library make install told it of (no
    SANDSLIDE_LIBRARY) and relaxes a ramp."""
    prefix = tmp_path / "prefix"
    env = dict(os.environ)
    env.pop("MAKEFLAGS", None)
    env.pop("MAKELEVEL", None)
    r = subprocess.run(["make", "--no-print-directory", *MAKEFLAGS, "install",
                        "PREFIX=" + str(prefix)], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    found = [d for d, _, files in os.walk(prefix / "lib") if "_library.py" in files]
    assert len(found) == 1, f"the module is not installed once under {prefix}/lib: {found}"
    pythondir = os.path.dirname(found[0])
    env.pop("SANDSLIDE_LIBRARY", None)
    if os.environ.get("SANDSLIDE_PY_PRELOAD"):   # a sanitized library (make SANITIZE=1)
        env.update(LD_PRELOAD=os.environ["SANDSLIDE_PY_PRELOAD"],
                   ASAN_OPTIONS="detect_leaks=0:exitcode=86")
    code = ("import numpy as np, sandslide\n"
            "h = np.add.outer(np.zeros(8), np.arange(12.0))  # a 45 deg ramp\n"
            "r, rep = sandslide.relax(h, dx=1.0, threads=1)\n"
            "from sandslide import _native\n"
            "print(sandslide.__file__, _native.lib._name, rep['steady'], "
            "rep['max_slope_after_deg'])\n")
    r = subprocess.run(["/usr/bin/python3", "-c", code], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120, env=dict(env, PYTHONPATH=pythondir))
    assert r.returncode == 0, f"the installed module failed:\n{r.stderr}"
    words = r.stdout.split()
    assert words[0].startswith(pythondir), f"imported {words[0]}, not the installed module"
    assert words[1] == str(prefix / "lib" / "libsandslide.so.0"), \
        f"loaded {words[1]}, not the installed library"
    assert words[-2] == "True" and float(words[-1]) <= 35.0 + 1e-6, r.stdout
    with open(os.path.join(found[0], "_library.py")) as f:
        assert str(prefix / "lib" / "libsandslide.so.0") in f.read()


def test_man_page_renders(staged):
    _, root = staged
    page = os.path.join(root, "share", "man", "man1", "sandslide.1")
    # the page make built from doc/sandslide.1.in and the option tables
    build = next((f[6:] for f in MAKEFLAGS if f.startswith("BUILD=")), "build")
    with open(page) as installed, open(os.path.join(ROOT, build, "sandslide.1")) as built:
        assert installed.read() == built.read(), \
            f"make install did not install {build}/sandslide.1 as the man page"
    if not shutil.which("man"):
        pytest.skip("man is not installed (make deps-test installs man-db)")
    r = subprocess.run(["man", "-l", page], capture_output=True, text=True,
                       env=dict(os.environ, MANWIDTH="80"))
    assert r.returncode == 0 and "relax" in r.stdout, r.stderr


def test_uninstall_removes_everything(tmp_path):
    make("install", destdir=tmp_path)
    make("uninstall", destdir=tmp_path)
    left = [os.path.join(d, f) for d, _, files in os.walk(tmp_path) for f in files]
    left += [os.path.join(d, s) for d, dirs, _ in os.walk(tmp_path) for s in dirs
             if os.path.islink(os.path.join(d, s))]
    assert not left, f"make uninstall left {left}"
