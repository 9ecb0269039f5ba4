# SPDX-License-Identifier: BSD-3-Clause
"""The shared library libsandslide.so.0 through ctypes: finding it, the
prototypes of the functions the module calls, and their status codes as
exceptions.

Only flat functions are called (relax_api.c, run_api.c: options set by
name, arrays and JSON text; watch.h: a call's stop flag and progress),
never a struct laid out here: the structs' layouts change between versions
of the library, names and strings do not.  call() runs a long call in a
worker thread so that Ctrl-C stops it, with an optional progress line.

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
import math
import os
import re
import sys
import threading
import time

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


# Their public names: a traceback, repr() and pickle say sandslide.InputError,
# the name the user catches, not the private module that defines them.
for _cls in (Error, InputError, RunError):
    _cls.__module__ = "sandslide"


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


def _passive_wait_by_default():
    """OMP_WAIT_POLICY=passive unless OMP_WAIT_POLICY or GOMP_SPINCOUNT is
    set: OpenMP threads that spin at every barrier (libgomp's default, about
    3 ms) lose their core to any other process and slow a call down up to
    tenfold on a busy machine (doc/running.md#threads).  libgomp reads the
    variables once, when it is loaded, which is with the library below
    unless something in this process loaded it first (then that first
    reading stays)."""
    if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
        os.environ["OMP_WAIT_POLICY"] = "passive"


_passive_wait_by_default()
lib = _load()

# What the module calls, with the types of relax.h, run.h, fit.h, error.h
# and version.h.  A library older than this module lacks some of them.
_P, _S, _I, _D, _Z = ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_double, \
    ctypes.c_size_t
_PROTOTYPES = {
    "ss_version": (_S, []),
    "ss_error_set_quiet": (None, [_I]),
    "ss_error_last_message": (_S, []),
    "ss_option_object_create": (_P, [_P]),
    "ss_option_object_destroy": (None, [_P]),
    "ss_option_object_set": (_I, [_P, _S, _S]),
    "ss_option_table_json": (_I, [_P, _P, _Z]),
    "ss_job_of": (_P, [_P, _P]),
    "ss_job_set_watch": (None, [_P, _P]),
    "ss_relax_heights": (_I, [_P, _I, _I, _D, _D, _P, _P, _P, _P, _Z]),
    "ss_relax_heights_angles": (_I, [_P, _I, _I, _D, _D, _P, _P, _P, _P, _P, _Z]),
    "ss_run_case_json": (_I, [_P, _P, _Z]),
    "ss_fit_run_json": (_I, [_P, _P, _Z]),
    "ss_relax_file_json": (_I, [_P, _P, _Z]),
    "ss_watch_create": (_P, []),
    "ss_watch_destroy": (None, [_P]),
    "ss_watch_stop": (None, [_P]),
    "ss_watch_read": (ctypes.c_longlong, [_P, _P, _P, _P, _P, _P]),
    "ss_snapshot_threadsafe": (_I, []),
    "ss_snapshot_read_summary": (_I, [_S, _P]),
    "ss_snapshot_summary_release": (None, [_P]),
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

# Calls on different data may run at the same time in different threads:
# the library keeps its last message per thread (error.c) and sets OpenMP's
# thread count per call in the calling thread (parallel.h).  HDF5 is the
# exception when it was not built thread-safe: then the calls that touch it
# (run, fit, an .h5 DEM or output) take this lock, one at a time.
HDF5_THREADSAFE = bool(lib.ss_snapshot_threadsafe())
hdf5_lock = threading.Lock()


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


def check(status, message=None, keywords=None):
    """Raise the exception for a status of the library: its message (the
    calling thread's last, unless given), with the command line's flags
    named as keywords (keywords: translate_message's)."""
    if status == SS_OK:
        return
    cls = InputError if status == SS_ERR_INPUT else RunError
    message = last_message() if message is None else message
    if keywords is not None:
        message = translate_message(message, keywords)
    raise cls(message or f"sandslide: the library returned status {status}")


def explain_output(path):
    """Raise the InputError `sandslide info PATH` would print, if the
    library finds PATH is not a readable sandslide output (damaged, not
    HDF5, not sandslide's); return quietly if it reads it."""
    # struct ss_snapshot_summary is read and released in place; its size
    # (under 1 KiB, snapshot.h) is well inside the buffer
    summary = ctypes.create_string_buffer(4096)
    locked = not HDF5_THREADSAFE
    if locked:
        hdf5_lock.acquire()
    try:
        status = lib.ss_snapshot_read_summary(os.fsencode(path), summary)
    finally:
        if locked:
            hdf5_lock.release()
    if status == SS_OK:
        lib.ss_snapshot_summary_release(summary)
        return
    check(status)


def translate_message(message, keywords):
    """The library's message with the command line's words made Python's.

    keywords maps an option name of the library ("tile", "force",
    "rkl2-tol", "output") to (python_keyword, is_flag), for the keywords of
    the function called.  A flag --force becomes force=True, an option
    --rkl2-tol becomes rkl2_tol=, and a message that starts with an
    option's name and its quoted value, as options set by name are refused
    ("tile '0x3': expected ..."), starts with the keyword, tile='0x3'.
    Flags that are not keywords of the function are left as they are."""
    def keyword(name):
        return keywords.get(name) or keywords.get(name.replace("_", "-"))

    def flag(m):
        k = keyword(m.group(1))
        if k is None:
            return m.group(0)
        return f"{k[0]}=True{m.group(2) or ''}" if k[1] else f"{k[0]}="

    if "restart" not in keywords:   # a hint for the command line only
        message = re.sub(r", or --restart \S+ to continue that run", "", message)
    m = re.match(r"([a-z][a-z0-9_-]*) '", message)
    if m and keyword(m.group(1)) is not None:
        message = keyword(m.group(1))[0] + "=" + message[m.end(1) + 1:]
    return re.sub(r"(?<![\w-])--([a-z][a-z0-9-]*)(=| (?=\S))?", flag, message)


class Options:
    """Heap options of the library (relax, run or fit: an options object of
    the command's table, option.h), destroyed on exit."""

    def __init__(self, kind, keywords=None):
        self.keywords = keywords   # the messages' keywords (translate_message)
        self.table = option_table(kind)
        self.ptr = None

    def __enter__(self):
        self.ptr = lib.ss_option_object_create(self.table)
        if not self.ptr:
            check(SS_ERR_FAIL)
        return self

    def __exit__(self, *exc):
        lib.ss_option_object_destroy(self.ptr)
        self.ptr = None

    def set(self, key, word):
        check(lib.ss_option_object_set(self.ptr, key.encode(), os.fsencode(word)),
              keywords=self.keywords)

    def watch(self, watch):
        """Attach watch (a Watch; None: detach) to the options' job (job.h)."""
        lib.ss_job_set_watch(lib.ss_job_of(self.table, self.ptr),
                             watch.ptr if watch is not None else None)


class Watch:
    """A watch of the library (watch.h): the stop flag and the last
    progress of one call, written by the thread running it."""

    def __init__(self):
        self.ptr = lib.ss_watch_create()
        if not self.ptr:
            check(SS_ERR_FAIL)

    def close(self):
        lib.ss_watch_destroy(self.ptr)
        self.ptr = None

    def stop(self):
        lib.ss_watch_stop(self.ptr)

    def read(self):
        """(reports, time s, end s, steps, fraction 0..1 or NaN, runs)."""
        t, e, f = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
        st, r = ctypes.c_longlong(), ctypes.c_longlong()
        n = lib.ss_watch_read(self.ptr, ctypes.byref(t), ctypes.byref(e), ctypes.byref(st),
                              ctypes.byref(f), ctypes.byref(r))
        return n, t.value, e.value, st.value, f.value, r.value


class Progress:
    """A progress line for a call: tqdm's bar when tqdm can be imported,
    else one line on stderr rewritten in place ("\\r"), four times a second
    at most.  update() from the thread that waits; close() always (it ends
    the line, also on an interrupt or an error)."""

    def __init__(self, what):
        self.what = what
        self.bar = None
        self.shown = False
        self.last = 0.0
        try:
            from tqdm import tqdm
        except ImportError:
            tqdm = None
        if tqdm is not None:
            self.bar = tqdm(total=100, desc=what, unit="%", leave=True,
                            bar_format="{l_bar}{bar}| {elapsed}<{remaining}{postfix}")

    @staticmethod
    def _detail(t, e, steps, runs):
        if runs:
            return f"{runs} forward runs"
        if math.isnan(t):
            return ""
        end = f" / {e:.6g} s" if math.isfinite(e) else " s (until steady)"
        return f"t = {t:.6g}{end}, {steps} steps"

    def update(self, reading, last=False):
        """Show reading (Watch.read); last: the call's final one, shown
        whatever the time since the line before."""
        n, t, e, steps, f, runs = reading
        if last:
            f = 1.0   # done, whatever the estimate said
        if n == 0:
            return
        detail = self._detail(t, e, steps, runs)
        if self.bar is not None:
            if not math.isnan(f):
                self.bar.n = round(100 * f, 1)
            self.bar.set_postfix_str(detail, refresh=False)
            self.bar.refresh()
            return
        now = time.monotonic()
        if now - self.last < 0.25 and not last:
            return
        self.last = now
        pct = "   ?%" if math.isnan(f) else f"{100 * f:4.0f}%"
        sys.stderr.write(f"\r{self.what}: {pct}  {detail}   ")
        sys.stderr.flush()
        self.shown = True

    def close(self):
        if self.bar is not None:
            self.bar.close()
        elif self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()


def call(options, function, args, *, progress=None, keywords=None, hdf5=False):
    """function(*args), a call of the library that returns a status, in a
    worker thread with a watch attached to the job of options (an Options),
    while this thread waits in short intervals.

    ctypes lets go of the GIL during the call, so the waiting thread stays
    free: a KeyboardInterrupt (Ctrl-C) lands here, sets the watch's stop
    flag, waits for the library to finish its substep and write what it
    has (relax's surface, run's last snapshot, fit's report marked
    "interrupted"), and is raised again.  A second Ctrl-C while it waits is
    ignored: the library owns the memory and the files until it returns.
    progress: the title of a Progress line, or None for none.  hdf5: the
    call touches HDF5, so it takes hdf5_lock unless HDF5 is thread-safe.
    Raises the exception of the status (check) with the message, read in
    the worker since it is per thread."""
    watch = Watch()
    options.watch(watch)
    done = {"status": SS_ERR_FAIL, "message": "sandslide: the call did not return"}
    # Held while the worker lives, released by it as its last act.  Not
    # Thread.join: a KeyboardInterrupt inside join() can leave the Thread
    # marked stopped while it still runs (CPython gh-90882), and the options
    # would then be freed under the library.  An interrupted acquire() does
    # not take the lock.
    running = threading.Lock()
    running.acquire()
    # "new" until the worker enters the library ("running"), or "cancelled"
    # by this thread first (Ctrl-C inside Thread.start): under gate, so that
    # exactly one of the two happens and this thread knows which.
    state = ["new"]
    gate = threading.Lock()

    def work():
        try:
            with gate:
                if state[0] == "cancelled":
                    return
                state[0] = "running"
            status = function(*args)
            done["status"] = status
            done["message"] = last_message() if status != SS_OK else ""
        finally:
            running.release()

    def wait():
        """Until the worker is done, in slices; True when Ctrl-C came."""
        interrupted = False
        while True:
            try:
                if running.acquire(timeout=0.1):
                    return interrupted
                if bar is not None and not interrupted:
                    bar.update(watch.read())
            except KeyboardInterrupt:
                # stop the library; a second Ctrl-C while it finishes its
                # substep changes nothing (it owns the memory and the files)
                interrupted = True
                watch.stop()

    worker = threading.Thread(target=work, name="sandslide-call", daemon=True)
    bar = None
    interrupted = finished = False
    locked = hdf5 and not HDF5_THREADSAFE
    if locked:
        hdf5_lock.acquire()
    try:
        bar = Progress(progress) if progress else None
        worker.start()
        interrupted = wait()
        finished = True
        if bar is not None and not interrupted and done["status"] == SS_OK:
            bar.update(watch.read(), last=True)
    finally:
        if not finished:   # an exception in this thread before wait() was done
            with gate:
                if state[0] == "new":
                    state[0] = "cancelled"
                inside = state[0] == "running"
            if inside:
                watch.stop()
                wait()
        if bar is not None:
            bar.close()
        options.watch(None)
        watch.close()
        if locked:
            hdf5_lock.release()
    if interrupted:
        raise KeyboardInterrupt
    check(done["status"], done["message"], keywords)
