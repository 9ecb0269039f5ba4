# SPDX-License-Identifier: BSD-3-Clause
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
library's message, naming the keyword the message is about (force=True,
tile=) where the command line names a flag.

Ctrl-C stops relax, run and fit within a fraction of a second: the
library finishes its substep and writes what it has, and the call raises
KeyboardInterrupt.  Calls on different data may run at the same time in
different threads (doc/python.md#threads).
"""
from __future__ import annotations   # the hints read as written, in help()

import ctypes
import functools
import json
import numbers
import os
import tempfile
import textwrap
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in the hints)

if TYPE_CHECKING:   # the hints' other types; neither is needed to run
    import osgeo.gdal
    import xarray

from ._native import Error, InputError, RunError  # noqa: F401  (the API)
from . import _native

# open is left out: `from sandslide import *` must not hide the built-in
__all__ = ["relax", "relax_raster", "run", "fit", "options", "version", "Error",
           "InputError", "RunError", "__version__"]

PathLike = Union[str, os.PathLike]


def version() -> str:
    """The library's version.

    Returns
    -------
    str
        "MAJOR.MINOR.PATCH", as ``sandslide --version`` prints it
        (``ss_version()``).

    Examples
    --------
    >>> sandslide.version()      # doctest: +SKIP
    '0.1.0'
    """
    return _native.lib.ss_version().decode()


__version__ = version()

# Room for the JSON the library writes: a report or summary is under 1 KiB
# but for its paths, which the library escapes (at most 6 bytes a byte).
_JSON_BYTES = 1 << 16


def options(command: str) -> List[Dict[str, Any]]:
    """The options of a command, as the library's table gives them.

    Parameters
    ----------
    command : {"relax", "run", "fit"}
        The command.

    Returns
    -------
    list of dict
        One dict an option (option.h): "name" (the command line's, '-'
        where the keyword has '_'), "case_key" (the case file's key of the
        same option, or None), "kind", "default" (the text a user would
        give, or None: none), "lo", "hi" (the range of a number, None when
        open-ended), "expected", "help", "command_line" and "by_name".

    Raises
    ------
    ValueError
        For a command that has no options table.

    Notes
    -----
    The module keeps no defaults of its own: a keyword left at None takes
    the library's, the default listed here.

    Examples
    --------
    >>> [o["default"] for o in sandslide.options("relax") if o["name"] == "angle"]
    ['35']
    """
    table = _native.option_table(command)
    buf = ctypes.create_string_buffer(_JSON_BYTES)
    _native.check(_native.lib.ss_option_table_json(table, buf, len(buf)))
    # the case's keys that are no option of the command (a case file's
    # sliding layer, in the model's table) have no name
    return [o for o in json.loads(buf.value.decode()) if o["name"] is not None]


_KINDS = {"real": "float", "int": "int", "flag": "bool", "word": "str", "text": "str",
          "list": "str", "tile": "str or (int, int)"}


def _options_doc(command, skip=()):
    """The options of the library's table as numpydoc parameters, for a
    docstring: name, type, the help (its flags named as keywords) and the
    default, indented for a function's docstring."""
    lines = []
    keywords = _keywords(command)
    for o in options(command):
        name = o["name"].replace("-", "_")
        if not o["by_name"] or o["kind"] in ("text", "list") or name in skip:
            continue
        kind = _KINDS["tile"] if name == "tile" else _KINDS.get(o["kind"], "str")
        lines.append(f"    {name} : {kind}, optional")
        text = _native.translate_message(" ".join(o["help"].split()), keywords)
        if o["default"] is not None:
            text += f" (library default: {o['default']})"
        lines += textwrap.wrap(text + ".", 79, initial_indent=" " * 8,
                               subsequent_indent=" " * 8)
    return "\n".join(lines)


@functools.lru_cache(maxsize=None)
def _keywords(command, rename=(), only=None, extra=()):
    """{option name of the library: (Python keyword, is a flag)} for the
    messages of a call (_native.translate_message): the options of the
    command's table by their names ('_' for '-'), only those in only when
    it is given (the function's keywords), renamed where the function's
    keyword differs (rename: pairs (library name, keyword)), with extra
    (name, keyword, is_flag) triples."""
    names = dict(rename)
    out = {o["name"]: (names.get(o["name"], o["name"].replace("-", "_")),
                       o["kind"] == "flag") for o in options(command)
           if only is None or o["name"] in only}
    for name, keyword, is_flag in extra:
        out[name] = (keyword, is_flag)
    return out


_THREADS_DOC = """threads : int, optional
        OpenMP threads of the call (1 to 4096).  When None, the library
        takes OMP_NUM_THREADS's first entry if it is an integer from 1 to
        4096 (read at each call, so os.environ counts), else the
        processors this process may run on (its CPU affinity: taskset, a
        batch system's cpuset), divided by the MPI ranks sharing the node
        (one outside MPI), and at most one per 65536 cells of the grid.
        The count is this call's own: calls in other threads keep
        theirs."""

_PROGRESS_DOC = """progress : bool, optional
        Show a progress bar while the call runs: tqdm's when tqdm can be
        imported, else a line on stderr rewritten in place.  Off by
        default; the line ends when the call does, also on Ctrl-C or an
        error."""

def _interrupt_note(what):
    """The Notes' paragraph on Ctrl-C, what: what the call leaves."""
    text = ("Ctrl-C (SIGINT in the main thread) stops the call within a fraction of a "
            f"second: the library finishes its substep and {what}, then KeyboardInterrupt "
            "is raised.  The call runs in a worker thread while the calling thread waits "
            "(ctypes lets go of the GIL), so other Python threads run meanwhile.")
    return "\n    ".join(textwrap.wrap(text, 74))


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


def _grid(name, values, expected="a finite height"):
    """values as a new float64 array [row, column] with row 0 the SOUTH
    edge, C-contiguous (the library's order); InputError if it is not a
    2-D array of real numbers (an infinite one: not what was expected)."""
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
        raise InputError(f"{name}[{r}, {c}] is {a[r, c]}: expected {expected}, or NaN "
                         f"for no data")
    # a copy always: relax writes its result over it (a one-row view is
    # contiguous, and ascontiguousarray would hand back the caller's memory)
    return np.array(a[::-1], dtype=np.float64, order="C", copy=True)


_RELAX_SKIP = ("dx", "zscale", "zoffset", "output_every", "force")


def _tile_word(tile):
    return "x".join(str(int(n)) for n in tile) if isinstance(tile, (tuple, list)) else tile


def relax(heights: np.typing.ArrayLike, dx: float, dy: Optional[float] = None,
          angle: Union[float, str, np.typing.ArrayLike, None] = None,
          closure: Optional[str] = None,
          nu: Optional[float] = None, sides: Optional[str] = None,
          bedrock: Optional[np.typing.ArrayLike] = None, tol: Optional[float] = None,
          threads: Optional[int] = None, *, gamma: Optional[float] = None,
          slope_tol: Optional[float] = None, integrator: Optional[str] = None,
          rest: Optional[str] = None, rkl2_max_stages: Optional[int] = None,
          rkl2_tol: Optional[float] = None, rkl2_pouring_tol: Optional[float] = None,
          static_angle: Optional[float] = None, max_time: Optional[float] = None,
          cfl: Optional[float] = None, nodata: Optional[str] = None, open_level: Optional[float] = None,
          add_sand: Optional[str] = None, sand_rate: Optional[float] = None,
          sand_duration: Optional[float] = None,
          tile: Union[str, Tuple[int, int], None] = None, device: Optional[str] = None,
          progress: bool = False) -> Tuple[np.ndarray, Dict[str, Any]]:
    """Relax a DEM array to the angle of repose, as ``sandslide relax`` does.

    Parameters
    ----------
    heights : array_like, shape (rows, columns)
        Heights in m, ``[row, column]`` with row 0 the NORTH edge (GDAL's
        and rasterio's order); NaN where there is no data.  Any real dtype
        (converted to float64; a masked array's mask becomes NaN).  Not
        modified.
    dx : float
        Cell size west-east, m.
    dy : float, optional
        Cell size south-north, m; dx when None.
    bedrock : array_like, optional
        The non-erodible base, shaped like heights: only the sand above it
        moves.  NaN only where heights is NaN.
    angle : float, str or array_like, optional
        The repose angle, degrees: one for every cell, a raster file, or
        an array shaped like heights (row 0 north; NaN only where heights
        is NaN), each cell's angle as ``--angle FILE`` gives them
        (doc/model.md#materials) (library default: {angle_default}).
    {threads}
    {progress}

    Other Parameters
    ----------------
{options}

    Every keyword left at None takes the library's default; each is
    checked by the library as the command line checks it.  add_sand is
    "rect=X0,Y0,X1,Y1" or "disk=X,Y,R" (m) with sand_rate (m/s) and
    sand_duration (s); tile is "NXxNY" or a pair (nx, ny).

    Returns
    -------
    relaxed : numpy.ndarray
        A new float64 array shaped like heights, row 0 north, NaN where
        heights is.
    report : dict
        The JSON of ``sandslide relax --report``: "steady", "end" ("steady",
        "max time"), "steps", "time", "volume_before", "volume_after",
        "max_slope_after_deg", ...; "input" is "heights", "output"
        "(array)".

    Raises
    ------
    InputError
        Bad input (a ValueError): an array that is not 2-D real numbers,
        an infinite height, an option out of range; the message names the
        keyword (``angle='95': expected degrees in (0, 90)``).
    RunError
        A failure while running (a RuntimeError).
    KeyboardInterrupt
        On Ctrl-C, within a fraction of a second; nothing is returned.

    See Also
    --------
    relax_raster : the same on a raster file or a GDAL dataset.

    Notes
    -----
    The same library as the ``sandslide`` program: the bits equal
    ``sandslide relax`` on the same DEM.  The relaxation runs until steady
    (max abs(dh/dt) < tol and no face above the repose angle) or max_time
    (doc/model.md).  Calls on different arrays may run in different
    threads at once.

    {interrupt}

    Examples
    --------
    >>> y, x = np.mgrid[0:60, 0:60] + 0.5
    >>> pile = np.maximum(20 - np.hypot(x - 30, y - 30), 0)   # 45 deg flanks
    >>> relaxed, report = sandslide.relax(pile, dx=1.0, angle=33)
    >>> report["steady"], round(report["max_slope_after_deg"])
    (True, 33)
    """
    h = _grid("heights", heights)
    angles = None
    if angle is not None and np.ndim(angle) > 0:
        angles = _grid("angle", angle, "degrees in (0, 90)")
        if angles.shape != h.shape:
            raise InputError(f"angle: shape {angles.shape} differs from the heights' "
                             f"{h.shape}")
        angle = None   # the library names the array "(array)"
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
             "integrator": integrator, "rest": rest, "rkl2_max_stages": rkl2_max_stages,
             "rkl2_tol": rkl2_tol, "rkl2_pouring_tol": rkl2_pouring_tol,
             "static_angle": static_angle, "max_time": max_time, "cfl": cfl, "nodata": nodata,
             "open_level": open_level, "add_sand": add_sand, "sand_rate": sand_rate,
             "sand_duration": sand_duration, "tile": _tile_word(tile), "device": device}
    report = ctypes.create_string_buffer(_JSON_BYTES)
    ny, nx = h.shape
    keywords = _keywords("relax", extra=(("dem", "heights", False), ("dy", "dy", False)))
    with _native.Options("relax", keywords) as o:
        o.set("dem", "heights")           # its name in the library's messages
        for key, value in given.items():
            if value is not None:
                o.set(key, _word(value))
        # h is this call's copy: the library may write the result over it
        _native.call(o, _native.lib.ss_relax_heights_angles,
                     (o.ptr, nx, ny, dx, dy, h.ctypes.data,
                      rock.ctypes.data if rock is not None else None,
                      angles.ctypes.data if angles is not None else None, h.ctypes.data,
                      report, len(report)),
                     progress="relax" if progress else None, keywords=keywords)
    return np.ascontiguousarray(h[::-1]), json.loads(report.value.decode())


relax.__doc__ = relax.__doc__.format(
    options=_options_doc("relax", skip=_RELAX_SKIP + ("threads", "angle")),
    angle_default=next(o["default"] for o in options("relax") if o["name"] == "angle"),
    threads=_THREADS_DOC, progress=_PROGRESS_DOC,
    interrupt=_interrupt_note("the surface of that moment is dropped"))


def run(case: PathLike, out: PathLike,
        set: Union[Mapping[str, Any], Sequence[str], str, None] = None, *,
        unset: Union[str, Sequence[str], None] = None, threads: Optional[int] = None,
        force: bool = False, device: Optional[str] = None,
        progress: bool = False) -> Dict[str, Any]:
    """Run a case file, as ``sandslide run CASE -o OUT [--set ...]`` does.

    Parameters
    ----------
    case : str or os.PathLike
        The case file (.ini; doc/case-file.md).
    out : str or os.PathLike
        The output .h5 (doc/output.md).  Its folder must exist.
    set : dict or list of str or str, optional
        Overrides of the case, {{"section.key": value}} or
        ["section.key=value", ...] (``--set``), applied in order; a key of
        the case they make redundant is dropped (the summary's "notes" say
        which).
    unset : str or list of str, optional
        Keys ("section.key") or wall, open and source sections ("source
        pour") to drop (``--unset``), applied before set.
    {threads}
    force : bool, optional
        Replace an existing output; without it an existing out is refused.
    device : str, optional
        "cpu" (the default), or "cuda" / "cuda:N" in a build with CUDA
        (doc/gpu.md): a GPU that is not there, or a build without CUDA, is
        an InputError with the reason.
    {progress}

    Returns
    -------
    dict
        The summary: "output", "end" ("done", "steady", "not steady"),
        "snapshots", "time" (s), "steps", "evaluations", "integrator",
        "threads", "wall_seconds", "notes", ...

    Raises
    ------
    InputError
        A bad case, override or output (a ValueError), e.g. an existing
        out without ``force=True``.
    RunError
        A failure while running (a RuntimeError).
    KeyboardInterrupt
        On Ctrl-C, within a fraction of a second.

    Notes
    -----
    The same library as ``sandslide run``: the same file.  The output's
    history attribute records the call.  Runs into different outputs may
    run in different threads at once; with an HDF5 that is not
    thread-safe they take turns (doc/python.md#threads).

    {interrupt}

    Examples
    --------
    >>> s = sandslide.run("cases/cone.ini", "out/cone.h5",
    ...                   set={{"time.end": 2}})      # doctest: +SKIP
    >>> s["end"], s["snapshots"]                  # doctest: +SKIP
    ('done', 5)
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
    # the library's run options that are run()'s keywords: restart is not
    keywords = _keywords("run", rename=(("output", "out"),),
                         only=("case", "output", "set", "unset", "threads", "force", "device"))
    with _native.Options("run", keywords) as o:
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
        if device is not None:
            o.set("device", _word(device))
        _native.call(o, _native.lib.ss_run_case_json,
                     (o.ptr, summary, len(summary)), progress="run" if progress else None,
                     keywords=keywords, hdf5=True)
    return json.loads(summary.value.decode())


run.__doc__ = run.__doc__.format(
    threads=_THREADS_DOC, progress=_PROGRESS_DOC,
    interrupt=_interrupt_note("writes a last snapshot of that moment, so "
                                     "the file ends at a complete snapshot"))
def _is_gdal_dataset(source):
    return type(source).__name__ == "Dataset" and \
        type(source).__module__.split(".")[0] == "osgeo"


def relax_raster(source: Union[str, os.PathLike, osgeo.gdal.Dataset], output: PathLike, *,
                 force: bool = False, bedrock: Optional[PathLike] = None,
                 threads: Optional[int] = None, progress: bool = False,
                 **relax_keywords: Any) -> Dict[str, Any]:
    """Relax a raster file or a GDAL dataset into a raster file, as
    ``sandslide relax SOURCE -o OUTPUT`` does.

    Parameters
    ----------
    source : str or os.PathLike or osgeo.gdal.Dataset
        The DEM: a path in any format ``sandslide relax`` reads (GeoTIFF
        and the other GDAL rasters, .asc, 16-bit PNG, FILE.h5[:/dataset]),
        or an open GDAL dataset of one band (saved as a temporary GeoTIFF
        first, so that it is read exactly as a file is).
    output : str or os.PathLike
        The relaxed raster, its format from the extension (.tif, .asc,
        .png, .h5 for the series of snapshots), written with the source's
        georeferencing (geotransform, CRS) and nodata value, under a
        temporary name and renamed when complete.
    force : bool, optional
        Replace an existing output; else it is refused.
    bedrock : str or os.PathLike, optional
        A raster of the non-erodible base, on the source's grid.
    {threads}
    {progress}
    **relax_keywords
        Any other option of relax (`relax`'s keywords: angle, closure,
        nu, tol, max_time, nodata, tile, ...), and those of rasters:
        dx (the cell size of a raster without a geotransform), zscale and
        zoffset (PNG), output_every (an .h5 output).

    Returns
    -------
    dict
        The report, the JSON of ``sandslide relax --report``; "input" names
        the source (a dataset by its description), "output" the file.

    Raises
    ------
    InputError
        A source the library refuses (a ValueError): a geographic CRS in
        degrees (the message gives the ``gdalwarp -t_srs`` command that
        reprojects it), a rotated raster, more than one band, a
        non-finite height, an existing output without ``force=True``, a
        bad option (named as the keyword).
    RunError
        A failure while running or writing (a RuntimeError).
    KeyboardInterrupt
        On Ctrl-C, within a fraction of a second.

    Notes
    -----
    The library reads, checks and writes the files itself, as the command
    line does: the output's bits equal ``sandslide relax`` on the same
    file, and nodata cells stay nodata (walls by default, nodata="open"
    lets sand out there).

    {interrupt}

    Examples
    --------
    >>> report = sandslide.relax_raster("terrain.tif", "terrain-relaxed.tif",
    ...                                 angle=33)          # doctest: +SKIP
    >>> from osgeo import gdal
    >>> ds = gdal.Open("terrain.tif")                        # doctest: +SKIP
    >>> report = sandslide.relax_raster(ds, "relaxed.tif", force=True)  # doctest: +SKIP
    """
    keywords = _keywords("relax", rename=(("dem", "source"),))
    name = None
    scratch = None
    try:
        if _is_gdal_dataset(source):
            from osgeo import gdal
            scratch = tempfile.TemporaryDirectory(prefix="sandslide-")
            path = os.path.join(scratch.name, "source.tif")
            desc = source.GetDescription()
            name = desc if desc else "(GDAL dataset)"
            copy = gdal.GetDriverByName("GTiff").CreateCopy(path, source)
            if copy is None:
                raise RunError(f"{name}: cannot save the dataset as a GeoTIFF for the "
                               f"library: {gdal.GetLastErrorMsg()}")
            copy = None   # closed: written
        else:
            path = os.fspath(source)
        out = os.fspath(output)
        history = f"python: sandslide.relax_raster({name or path!r}, {out!r})"
        report = ctypes.create_string_buffer(_JSON_BYTES)
        touches_h5 = any(os.fspath(p).split(":/")[0].endswith(".h5")
                         for p in (path, out, bedrock or "") if p)
        with _native.Options("relax", keywords) as o:
            o.set("dem", path)
            o.set("output", out)
            o.set("history", history)
            if force:
                o.set("force", "1")
            if bedrock is not None:
                o.set("bedrock", os.fspath(bedrock))
            if threads is not None:
                o.set("threads", _word(threads))
            for key, value in relax_keywords.items():
                if value is not None:
                    o.set(key, _word(_tile_word(value) if key == "tile" else value))
            _native.call(o, _native.lib.ss_relax_file_json, (o.ptr, report, len(report)),
                         progress="relax" if progress else None, keywords=keywords,
                         hdf5=touches_h5)
        result = json.loads(report.value.decode())
        if name is not None:
            result["input"] = name
        return result
    except Error as e:
        if name is None:
            raise
        # the temporary copy is no name the caller knows
        raise type(e)(str(e).replace(path, name)) from None
    finally:
        if scratch is not None:
            scratch.cleanup()


relax_raster.__doc__ = relax_raster.__doc__.format(
    threads=_THREADS_DOC, progress=_PROGRESS_DOC,
    interrupt=_interrupt_note("the output holds the surface of that moment"))


def _fit_bound(name, bounds):
    """--param's word for one entry of fit's params: (lo, hi) or
    (lo, hi, "log"), or the word itself."""
    if isinstance(bounds, str):
        return f"{name}={bounds}"
    lo, hi, *scale = bounds
    return f"{name}={_word(lo)}:{_word(hi)}" + (f":{scale[0]}" if scale else "")


def fit(case: PathLike, observations: PathLike,
        params: Mapping[str, Union[Tuple[float, float], Tuple[float, float, str], str]],
        closures: Union[str, Sequence[str], None] = None, *, cost: Optional[str] = None,
        threshold: Optional[float] = None, out: Optional[PathLike] = None,
        plot: Optional[PathLike] = None, threads: Optional[int] = None, force: bool = False,
        progress: bool = False, **options: Any) -> Dict[str, Any]:
    """Fit a closure and its parameters to observations, as ``sandslide fit
    CASE OBS --param ...`` does (doc/fit.md).

    Parameters
    ----------
    case : str or os.PathLike
        The case file: geometry, walls, sources, the initial state.
    observations : str or os.PathLike
        A height series (.h5 in sandslide's layout), a CSV "time,path" of
        rasters, or a CSV "time,x,y" of points on the front.
    params : dict
        The [model] keys to free with their bounds: (lo, hi), (lo, hi,
        "log") or the command line's "LO:HI[:log]", e.g. {{"nu": (0.01, 1,
        "log"), "repose_angle": (30, 40)}}; at most 4.
    closures : str or list of str, optional
        "all", a list of closure names, or None for the case's closure.
    cost : {{"height", "support", "both"}}, optional
        The cost functional; None chooses by the observations.
    threshold : float, optional
        Sand thicker than this (m) is in the support.
    out, plot : str or os.PathLike, optional
        The report (FIT.json) and its figure (FIT.png) to write.
    {threads}
    force : bool, optional
        Replace out and plot if they exist; else an existing one is refused.
    {progress}
    **options
        Any other option of ``sandslide fit --help`` by its name ('_' for
        '-'), listed below.

    Other Parameters
    ----------------
{options}

    Returns
    -------
    dict
        The report: "best" {{"closure", "params", "cost"}}, "closures" (each
        with "params", "uncertainty", "identifiable", "cost", "aic",
        "evaluations", "profile"), "indistinguishable", "verdict",
        "cost_functional", "observations", "forward_runs", "seconds",
        "interrupted".

    Raises
    ------
    InputError
        Bad options, case or observations (a ValueError).
    RunError
        A failure while fitting (a RuntimeError).
    KeyboardInterrupt
        On Ctrl-C, within a fraction of a second.

    Notes
    -----
    A fit is many forward runs of the case (the report's "forward_runs");
    try the bounds on a coarse copy of the case first.  With an HDF5 that
    is not thread-safe, fits take turns with runs (doc/python.md#threads).

    {interrupt}

    Examples
    --------
    >>> report = sandslide.fit("cases/cone.ini", "scan.h5", {{"nu": (0.01, 1, "log")}},
    ...                        closures="all", out="fit.json")   # doctest: +SKIP
    >>> report["best"]["closure"], report["verdict"]             # doctest: +SKIP
    """
    if isinstance(closures, (list, tuple)):
        closures = ",".join(closures)
    report = ctypes.create_string_buffer(1 << 20)   # profiles of 4 closures: tens of kB
    keywords = _keywords("fit", rename=(("output", "out"), ("param", "params")),
                         extra=(("case", "case", False),
                                ("observations", "observations", False)))
    with _native.Options("fit", keywords) as o:
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
        _native.call(o, _native.lib.ss_fit_run_json,
                     (o.ptr, report, len(report)), progress="fit" if progress else None,
                     keywords=keywords, hdf5=True)
    return json.loads(report.value.decode())


fit.__doc__ = fit.__doc__.format(
    options=_options_doc("fit", skip=("closures", "cost", "threshold", "force", "threads")),
    threads=_THREADS_DOC, progress=_PROGRESS_DOC,
    interrupt=_interrupt_note("writes out with \"interrupted\": true and the "
                                     "best so far"))


def open(path: PathLike, *, timedelta: bool = False, **kwargs: Any) -> xarray.Dataset:
    """The output of a run (or of ``relax -o OUT.h5``) as an xarray Dataset.

    Parameters
    ----------
    path : str or os.PathLike
        The .h5 output.
    timedelta : bool, optional
        False (the default): time stays float seconds, as the file stores
        it, so that plots read seconds.  True: decoded as numpy
        timedelta64 (xarray's default for units "seconds", whose axes then
        read nanoseconds).
    **kwargs
        Passed to xarray.open_dataset (a decode_timedelta given here wins
        over timedelta).  The snapshots are those the file's time counts:
        a run killed in the middle of a snapshot leaves height one longer,
        and that unfinished one is left out.

    Returns
    -------
    xarray.Dataset
        height(time, y, x), time, x, y, the diagnostics, the case in the
        attributes.  Lazy: close it, or use ``with``.

    Raises
    ------
    ImportError
        Without xarray, or without netCDF4 or h5netcdf for it.
    InputError
        A file that is not a sandslide output, or is damaged: the message
        is the one ``sandslide info`` prints.

    Notes
    -----
    The layout is doc/output.md's; y rises northwards (row 0 is the
    south edge in the file).

    Examples
    --------
    >>> with sandslide.open("out/cone.h5") as ds:          # doctest: +SKIP
    ...     ds["height"].isel(time=-1).plot()
    """
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
    decode = kwargs.pop("decode_timedelta", bool(timedelta))
    try:
        ds = xarray.open_dataset(os.fspath(path), engine=engine, decode_timedelta=False,
                                 **kwargs)
    except (OSError, ValueError):
        # netCDF's "[Errno -101] NetCDF: HDF error" says nothing of what is
        # wrong; the library's reader says what `sandslide info` says (which
        # dataset is damaged, or that it is not an output at all)
        if not os.path.isfile(os.fspath(path)):
            raise
        _native.explain_output(os.fspath(path))
        raise
    # A run killed between a snapshot's two flushes leaves height and the
    # diagnostics one longer than time, which netCDF reads as one more time
    # that was never written (the default fill value, 9.97e36): the
    # complete snapshots are the leading ones with a time written
    # (doc/output.md#written-as-the-run-goes).
    if "time" in ds.dims and "time" in ds.variables and ds["time"].dtype.kind == "f":
        t = ds["time"].values
        written = np.isfinite(t) & (np.abs(t) < 1e36)
        complete = len(t) if written.all() else int(np.argmin(written))
        if complete < len(t):
            ds = ds.isel(time=slice(0, complete))
        if decode and ds["time"].attrs.get("units") == "seconds":
            # as xarray decodes units "seconds", after the trim (the fill
            # value overflows timedelta64)
            attrs = {k: v for k, v in ds["time"].attrs.items() if k != "units"}
            ds = ds.assign_coords(time=("time", (ds["time"].values * 1e9).astype(
                "timedelta64[ns]"), attrs))
    return ds
