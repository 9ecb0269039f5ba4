# SPDX-License-Identifier: BSD-3-Clause
"""setup.py - what pyproject.toml cannot say: the shared library, built by
the project's Makefile, goes into the package.

pip (doc/python.md#install-with-pip) runs setuptools in the checkout, which
runs this file:

  * build_py runs `make lib` (BUILD=build, no sanitizers, no MPI: the
    plain library), incremental like any make, so nothing is compiled when
    build/ is up to date; then it copies build/libsandslide.so.0 (the file
    the link names) to sandslide/libsandslide.so.0, where _native.py looks
    first after SANDSLIDE_LIBRARY.  The installed module needs no checkout,
    no `make install` and no LD_LIBRARY_PATH; it does need the Debian
    packages of the libraries libsandslide links (libhdf5, libpng, libgdal,
    libnlopt, libgomp, ...), which the wheel does not carry.
  * The package holds a binary for this machine, so the wheel is marked
    platform-specific (has_ext_modules); its tag is py3-none-PLATFORM,
    since ctypes loads the library from any Python 3.
  * setuptools' own folders (build/lib*, bdist.*, sandslide.egg-info) go
    to build/setuptools/, inside make's build/ (ignored by git, removed by
    `make clean`), so the checkout is left as it was.

The version is the Makefile's VERSION, the one the library reports.
The environment reaches make as for any build (CFLAGS, GDAL=0, OPENMP=0).
"""
import os
import re
import shutil

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution
from setuptools.errors import ExecError

HERE = os.path.dirname(os.path.abspath(__file__))
SONAME = "libsandslide.so.0"
SETUPTOOLS_BUILD = os.path.join("build", "setuptools")


def version():
    with open(os.path.join(HERE, "Makefile")) as f:
        m = re.search(r"^VERSION\s*:=\s*(\S+)", f.read(), re.M)
    if not m:
        raise RuntimeError("setup.py: no 'VERSION := ...' line in the Makefile")
    return m.group(1)


def make_jobs():
    """-jN for the processors this process may use, or nothing when a make
    above shares its job slots (a jobserver in MAKEFLAGS)."""
    if "jobserver" in os.environ.get("MAKEFLAGS", ""):
        return []
    return [f"-j{len(os.sched_getaffinity(0))}"]


class build_py_with_library(build_py):
    """The Python files, then the library built by make beside them."""

    def run(self):
        cmd = ["make", "-C", HERE, "--no-print-directory", *make_jobs(),
               "BUILD=build", "SANITIZE=0", "MPI=0", "lib"]
        try:
            self.spawn(cmd)
        except ExecError as e:
            raise ExecError(f"{e}: building libsandslide failed (`make deps` installs the "
                            f"Debian packages building needs; README.md#install)") from None
        # the package afresh: a module deleted from python/sandslide must
        # not live on in the wheel from an earlier build
        shutil.rmtree(os.path.join(self.build_lib, "sandslide"), ignore_errors=True)
        super().run()
        self.copy_file(os.path.realpath(os.path.join(HERE, "build", SONAME)),
                       self._library_path(), preserve_mode=True)

    def _library_path(self):
        return os.path.join(self.build_lib, "sandslide", SONAME)

    def get_outputs(self, include_bytecode=True):
        return super().get_outputs(include_bytecode) + [self._library_path()]


class BinaryDistribution(Distribution):
    """A package with a binary in it: platlib, and a platform wheel."""

    def has_ext_modules(self):
        return True


cmdclass = {"build_py": build_py_with_library}
try:
    from wheel.bdist_wheel import bdist_wheel

    class bdist_wheel_py3(bdist_wheel):
        """py3-none-PLATFORM: the platform's, but no Python ABI (ctypes)."""

        def get_tag(self):
            return ("py3", "none", super().get_tag()[2])

    cmdclass["bdist_wheel"] = bdist_wheel_py3
except ImportError:     # no wheel: pip cannot build one anyway
    pass

os.makedirs(os.path.join(HERE, SETUPTOOLS_BUILD), exist_ok=True)
setup(version=version(), distclass=BinaryDistribution, cmdclass=cmdclass,
      options={"build": {"build_base": SETUPTOOLS_BUILD},
               "egg_info": {"egg_base": SETUPTOOLS_BUILD}})
