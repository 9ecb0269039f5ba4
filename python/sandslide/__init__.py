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
__all__ = ["relax", "run", "options", "version", "Error", "InputError", "RunError",
           "__version__"]


def version():
    """The library's version, "MAJOR.MINOR.PATCH" (ss_version())."""
    return _native.lib.ss_version().decode()


__version__ = version()

# Room for the JSON the library writes: a report or summary is under 1 KiB
# but for its paths, which the library escapes (at most 6 bytes a byte).
_JSON_BYTES = 1 << 16


def options(command):
    """The options of `command` ("relax" or "run") as the library's table
    gives them (option.h), a list of dicts: "name" (relax's keyword, with
    '_' for '-'), "case_key" (the case file's key of the same option, or
    None), "kind", "default" (the text a user would give, or None: none),
    "lo", "hi" (the range of a number, None when open-ended), "expected",
    "help", "command_line" and "by_name".  The module keeps no defaults of
    its own: a keyword left at None takes the library's."""
    table = _native.option_table(command)
    buf = ctypes.create_string_buffer(_JSON_BYTES)
    _native.check(_native.lib.ss_option_table_json(table, buf, len(buf)))
    return json.loads(buf.value.decode())


def _options_doc(command):
    """The options' defaults and help, for a docstring."""
    lines = []
    for o in options(command):
        if not o["by_name"] or o["kind"] in ("text", "list"):
            continue
        default = o["default"] if o["default"] is not None else "none"
        text = " ".join(o["help"].split())
        lines.append(f"    {o['name'].replace('-', '_')} (default {default}): {text}")
    return "\n".join(lines)


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


def relax(heights, dx, dy=None, angle=None, closure=None, nu=None, sides=None,
          bedrock=None, tol=None, threads=None, *, gamma=None, slope_tol=None,
          integrator=None, rkl2_max_stages=None, rkl2_tol=None, max_time=None, cfl=None,
          nodata=None, open_level=None, add_sand=None, sand_rate=None, sand_duration=None,
          tile=None):
    """Relax a DEM to the repose angle, as `sandslide relax` does.

    heights: 2-D array [row, column], row 0 the NORTH edge (GDAL's and
    rasterio's order), in m; NaN where there is no data.  Any real dtype
    (converted to float64; a masked array's mask becomes NaN); not modified.
    dx, dy: cell size in m (dy: dx when None).  bedrock: an array like
    heights, the non-erodible base: only the sand above it moves (NaN only
    where heights is NaN).

    Every other keyword is relax's option of that name ('_' for '-'),
    checked by the library as the command line checks it; None (the
    default) takes the library's default.  add_sand is "rect=X0,Y0,X1,Y1"
    or "disk=X,Y,R" (m) with sand_rate (m/s) and sand_duration (s); tile
    is "NXxNY" or a pair (nx, ny).  The
    options and their defaults, from the library (sandslide.options("relax")):

{options}

    Returns (relaxed, report): relaxed a new float64 array shaped like
    heights, row 0 north, NaN where heights is; report the dict that
    `sandslide relax --report FILE` writes ("steady", "end", "steps",
    "time", "volume_before", "volume_after", "max_slope_after_deg", ...;
    "input" is "heights" and "output" "(array)").  Raises InputError for
    bad input (ValueError) and RunError for a failure while running.
    """
    h = _grid("heights", heights)
    rock = None
    if bedrock is not None:
        rock = _grid("bedrock", bedrock)
        if rock.shape != h.shape:   # the library takes one size for both
            raise InputError(f"bedrock: shape {rock.shape} differs from the heights' "
                             f"{h.shape}")
    try:
        dx = float(dx)
        dy = dx if dy is None else float(dy)
    except (TypeError, ValueError):
        raise InputError(f"dx, dy: expected cell sizes in m > 0, got {dx!r}, {dy!r}") from None

    given = {"angle": angle, "closure": closure, "nu": nu, "sides": sides, "tol": tol,
             "threads": threads, "gamma": gamma, "slope_tol": slope_tol,
             "integrator": integrator, "rkl2_max_stages": rkl2_max_stages,
             "rkl2_tol": rkl2_tol, "max_time": max_time, "cfl": cfl, "nodata": nodata,
             "open_level": open_level, "add_sand": add_sand, "sand_rate": sand_rate,
             "sand_duration": sand_duration,
             "tile": "x".join(str(int(n)) for n in tile) if isinstance(tile, (tuple, list))
             else tile}
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


relax.__doc__ = relax.__doc__.format(options=_options_doc("relax"))


def run(case, out, set=None, *, unset=None, threads=None, force=False):
    """Run a case file, as `sandslide run CASE -o OUT [--set ...]` does.

    case: the case file (.ini); out: the output .h5 (its folder must
    exist; an existing file is refused unless force).  set: overrides of
    the case, a dict {"section.key": value} or a list of
    "section.key=value" strings (--set), applied in order; a key of the
    case they make redundant is dropped (the summary's "notes" say which).
    unset: keys ("section.key") or wall, open and source sections
    ("source pour") to drop, a string or a list (--unset), applied before
    set.  threads: OpenMP threads (default: OMP_NUM_THREADS, else every
    processor).

    Returns the summary as a dict: "output", "end" ("done", "steady",
    "not steady", "interrupted"), "snapshots", "time" (s), "steps",
    "evaluations", "integrator", "threads", "wall_seconds", "notes", ...
    """
    if set is None:
        sets = []
    elif isinstance(set, str):
        sets = [set]
    elif isinstance(set, dict):
        sets = [f"{k}={_word(v)}" for k, v in set.items()]
    else:
        sets = [_word(s) for s in set]
    unsets = [] if unset is None else [unset] if isinstance(unset, str) else list(unset)
    history = f"python: sandslide.run({os.fspath(case)!r}, {os.fspath(out)!r}"
    history += f", set={sets!r}" if sets else ""
    history += f", unset={unsets!r})" if unsets else ")"
    summary = ctypes.create_string_buffer(_JSON_BYTES)
    with _native.lock, _native.Options("run") as o:
        o.set("case", os.fspath(case))
        o.set("output", os.fspath(out))
        o.set("history", history)
        for u in unsets:
            o.set("unset", u)
        for s in sets:
            o.set("set", s)
        if threads is not None:
            o.set("threads", _word(threads))
        if force:
            o.set("force", "1")
        _native.check(_native.lib.ss_run_case_json(o.ptr, summary, len(summary)))
    return json.loads(summary.value.decode())


def _fit_bound(name, bounds):
    """--param's word for one entry of fit's params: (lo, hi) or
    (lo, hi, "log"), or the word itself."""
    if isinstance(bounds, str):
        return f"{name}={bounds}"
    lo, hi, *scale = bounds
    return f"{name}={_word(lo)}:{_word(hi)}" + (f":{scale[0]}" if scale else "")


def fit(case, observations, params, closures=None, *, cost=None, threshold=None,
        out=None, plot=None, threads=None, force=False, **options):
    """Fit a closure and its parameters to observations, as `sandslide fit
    CASE OBS --param ...` does (doc/fit.md).

    case: the case file (geometry, walls, sources, initial state).
    observations: a height series (.h5 in sandslide's layout), a CSV
    "time,path" of rasters, or a CSV "time,x,y" of front points.  params:
    {"nu": (0.01, 1, "log"), "repose_angle": (30, 40)} (or "LO:HI[:log]"
    strings).  closures: "all", a list of names, or None for the case's.
    cost: "height", "support" or "both" (default by the observations);
    threshold: the support's, m.  out, plot: FIT.json and FIT.png to write.
    Other keyword options of `sandslide fit --help` by name, e.g.
    grid_points=5, max_runs=40, profile_points=9, support_weight=0.5.

    Returns the report as a dict: "best" {"closure", "params", "cost"},
    "closures" (each with "params", "uncertainty", "identifiable", "cost",
    "aic", "evaluations", "profile"), "indistinguishable", "verdict",
    "cost_functional", "observations", "forward_runs", "seconds".
    """
    if isinstance(closures, (list, tuple)):
        closures = ",".join(closures)
    report = ctypes.create_string_buffer(1 << 20)   # profiles of 4 closures: tens of kB
    with _native.lock, _native.Options("fit") as o:
        o.set("case", os.fspath(case))
        o.set("observations", os.fspath(observations))
        for name, bounds in params.items():
            o.set("param", _fit_bound(name, bounds))
        for key, value in [("closures", closures), ("cost", cost), ("threshold", threshold),
                           ("output", out), ("plot", plot), ("threads", threads)]:
            if value is not None:
                o.set(key, value if isinstance(value, str) else _word(value))
        if force:
            o.set("force", "1")
        for key, value in options.items():
            o.set(key, _word(value))
        _native.check(_native.lib.ss_fit_run_json(o.ptr, report, len(report)))
    return json.loads(report.value.decode())


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
