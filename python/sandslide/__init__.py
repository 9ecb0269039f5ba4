"""sandslide from Python: sand surfaces relaxed to the angle of repose.

    import sandslide
    relaxed, report = sandslide.relax(dem, dx=1.0)            # a DEM array
    summary = sandslide.run("cases/cone.ini", "out/cone.h5")  # a case file
    ds = sandslide.open("out/cone.h5")                        # xarray Dataset

The module calls the shared library libsandslide.so.0 (the engine of the
`sandslide` program) through ctypes: the same code, so `relax` gives the
same bits as `sandslide relax` on the same DEM, and `run` writes the same
file as `sandslide run`.  Where the library is found: _native.py.

Arrays are indexed [row, column] with row 0 the NORTH edge, as GDAL and
rasterio give them; NaN marks cells without data.  Failures raise
sandslide.InputError (bad input, a ValueError) or sandslide.RunError (a
failure while running, a RuntimeError), both sandslide.Error, with the
library's message.  Calls into the library run one at a time.
"""
import ctypes
import json
import numbers
import os

import numpy as np

from ._native import Error, InputError, RunError  # noqa: F401  (the API)
from . import _native

# open is left out: `from sandslide import *` must not hide the built-in
__all__ = ["relax", "run", "version", "Error", "InputError", "RunError", "__version__"]


def version():
    """The library's version, "MAJOR.MINOR.PATCH" (ss_version())."""
    return _native.lib.ss_version().decode()


__version__ = version()

# Room for the JSON the library writes: a report or summary is under 1 KiB
# but for its paths, which the library escapes (at most 6 bytes a byte).
_JSON_BYTES = 1 << 16


def _word(value):
    """value as the word the command line would take: numbers so that the
    library reads back the same double (repr), text as it is."""
    if isinstance(value, str):
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return str(int(value))
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return repr(float(value))
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def _grid(name, values):
    """values as a new float64 array [row, column] with row 0 the SOUTH
    edge, C-contiguous (the library's order); InputError if it is not a
    2-D array of real numbers."""
    try:
        if isinstance(values, np.ma.MaskedArray):   # rasterio's masked=True
            values = values.astype(np.float64).filled(np.nan)
        a = np.asarray(values)
        if a.dtype.kind == "O":
            a = a.astype(np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(f"{name}: cannot be read as an array of numbers: {e}") from None
    if a.dtype.kind not in "fiu":
        raise InputError(f"{name}: expected real numbers (converted to float64), got an "
                         f"array of dtype {a.dtype}")
    if a.ndim != 2:
        raise InputError(f"{name}: expected a 2-D array [row, column] (row 0 the north edge), "
                         f"got shape {a.shape}")
    if a.shape[0] < 1 or a.shape[1] < 1:
        raise InputError(f"{name}: expected at least one row and one column, got shape "
                         f"{a.shape}")
    inf = np.isinf(a)
    if inf.any():
        r, c = np.argwhere(inf)[0]
        raise InputError(f"{name}[{r}, {c}] is {a[r, c]}: expected a finite height, or NaN "
                         f"for no data")
    # a copy always: relax writes its result over it (a one-row view is
    # contiguous, and ascontiguousarray would hand back the caller's memory)
    return np.array(a[::-1], dtype=np.float64, order="C", copy=True)


def relax(heights, dx, dy=None, angle=35.0, closure="coulomb", nu=None, sides="wall",
          bedrock=None, tol=1e-9, threads=None, *, gamma=None, slope_tol=None,
          integrator=None, rkl2_max_stages=None, rkl2_tol=None, max_time=None, cfl=None,
          nodata=None, open_level=None):
    """Relax a DEM to the repose angle, as `sandslide relax` does.

    heights: 2-D array [row, column], row 0 the NORTH edge (GDAL's and
    rasterio's order), in m; NaN where there is no data.  Any real dtype
    (converted to float64; a masked array's mask becomes NaN); not modified.
    dx, dy: cell size in m (dy: dx when None).

    The options are relax's, with the same defaults and checks (None: the
    library's default): angle (deg, default 35), closure ("coulomb",
    "bingham", "herschel-bulkley", "casson"), nu (m^2/s, default 1: sets
    the time scale only), sides ("wall" or "open"), bedrock (an array like
    heights: only the sand above it moves; NaN only where heights is NaN),
    tol (m/s: steady when max |dh/dt| < tol), threads (default: every
    processor; OMP_NUM_THREADS is not consulted), and gamma, slope_tol,
    integrator ("auto", "euler", "rkl2"), rkl2_max_stages, rkl2_tol,
    max_time (s), cfl, nodata ("wall", the default: no sand enters cells
    without data, so a DEM below the repose angle comes back bit for bit;
    "open": they let sand out, held at open_level, default the lowest
    height), open_level (m).

    Returns (relaxed, report): relaxed a new float64 array shaped like
    heights, row 0 north, NaN where heights is; report the dict that
    `sandslide relax --report FILE` writes ("steady", "steps", "time",
    "volume_before", "volume_after", "max_slope_after_deg", ...; "input"
    is "heights" and "output" "(array)").  Raises InputError for bad input
    (ValueError) and RunError for a failure while running.
    """
    h = _grid("heights", heights)
    rock = None
    if bedrock is not None:
        rock = _grid("bedrock", bedrock)
        if rock.shape != h.shape:
            raise InputError(f"bedrock: shape {rock.shape} differs from the heights' "
                             f"{h.shape}")
        # the library checks these too, but names cells from the south
        missing = np.isnan(rock) & ~np.isnan(h)
        if missing.any():
            r, c = np.argwhere(missing[::-1])[0]
            raise InputError(f"bedrock[{r}, {c}] is NaN where heights has data: the "
                             f"bedrock must be given under all the sand")
        with np.errstate(invalid="ignore"):
            above = rock[::-1] > h[::-1]
        if above.any():
            r, c = np.argwhere(above)[0]
            raise InputError(f"bedrock[{r}, {c}] = {rock[::-1][r, c]!r} m is above heights"
                             f"[{r}, {c}] = {h[::-1][r, c]!r} m: the surface must be at or "
                             f"above the bedrock")
    try:
        dx = float(dx)
        dy = dx if dy is None else float(dy)
    except (TypeError, ValueError):
        raise InputError(f"dx, dy: expected cell sizes in m > 0, got {dx!r}, {dy!r}") from None

    given = {"angle": angle, "closure": closure, "nu": nu, "sides": sides, "tol": tol,
             "threads": threads, "gamma": gamma, "slope_tol": slope_tol,
             "integrator": integrator, "rkl2_max_stages": rkl2_max_stages,
             "rkl2_tol": rkl2_tol, "max_time": max_time, "cfl": cfl, "nodata": nodata,
             "open_level": open_level}
    report = ctypes.create_string_buffer(_JSON_BYTES)
    ny, nx = h.shape
    with _native.lock, _native.Options("relax") as o:
        o.set("dem", "heights")           # its name in the library's messages
        for key, value in given.items():
            if value is not None:
                o.set(key, _word(value))
        # h is this call's copy: the library may write the result over it
        _native.check(_native.lib.ss_relax_heights(
            o.ptr, nx, ny, dx, dy, h.ctypes.data, rock.ctypes.data if rock is not None
            else None, h.ctypes.data, report, len(report)))
    return np.ascontiguousarray(h[::-1]), json.loads(report.value.decode())


def run(case, out, set=None, *, threads=None, force=False):
    """Run a case file, as `sandslide run CASE -o OUT [--set ...]` does.

    case: the case file (.ini); out: the output .h5 (its folder must
    exist; an existing file is refused unless force).  set: overrides of
    the case, a dict {"section.key": value} or a list of
    "section.key=value" strings (--set), applied in order.  threads:
    OpenMP threads (default every processor).

    Returns the summary as a dict: "output", "end" ("done", "steady",
    "not steady", "interrupted"), "snapshots", "time" (s), "steps",
    "evaluations", "integrator", "threads", "wall_seconds", ...
    """
    if set is None:
        sets = []
    elif isinstance(set, str):
        sets = [set]
    elif isinstance(set, dict):
        sets = [f"{k}={_word(v)}" for k, v in set.items()]
    else:
        sets = [_word(s) for s in set]
    history = f"python: sandslide.run({os.fspath(case)!r}, {os.fspath(out)!r}"
    history += f", set={sets!r})" if sets else ")"
    summary = ctypes.create_string_buffer(_JSON_BYTES)
    with _native.lock, _native.Options("run") as o:
        o.set("case", os.fspath(case))
        o.set("output", os.fspath(out))
        o.set("history", history)
        for s in sets:
            o.set("set", s)
        if threads is not None:
            o.set("threads", _word(threads))
        if force:
            o.set("force", "1")
        _native.check(_native.lib.ss_run_case_json(o.ptr, summary, len(summary)))
    return json.loads(summary.value.decode())


def open(path, **kwargs):
    """The output of a run (or of relax -o OUT.h5) as an xarray Dataset:
    height(time, y, x), time, x, y, the diagnostics, the case in the
    attributes.  Lazy: close it (or use `with`).  kwargs go to
    xarray.open_dataset.  Needs xarray with netCDF4 or h5netcdf."""
    try:
        import xarray
    except ImportError:
        raise ImportError("sandslide.open needs xarray: install Debian package "
                          "python3-xarray (with python3-netcdf4), or pip install "
                          "xarray netCDF4") from None
    engine = None
    for module, name in (("netCDF4", "netcdf4"), ("h5netcdf", "h5netcdf")):
        try:
            __import__(module)
            engine = name
            break
        except ImportError:
            pass
    if engine is None:
        raise ImportError("sandslide.open needs netCDF4 or h5netcdf for xarray: install "
                          "Debian package python3-netcdf4 (or python3-h5netcdf)")
    return xarray.open_dataset(os.fspath(path), engine=engine, **kwargs)
