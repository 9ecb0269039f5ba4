# SPDX-License-Identifier: BSD-3-Clause
"""sandslide as a Python BMI 2.0 component: SandslideBmi, the methods of
bmipy's Bmi over the library's C BMI (include/sandslide/bmi.h).

    from sandslide.bmi import SandslideBmi
    with SandslideBmi() as m:
        m.initialize("cases/cone.ini")              # a case file
        m.update_until(10.0)                        # seconds
        h = m.get_value("land_surface__elevation", np.empty(m.get_grid_size(0)))

Every call goes to the C functions that ss_bmi_register puts in a struct
Bmi, so Python and C drive the same code and give the same bits.  The
conventions are bmipy's: getters return a value, or fill the caller's dest
array and return it; names are str; the name lists are tuples.  The
variables, grids and time are the C BMI's (doc/bmi.md): arrays are flat
[y][x] with row 0 the SOUTH row (the HDF5 output's order, not the north-up
order of sandslide.relax), and the C type "double" is numpy's float64.

Checked here before the library is called, so that a refused call changes
nothing: that the model is initialized, that a name, a grid or an index
exists, that an array has the variable's size and a dtype that converts
safely.  Failures raise sandslide.InputError (bad names, grids, indices,
sizes, types, values; a case file the library refuses) or
sandslide.RunError (the model stopped while stepping), with the library's
message where it gave one; UnsupportedError (also a NotImplementedError)
for what sandslide's grids and storage do not offer: get_value_ptr (the
heights live with a halo ring, so there is no [y][x] array to point at:
use get_value) and the rectilinear, curvilinear and unstructured grid
functions.

bmipy is not in Debian: SandslideBmi subclasses bmipy.Bmi when bmipy is
importable, and has the same methods as a plain class otherwise.
"""
import contextlib
import ctypes
import math
import os
import threading

import numpy as np

from . import _native
from ._native import Error, InputError, RunError

try:
    from bmipy import Bmi as _Base
except ImportError:   # not in Debian: duck-typed, the same methods
    _Base = object

__all__ = ["SandslideBmi", "UnsupportedError"]

BMI_SUCCESS = 0
BMI_MAX_NAME = 2048   # BMI_MAX_{UNITS,TYPE,COMPONENT,VAR}_NAME of bmi.h

# The C BMI's type names as numpy's (bmi.h says "double" for every variable
# today; the others are what BMI's C binding could say).
_NUMPY_TYPE = {"double": "float64", "float": "float32", "int": "int32", "long": "int64"}


class UnsupportedError(Error, NotImplementedError):
    """A BMI function sandslide does not offer (get_value_ptr, the grids
    that are not uniform_rectilinear or scalar)."""


# struct Bmi, laid out as bmi.h (and csdms/bmi-c's bmi.h) declares it: a
# data pointer, then 41 function pointers in the published order.  Unlike
# the library's own structs, which this module never lays out (_native.py),
# this layout is BMI 2.0's C binding: a published interface that
# frameworks compile against, fixed by the standard, not by a version of
# sandslide.  Each function takes the struct's address first; buffers are
# passed as addresses (c_void_p), scalars through pointers.
_I, _D, _S, _P = ctypes.c_int, ctypes.c_double, ctypes.c_char_p, ctypes.c_void_p
_PI, _PD = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double)


def _fn(*args):
    return ctypes.CFUNCTYPE(_I, _P, *args)


_GRID_INTS, _GRID_DOUBLES = _fn(_I, _P), _fn(_I, _P)


class _CBmi(ctypes.Structure):
    _fields_ = [
        ("data", _P),
        # initialize, run, finalize
        ("initialize", _fn(_S)),
        ("update", _fn()),
        ("update_until", _fn(_D)),
        ("finalize", _fn()),
        # exchange items
        ("get_component_name", _fn(_P)),
        ("get_input_item_count", _fn(_PI)),
        ("get_output_item_count", _fn(_PI)),
        ("get_input_var_names", _fn(_P)),
        ("get_output_var_names", _fn(_P)),
        # variable information
        ("get_var_grid", _fn(_S, _PI)),
        ("get_var_type", _fn(_S, _P)),
        ("get_var_units", _fn(_S, _P)),
        ("get_var_itemsize", _fn(_S, _PI)),
        ("get_var_nbytes", _fn(_S, _PI)),
        ("get_var_location", _fn(_S, _P)),
        # time
        ("get_current_time", _fn(_PD)),
        ("get_start_time", _fn(_PD)),
        ("get_end_time", _fn(_PD)),
        ("get_time_units", _fn(_P)),
        ("get_time_step", _fn(_PD)),
        # getters
        ("get_value", _fn(_S, _P)),
        ("get_value_ptr", _fn(_S, _P)),
        ("get_value_at_indices", _fn(_S, _P, _P, _I)),
        # setters
        ("set_value", _fn(_S, _P)),
        ("set_value_at_indices", _fn(_S, _P, _I, _P)),
        # grid information
        ("get_grid_rank", _fn(_I, _PI)),
        ("get_grid_size", _fn(_I, _PI)),
        ("get_grid_type", _fn(_I, _P)),
        # uniform rectilinear
        ("get_grid_shape", _GRID_INTS),
        ("get_grid_spacing", _GRID_DOUBLES),
        ("get_grid_origin", _GRID_DOUBLES),
        # non-uniform rectilinear, curvilinear
        ("get_grid_x", _GRID_DOUBLES),
        ("get_grid_y", _GRID_DOUBLES),
        ("get_grid_z", _GRID_DOUBLES),
        # unstructured
        ("get_grid_node_count", _fn(_I, _PI)),
        ("get_grid_edge_count", _fn(_I, _PI)),
        ("get_grid_face_count", _fn(_I, _PI)),
        ("get_grid_edge_nodes", _GRID_INTS),
        ("get_grid_face_edges", _GRID_INTS),
        ("get_grid_face_nodes", _GRID_INTS),
        ("get_grid_nodes_per_face", _GRID_INTS),
    ]


def _prototype(name, res, args):
    try:
        f = getattr(_native.lib, name)
    except AttributeError:
        raise ImportError(f"sandslide.bmi: the library {_native.lib._name} has no {name}: it "
                          f"is older than this module (rebuild it with `make`)") from None
    f.restype, f.argtypes = res, args
    return f


_register = _prototype("ss_bmi_register", _P, [_P])


class SandslideBmi(_Base):
    """sandslide behind the Basic Model Interface 2.0 (bmipy's Bmi).

    SandslideBmi() makes an uninitialized model; initialize(config) sets
    up a case file, or a [bmi] config naming a case or a DEM
    (doc/bmi.md#the-config); finalize() releases it (also
    on leaving a `with` block, or when the object is collected).  Every
    other call before initialize raises sandslide.Error."""

    def __init__(self):
        self._c = _CBmi()
        if not _register(ctypes.addressof(self._c)):
            raise RunError("BMI: ss_bmi_register refused the struct")
        self._self = ctypes.addressof(self._c)
        self._lock = threading.Lock()
        self._vars = None     # name -> (grid, numpy dtype, item count, is input)
        self._grids = None    # grid id -> (type, rank, size)

    # ---- calling C --------------------------------------------------------

    # The C functions that report every failure through error.h, once the
    # checks here have passed (bmi.c): the case file, the stepper, the
    # values set.  For the others a message is used only if the call left
    # a new one (the last message may be an older call's).
    _REPORTS = {"initialize", "update", "update_until", "set_value", "set_value_at_indices"}

    def _call(self, func, *args, error=InputError, what=None):
        """The C function func(self, *args); error(message) on BMI_FAILURE,
        with the library's message where it gave one."""
        # the library's last message is per thread; one model's calls go
        # one at a time (its state is not shared between threads), and
        # initialize may read an HDF5 file (an initial surface from an
        # output), under the module's HDF5 lock when HDF5 is not thread-safe
        hdf5 = func == "initialize" and not _native.HDF5_THREADSAFE
        with self._lock, (_native.hdf5_lock if hdf5 else contextlib.nullcontext()):
            before = _native.last_message()
            status = getattr(self._c, func)(self._self, *args)
            after = _native.last_message()
        if status == BMI_SUCCESS:
            return
        fresh = after and (func in self._REPORTS or after != before)
        raise error(after if fresh else f"BMI {what or func}: failed")

    def _ready(self, func):
        if self._vars is None:
            raise InputError(f"BMI {func}: the model is not initialized (call initialize "
                             f"with a case file first)")

    def _var(self, func, name):
        """(grid, dtype, count, is_input) of the variable name."""
        self._ready(func)
        if not isinstance(name, str):
            raise InputError(f"BMI {func}: a variable name is a str, got {name!r}")
        try:
            return self._vars[name]
        except KeyError:
            raise InputError(f"BMI {func}: no variable {name!r}; sandslide's are "
                             f"{', '.join(self._vars)}") from None

    def _grid(self, func, grid, types=None):
        """(type, rank, size) of grid id grid; with types, it must be one."""
        self._ready(func)
        try:
            gid = int(grid)
            ok = gid == grid and gid in self._grids
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(f"BMI {func}: no grid {grid!r}; sandslide's are "
                             f"{', '.join(map(str, sorted(self._grids)))}")
        info = self._grids[gid]
        if types is not None and info[0] not in types:
            raise UnsupportedError(f"BMI {func}: grid {gid} is {info[0]}: {func} is for "
                                   f"{' and '.join(types)} grids")
        return gid, info

    def _text(self, func, *args):
        buf = ctypes.create_string_buffer(BMI_MAX_NAME)
        self._call(func, *args, ctypes.addressof(buf))
        return buf.value.decode()

    def _int(self, func, *args):
        v = ctypes.c_int()
        self._call(func, *args, ctypes.byref(v))
        return v.value

    def _double(self, func, *args):
        v = ctypes.c_double()
        self._call(func, *args, ctypes.byref(v))
        return v.value

    def _names(self, func, count):
        bufs = [ctypes.create_string_buffer(BMI_MAX_NAME) for _ in range(count)]
        ptrs = (ctypes.c_void_p * max(count, 1))(*[ctypes.addressof(b) for b in bufs])
        self._call(func, ctypes.addressof(ptrs))
        return tuple(b.value.decode() for b in bufs)

    # ---- initialize, run, finalize ----------------------------------------

    def initialize(self, config_file):
        """Set up config_file: a case file (doc/case-file.md), set up as
        `sandslide run` does, or a BMI config whose [bmi] section names a
        case or a DEM with relax's options (doc/bmi.md#the-config).
        InputError for a config the library refuses, or when the model is
        already initialized (finalize first)."""
        if self._vars is not None:
            raise InputError("BMI initialize: already initialized (finalize first)")
        path = os.fsencode(config_file)
        self._call("initialize", path, what=f"initialize({os.fsdecode(path)!r})")
        try:
            names_in = self._names("get_input_var_names", self._int("get_input_item_count"))
            names_out = self._names("get_output_var_names",
                                    self._int("get_output_item_count"))
            vars_, grids = {}, {}
            for name in dict.fromkeys(names_in + names_out):
                b = name.encode()
                grid = self._int("get_var_grid", b)
                ctype = self._text("get_var_type", b)
                dtype = np.dtype(_NUMPY_TYPE.get(ctype, ctype))
                nbytes, itemsize = self._int("get_var_nbytes", b), self._int("get_var_itemsize", b)
                if itemsize != dtype.itemsize or nbytes % itemsize:
                    raise RunError(f"BMI initialize: {name}: itemsize {itemsize} and nbytes "
                                   f"{nbytes} do not fit its type {dtype}")
                vars_[name] = (grid, dtype, nbytes // itemsize, name in names_in)
                if grid not in grids:
                    grids[grid] = (self._text("get_grid_type", grid),
                                   self._int("get_grid_rank", grid),
                                   self._int("get_grid_size", grid))
        except Exception:
            getattr(self._c, "finalize")(self._self)
            raise
        self._names_in, self._names_out = names_in, names_out
        self._vars, self._grids = vars_, grids

    def update(self):
        """Advance one time step (output_every): from k * step to (k + 1) *
        step, as `sandslide run` goes from snapshot to snapshot.  RunError
        if the model stops short (it stays where it stopped)."""
        self._ready("update")
        self._call("update", error=RunError)

    def update_until(self, time):
        """Advance to time (s) in one call.  InputError for a time before
        the current one, or not finite."""
        self._ready("update_until")
        try:
            t = float(time)
        except (TypeError, ValueError):
            raise InputError(f"BMI update_until: expected a time in s, got {time!r}") from None
        now = self.get_current_time()
        if not math.isfinite(t) or t < now:
            raise InputError(f"BMI update_until: {t!r} s is not a finite time at or after "
                             f"the current time, {now!r} s")
        self._call("update_until", t, error=RunError, what=f"update_until({t!r})")

    def finalize(self):
        """Release the model.  A no-op when it is not initialized (so that
        `with`, finalize and garbage collection may each call it)."""
        if self._vars is None:
            return
        self._vars = self._grids = None
        self._call("finalize", error=RunError)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.finalize()

    def __del__(self):
        # at interpreter exit the module's globals may be gone: best effort
        try:
            if getattr(self, "_vars", None) is not None:
                self._vars = None
                self._c.finalize(self._self)
        except Exception:
            pass

    # ---- exchange items ---------------------------------------------------

    def get_component_name(self):
        self._ready("get_component_name")
        return self._text("get_component_name")

    def get_input_item_count(self):
        self._ready("get_input_item_count")
        return len(self._names_in)

    def get_output_item_count(self):
        self._ready("get_output_item_count")
        return len(self._names_out)

    def get_input_var_names(self):
        self._ready("get_input_var_names")
        return self._names_in

    def get_output_var_names(self):
        self._ready("get_output_var_names")
        return self._names_out

    # ---- variable information ---------------------------------------------

    def get_var_grid(self, name):
        self._var("get_var_grid", name)
        return self._int("get_var_grid", name.encode())

    def get_var_type(self, name):
        """numpy's name of the type ("float64" where C says "double")."""
        return str(self._var("get_var_type", name)[1])

    def get_var_units(self, name):
        self._var("get_var_units", name)
        return self._text("get_var_units", name.encode())

    def get_var_itemsize(self, name):
        self._var("get_var_itemsize", name)
        return self._int("get_var_itemsize", name.encode())

    def get_var_nbytes(self, name):
        self._var("get_var_nbytes", name)
        return self._int("get_var_nbytes", name.encode())

    def get_var_location(self, name):
        self._var("get_var_location", name)
        return self._text("get_var_location", name.encode())

    # ---- time ---------------------------------------------------------------

    def get_current_time(self):
        self._ready("get_current_time")
        return self._double("get_current_time")

    def get_start_time(self):
        self._ready("get_start_time")
        return self._double("get_start_time")

    def get_end_time(self):
        self._ready("get_end_time")
        return self._double("get_end_time")

    def get_time_units(self):
        self._ready("get_time_units")
        return self._text("get_time_units")

    def get_time_step(self):
        self._ready("get_time_step")
        return self._double("get_time_step")

    # ---- getters and setters ----------------------------------------------

    @staticmethod
    def _dest(func, name, dest, dtype, count):
        """dest checked: a writable numpy array of count items that dtype
        converts to safely."""
        if not isinstance(dest, np.ndarray):
            raise InputError(f"BMI {func}: {name}: dest must be a numpy array, got "
                             f"{type(dest).__name__}")
        if dest.size != count:
            raise InputError(f"BMI {func}: {name}: dest has {dest.size} items, expected "
                             f"{count}")
        if not np.can_cast(dtype, dest.dtype, "safe"):
            raise InputError(f"BMI {func}: {name}: dest has dtype {dest.dtype}, which "
                             f"{dtype} does not convert to safely")
        if not dest.flags.writeable:
            raise InputError(f"BMI {func}: {name}: dest is read-only")
        return dest

    @staticmethod
    def _fill(dest, values):
        """values (flat, C order) into dest, in dest's C order."""
        if dest.flags.c_contiguous:
            dest.reshape(-1)[...] = values
        else:
            dest[...] = values.reshape(dest.shape)
        return dest

    def _indices(self, func, name, inds, count):
        """inds as contiguous C ints, each in [0, count)."""
        try:
            a = np.asarray(inds)
        except (TypeError, ValueError):
            a = None
        if a is None or a.ndim > 1 or (a.size and a.dtype.kind not in "iu"):
            raise InputError(f"BMI {func}: {name}: inds must be a 1-D array of integers, got "
                             f"{inds!r}")
        bad = (a < 0) | (a >= count)
        if bad.any():
            raise InputError(f"BMI {func}: {name}: index {a[bad][0]} is outside [0, {count})")
        return np.ascontiguousarray(a.reshape(-1), dtype=np.intc)

    def _src(self, func, name, src, dtype, count):
        """src as a new contiguous array of dtype with count items, C order;
        InputError for another size or a dtype that does not convert safely."""
        try:
            a = np.asarray(src)
        except (TypeError, ValueError) as e:
            raise InputError(f"BMI {func}: {name}: cannot read src as an array: {e}") from None
        if a.size != count:
            raise InputError(f"BMI {func}: {name}: src has {a.size} items, expected {count}")
        if not np.can_cast(a.dtype, dtype, "safe"):
            raise InputError(f"BMI {func}: {name}: src has dtype {a.dtype}, which does not "
                             f"convert to {dtype} safely")
        return np.array(a.reshape(-1), dtype=dtype, order="C", copy=True)

    def get_value(self, name, dest):
        """A copy of the variable in dest (a numpy array of its size, any
        shape: filled in C order, so an [ny, nx] array gets row 0 south),
        which is returned."""
        _, dtype, count, _ = self._var("get_value", name)
        self._dest("get_value", name, dest, dtype, count)
        if dest.dtype == dtype and dest.flags.c_contiguous:
            self._call("get_value", name.encode(), dest.ctypes.data)
            return dest
        tmp = np.empty(count, dtype)
        self._call("get_value", name.encode(), tmp.ctypes.data)
        return self._fill(dest, tmp)

    def get_value_ptr(self, name):
        """Not offered: the heights live with a halo ring, so there is no
        [y][x] array to point at.  Use get_value."""
        self._var("get_value_ptr", name)
        raise UnsupportedError(f"BMI get_value_ptr: {name}: sandslide keeps its fields with a "
                               f"halo ring, not as one [y][x] array to point at; use "
                               f"get_value(name, dest) for a copy")

    def get_value_at_indices(self, name, dest, inds):
        """The values at flat [y][x] indices inds into dest (as many items as
        inds), which is returned."""
        grid, dtype, count, _ = self._var("get_value_at_indices", name)
        idx = self._indices("get_value_at_indices", name, inds, count)
        self._dest("get_value_at_indices", name, dest, dtype, idx.size)
        tmp = np.empty(idx.size, dtype)
        self._call("get_value_at_indices", name.encode(), tmp.ctypes.data, idx.ctypes.data,
                   int(idx.size))
        return self._fill(dest, tmp)

    def set_value(self, name, src):
        """Set an input variable to src (its size, any shape read in C
        order, a dtype that converts to its type safely).  A refused src
        changes nothing."""
        _, dtype, count, is_input = self._var("set_value", name)
        if not is_input:
            raise InputError(f"BMI set_value: {name} is an output only; the inputs are "
                             f"{', '.join(self._names_in)}")
        a = self._src("set_value", name, src, dtype, count)
        self._call("set_value", name.encode(), a.ctypes.data)

    def set_value_at_indices(self, name, inds, src):
        """Set an input variable at flat [y][x] indices inds to src (as many
        items as inds)."""
        _, dtype, count, is_input = self._var("set_value_at_indices", name)
        if not is_input:
            raise InputError(f"BMI set_value_at_indices: {name} is an output only; the "
                             f"inputs are {', '.join(self._names_in)}")
        idx = self._indices("set_value_at_indices", name, inds, count)
        a = self._src("set_value_at_indices", name, src, dtype, idx.size)
        self._call("set_value_at_indices", name.encode(), idx.ctypes.data, int(idx.size),
                   a.ctypes.data)

    # ---- grids ---------------------------------------------------------------

    def get_grid_rank(self, grid):
        return self._grid("get_grid_rank", grid)[1][1]

    def get_grid_size(self, grid):
        return self._grid("get_grid_size", grid)[1][2]

    def get_grid_type(self, grid):
        return self._grid("get_grid_type", grid)[1][0]

    def _grid_array(self, func, grid, out, dtype):
        """The rank values of func for a uniform_rectilinear grid into out."""
        gid, (_, rank, _) = self._grid(func, grid, ("uniform_rectilinear",))
        self._dest(func, f"grid {gid}", out, np.dtype(dtype), rank)
        tmp = np.empty(rank, dtype)
        self._call(func, gid, tmp.ctypes.data)
        return self._fill(out, tmp)

    def get_grid_shape(self, grid, shape):
        """[ny, nx] into shape (an int array of rank items), returned."""
        return self._grid_array("get_grid_shape", grid, shape, np.intc)

    def get_grid_spacing(self, grid, spacing):
        """[dy, dx] in m into spacing, returned."""
        return self._grid_array("get_grid_spacing", grid, spacing, np.float64)

    def get_grid_origin(self, grid, origin):
        """[y, x] of the centre of cell (0, 0), the south-west one, in m,
        into origin, returned."""
        return self._grid_array("get_grid_origin", grid, origin, np.float64)

    def _not_offered(self, func, grid):
        gid, (gtype, _, _) = self._grid(func, grid)
        raise UnsupportedError(f"BMI {func}: grid {gid} is {gtype}: sandslide has no "
                               f"rectilinear, curvilinear or unstructured grids"
                               + ("; use get_grid_origin and get_grid_spacing"
                                  if gtype == "uniform_rectilinear" else ""))

    def get_grid_x(self, grid, x):
        self._not_offered("get_grid_x", grid)

    def get_grid_y(self, grid, y):
        self._not_offered("get_grid_y", grid)

    def get_grid_z(self, grid, z):
        self._not_offered("get_grid_z", grid)

    def get_grid_node_count(self, grid):
        self._not_offered("get_grid_node_count", grid)

    def get_grid_edge_count(self, grid):
        self._not_offered("get_grid_edge_count", grid)

    def get_grid_face_count(self, grid):
        self._not_offered("get_grid_face_count", grid)

    def get_grid_edge_nodes(self, grid, edge_nodes):
        self._not_offered("get_grid_edge_nodes", grid)

    def get_grid_face_edges(self, grid, face_edges):
        self._not_offered("get_grid_face_edges", grid)

    def get_grid_face_nodes(self, grid, face_nodes):
        self._not_offered("get_grid_face_nodes", grid)

    def get_grid_nodes_per_face(self, grid, nodes_per_face):
        self._not_offered("get_grid_nodes_per_face", grid)
