"""The shared library libsandslide.so.0 through ctypes: finding it, the
prototypes of the functions the module calls, and their status codes as
exceptions.

Only flat functions are called (relax_api.c, run_api.c: options set by
name, arrays and JSON text), never a struct laid out here: the structs'
layouts change between versions of the library, names and strings do not.

The library is looked for in this order, the first that loads wins:
  1. the path in the environment variable SANDSLIDE_LIBRARY (when set, it
     must load: a wrong path is an error, not a reason to try others);
  2. libsandslide.so.0 beside this file: the copy a wheel carries
     (`pip install .`, setup.py);
  3. _library.PATH, written by `make install` beside this file;
  4. the build tree of a checkout: ../../build/libsandslide.so.0 from
     this folder (PYTHONPATH=python);
  5. ctypes.util.find_library("sandslide") (the loader's paths).
"""
import ctypes
import ctypes.util
import os
import threading

SONAME = "libsandslide.so.0"

# The library's status codes (error.h).
SS_OK = 0
SS_ERR_FAIL = -1
SS_ERR_INPUT = -2


class Error(Exception):
    """A failure the sandslide library reported; str() is its message."""


class InputError(Error, ValueError):
    """Input the library refuses (SS_ERR_INPUT; the CLI's exit status 2)."""


class RunError(Error, RuntimeError):
    """A failure while running (SS_ERR_FAIL; the CLI's exit status 1)."""


def _candidates():
    """(description, path or name) in the order they are tried."""
    here = os.path.dirname(os.path.abspath(__file__))
    out = [("the wheel's copy (pip install)", os.path.join(here, SONAME))]
    try:
        from . import _library
        out.append(("_library.PATH (make install)", _library.PATH))
    except ImportError:
        out.append(("_library.PATH (make install)", None))
    out.append(("the build tree", os.path.normpath(os.path.join(here, "..", "..", "build",
                                                                SONAME))))
    out.append(('ctypes.util.find_library("sandslide")', ctypes.util.find_library("sandslide")))
    return out


def _load():
    """The loaded library; ImportError saying what was tried."""
    env = os.environ.get("SANDSLIDE_LIBRARY")
    if env:
        try:
            return ctypes.CDLL(env)
        except OSError as e:
            raise ImportError(f"sandslide: cannot load the library that SANDSLIDE_LIBRARY "
                              f"names, {env!r}: {e}") from None
    tried = ["SANDSLIDE_LIBRARY (not set)"]
    for what, path in _candidates():
        if not path:
            tried.append(f"{what} (none)")
            continue
        if os.path.isabs(path) and not os.path.exists(path):
            tried.append(f"{what}: {path} (no such file)")
            continue
        try:
            return ctypes.CDLL(path)
        except OSError as e:
            tried.append(f"{what}: {path} ({e})")
    raise ImportError("sandslide: cannot find the library " + SONAME + "; tried " +
                      "; ".join(tried) + ".  Build it with `make`, install it with "
                      "`make install`, or set SANDSLIDE_LIBRARY to its path")


lib = _load()

# What the module calls, with the types of relax.h, run.h, fit.h, error.h
# and version.h.  A library older than this module lacks some of them.
_P, _S, _I, _D, _Z = ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_double, \
    ctypes.c_size_t
_PROTOTYPES = {
    "ss_version": (_S, []),
    "ss_error_set_quiet": (None, [_I]),
    "ss_error_last_message": (_S, []),
    "ss_relax_options_create": (_P, []),
    "ss_relax_options_destroy": (None, [_P]),
    "ss_relax_options_set": (_I, [_P, _S, _S]),
    "ss_relax_heights": (_I, [_P, _I, _I, _D, _D, _P, _P, _P, _P, _Z]),
    "ss_run_options_create": (_P, []),
    "ss_run_options_destroy": (None, [_P]),
    "ss_run_options_set": (_I, [_P, _S, _S]),
    "ss_run_case_json": (_I, [_P, _P, _Z]),
    "ss_option_table_json": (_I, [_P, _P, _Z]),
    "ss_fit_options_create": (_P, []),
    "ss_fit_options_destroy": (None, [_P]),
    "ss_fit_options_set": (_I, [_P, _S, _S]),
    "ss_fit_run_json": (_I, [_P, _P, _Z]),
}
for _name, (_res, _args) in _PROTOTYPES.items():
    try:
        _f = getattr(lib, _name)
    except AttributeError:
        raise ImportError(f"sandslide: the library {lib._name} has no {_name}: it is older "
                          f"than this module (rebuild it with `make`)") from None
    _f.restype = _res
    _f.argtypes = _args

# Messages become exceptions: the library must not print them too.
lib.ss_error_set_quiet(1)

# The library keeps its last message, and OpenMP its thread count, per
# process: one call at a time, whatever the Python threads do.
lock = threading.Lock()


def option_table(command):
    """The address of the library's option table of command (option.h:
    the tables are data, ss_COMMAND_option_table)."""
    try:
        return ctypes.addressof(ctypes.c_char.in_dll(lib, f"ss_{command}_option_table"))
    except ValueError:
        raise ValueError(f"sandslide: no options of a command {command!r}: expected relax, "
                         f"run or fit") from None


def last_message():
    m = lib.ss_error_last_message()
    return m.decode("utf-8", "replace") if m else ""


def check(status):
    """Raise the exception for a status of the library (its message)."""
    if status == SS_OK:
        return
    cls = InputError if status == SS_ERR_INPUT else RunError
    raise cls(last_message() or f"sandslide: the library returned status {status}")


class Options:
    """Heap options of the library (relax, run or fit), destroyed on exit."""

    def __init__(self, kind):
        self._create = getattr(lib, f"ss_{kind}_options_create")
        self._destroy = getattr(lib, f"ss_{kind}_options_destroy")
        self._set = getattr(lib, f"ss_{kind}_options_set")
        self.ptr = None

    def __enter__(self):
        self.ptr = self._create()
        if not self.ptr:
            check(SS_ERR_FAIL)
        return self

    def __exit__(self, *exc):
        self._destroy(self.ptr)
        self.ptr = None

    def set(self, key, word):
        check(self._set(self.ptr, key.encode(), os.fsencode(word)))
