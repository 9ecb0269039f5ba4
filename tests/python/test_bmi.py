# SPDX-License-Identifier: BSD-3-Clause
"""sandslide.bmi.SandslideBmi, the Python BMI over the C BMI.

Run from the top of the repository after `make`:

    SANDSLIDE_LIBRARY=$PWD/build/libsandslide.so.0 PYTHONPATH=python \
        /usr/bin/python3 -m pytest -q tests/python/test_bmi.py

Every BMI function called as the bmi-tester project's stages call a
Python component (bootstrap, info, time, vars, grid, value; written here,
bmi-tester is not in Debian), then the bits: k updates are what
`sandslide.run` writes at k * output_every (h5py); set_value then
update_until is a run of the same case whose initial file holds the
heights set; a refused set changes nothing, down to the bits of the
updates that follow.
"""
import gc
import inspect
import math
import os

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
import sandslide  # conftest.py: this checkout's when not installed
from sandslide.bmi import SandslideBmi, UnsupportedError

ELEV = "land_surface__elevation"
NX, NY, DX, DY = 14, 10, 0.1, 0.12
# A cone slumping towards an open east side (heights change every step);
# dx != dy and an origin off 0, so that swapped axes fail.  As test_bmi.c.
CASE = f"""[grid]
nx = {NX}
ny = {NY}
dx = {DX}
dy = {DY}
origin = 2 -1

[model]
closure = coulomb
repose_angle = 35
nu = 0.1

[time]
end = 1
output_every = 0.25

[boundary]
west = wall
east = open
south = wall
north = wall

[initial]
type = cone
center = 2.7 -0.4
radius = 0.5
angle = 50
height = 0.1
"""
GRID_TYPES = ("none", "scalar", "vector", "unstructured", "unstructured_triangular",
              "rectilinear", "structured_quadrilateral", "uniform_rectilinear",
              "uniform_rectilinear_grid")   # bmi-tester's VALID_GRID_TYPES

# bmipy's Bmi (src/bmipy/bmi.py): every method and its parameters.
BMIPY = {
    "initialize": ["config_file"], "update": [], "update_until": ["time"], "finalize": [],
    "get_component_name": [], "get_input_item_count": [], "get_output_item_count": [],
    "get_input_var_names": [], "get_output_var_names": [],
    "get_var_grid": ["name"], "get_var_type": ["name"], "get_var_units": ["name"],
    "get_var_itemsize": ["name"], "get_var_nbytes": ["name"], "get_var_location": ["name"],
    "get_current_time": [], "get_start_time": [], "get_end_time": [], "get_time_units": [],
    "get_time_step": [],
    "get_value": ["name", "dest"], "get_value_ptr": ["name"],
    "get_value_at_indices": ["name", "dest", "inds"], "set_value": ["name", "src"],
    "set_value_at_indices": ["name", "inds", "src"],
    "get_grid_rank": ["grid"], "get_grid_size": ["grid"], "get_grid_type": ["grid"],
    "get_grid_shape": ["grid", "shape"], "get_grid_spacing": ["grid", "spacing"],
    "get_grid_origin": ["grid", "origin"], "get_grid_x": ["grid", "x"],
    "get_grid_y": ["grid", "y"], "get_grid_z": ["grid", "z"],
    "get_grid_node_count": ["grid"], "get_grid_edge_count": ["grid"],
    "get_grid_face_count": ["grid"], "get_grid_edge_nodes": ["grid", "edge_nodes"],
    "get_grid_face_edges": ["grid", "face_edges"], "get_grid_face_nodes": ["grid", "face_nodes"],
    "get_grid_nodes_per_face": ["grid", "nodes_per_face"],
}


def same_bits(a, b):
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def empty_var_buffer(bmi, name):
    """Random bytes of the variable's size and type, as bmi-tester's."""
    dtype = np.dtype(bmi.get_var_type(name))
    return np.frombuffer(np.random.bytes(bmi.get_var_nbytes(name)), dtype=dtype).copy()


@pytest.fixture
def case(tmp_path):
    path = tmp_path / "cone.ini"
    path.write_text(CASE)
    return path


@pytest.fixture
def bmi(case):
    m = SandslideBmi()
    m.initialize(str(case))
    yield m
    m.finalize()


def heights(m):
    return m.get_value(ELEV, np.empty(m.get_grid_size(m.get_var_grid(ELEV))))


# ---- bootstrap ---------------------------------------------------------------

def test_has_bmipys_methods_and_signatures():
    for name, params in BMIPY.items():
        f = getattr(SandslideBmi, name, None)
        assert callable(f), f"SandslideBmi has no {name}"
        got = list(inspect.signature(f).parameters)[1:]
        assert got == params, f"{name}{tuple(got)}: bmipy's is {name}{tuple(params)}"
    try:
        import bmipy
    except ImportError:
        return
    assert issubclass(SandslideBmi, bmipy.Bmi)


def test_bootstrap(case, tmp_path):
    m = SandslideBmi()
    with pytest.raises(sandslide.InputError, match="not initialized"):
        m.get_current_time()
    with pytest.raises(sandslide.InputError, match="not initialized"):
        m.update()
    m.finalize()                                     # a no-op before initialize
    for _ in range(2):                               # the message both times
        with pytest.raises(sandslide.InputError, match=r"cannot .*missing\.ini"):
            m.initialize(str(tmp_path / "missing.ini"))
    with pytest.raises(sandslide.InputError, match="not initialized"):
        m.get_component_name()                       # nothing kept of it
    assert m.initialize(str(case)) is None
    with pytest.raises(sandslide.InputError, match="already initialized"):
        m.initialize(str(case))
    assert m.update() is None
    assert m.finalize() is None
    m.finalize()
    with pytest.raises(sandslide.Error):
        m.get_current_time()
    m.initialize(case)                               # a PathLike, again
    assert m.get_current_time() == 0.0
    m.finalize()
    with SandslideBmi() as w:
        w.initialize(str(case))
        w.update()
    with pytest.raises(sandslide.InputError):
        w.get_current_time()                         # finalized on leaving
    g = SandslideBmi()
    g.initialize(str(case))
    del g                                            # finalized when collected
    gc.collect()


def test_a_bad_case_gives_the_librarys_message(tmp_path):
    bad = tmp_path / "bad.ini"
    bad.write_text(CASE.replace("closure = coulomb", "closure = colomb"))
    with pytest.raises(sandslide.InputError, match="closure = 'colomb' is not valid"):
        SandslideBmi().initialize(str(bad))


# ---- info --------------------------------------------------------------------

def test_info(bmi):
    assert bmi.get_component_name() == "sandslide"
    names_in, names_out = bmi.get_input_var_names(), bmi.get_output_var_names()
    assert isinstance(names_in, tuple) and isinstance(names_out, tuple)
    assert all(isinstance(n, str) for n in names_in + names_out)
    assert bmi.get_input_item_count() == len(names_in) and ELEV in names_in
    assert bmi.get_output_item_count() == len(names_out) and names_out[0] == ELEV
    for n in ("sand__volume", "sand__time_integral_of_source_volume_flux",
              "sand__time_integral_of_outflow_volume_flux",
              "sand_surface__max_of_slope_angle"):
        assert n in names_out


# ---- time --------------------------------------------------------------------

def test_time(bmi):
    start, step, end = bmi.get_start_time(), bmi.get_time_step(), bmi.get_end_time()
    assert all(isinstance(v, float) for v in (start, step, end))
    assert (start, step, end) == (0.0, 0.25, 1.0)
    assert bmi.get_time_units() == "s"
    assert start <= bmi.get_current_time() <= end
    assert bmi.update() is None and bmi.get_current_time() == 0.25
    with pytest.raises(sandslide.InputError, match="at or after the current time"):
        bmi.update_until(0.1)
    assert bmi.get_current_time() == 0.25
    assert bmi.update_until(0.3) is None and bmi.get_current_time() == 0.3
    bmi.update()
    assert bmi.get_current_time() == 0.3 + 0.25      # off the lattice: + step
    for bad in (math.nan, math.inf, "soon"):
        with pytest.raises(sandslide.InputError):
            bmi.update_until(bad)
    bmi.update_until(0.55)                           # now: nothing to do
    assert bmi.get_current_time() == 0.55


# ---- vars --------------------------------------------------------------------

def test_vars(bmi):
    units = {ELEV: "m", RATE: "m s-1", "sand__external_volume_change": "m3",
             "sand__volume": "m3", "sand__time_integral_of_source_volume_flux": "m3",
             "sand__time_integral_of_outflow_volume_flux": "m3",
             "sand_surface__max_of_slope_angle": "deg"}
    for name in set(bmi.get_input_var_names() + bmi.get_output_var_names()):
        grid = bmi.get_var_grid(name)
        assert isinstance(grid, int)
        itemsize, nbytes = bmi.get_var_itemsize(name), bmi.get_var_nbytes(name)
        assert itemsize == 8 and nbytes == itemsize * bmi.get_grid_size(grid), name
        assert bmi.get_var_type(name) == "float64"
        np.empty(1, dtype=bmi.get_var_type(name))
        assert bmi.get_var_location(name) in ("node", "edge", "face", "none")
        if name in units:
            assert bmi.get_var_units(name) == units[name]
    assert bmi.get_var_grid(ELEV) == 0 and bmi.get_var_location(ELEV) == "node"
    for f in ("get_var_grid", "get_var_type", "get_var_units", "get_var_itemsize",
              "get_var_nbytes", "get_var_location"):
        with pytest.raises(sandslide.InputError, match="no variable 'sea_water__depth'"):
            getattr(bmi, f)("sea_water__depth")


# ---- grid --------------------------------------------------------------------

def test_grid(bmi, tmp_path, case):
    grids = {bmi.get_var_grid(n) for n in bmi.get_output_var_names()}
    assert grids == {0, 1}
    for g in grids:
        rank, size, gtype = bmi.get_grid_rank(g), bmi.get_grid_size(g), bmi.get_grid_type(g)
        assert isinstance(rank, int) and rank <= 3
        assert isinstance(size, int) and size > 0
        assert gtype in GRID_TYPES
        if gtype == "scalar":
            assert rank == 0 and size == 1
            with pytest.raises(UnsupportedError):
                bmi.get_grid_shape(g, np.empty(0, np.int32))
    assert bmi.get_grid_type(0) == "uniform_rectilinear" and bmi.get_grid_rank(0) == 2
    assert bmi.get_grid_size(0) == NX * NY
    shape = np.empty(2, dtype=np.int32)
    assert bmi.get_grid_shape(0, shape) is shape and list(shape) == [NY, NX]
    shape64 = np.empty(2, dtype=np.int64)
    assert bmi.get_grid_shape(0, shape64) is shape64 and list(shape64) == [NY, NX]
    spacing = np.empty(2)
    assert bmi.get_grid_spacing(0, spacing) is spacing and list(spacing) == [DY, DX]
    origin = np.empty(2)
    assert bmi.get_grid_origin(0, origin) is origin
    # the centre of the south-west cell: the HDF5 output's y[0], x[0]
    h5py = pytest.importorskip("h5py")
    sandslide.run(case, tmp_path / "cone.h5", threads=1)
    with h5py.File(tmp_path / "cone.h5", "r") as f:
        assert origin[0] == pytest.approx(f["y"][0], abs=1e-12)
        assert origin[1] == pytest.approx(f["x"][0], abs=1e-12)
    with pytest.raises(sandslide.InputError, match="no grid 2"):
        bmi.get_grid_rank(2)
    with pytest.raises(sandslide.InputError, match="no grid -1"):
        bmi.get_grid_size(-1)
    with pytest.raises(sandslide.InputError, match="3 items, expected 2"):
        bmi.get_grid_spacing(0, np.empty(3))
    with pytest.raises(sandslide.InputError, match="dtype"):
        bmi.get_grid_spacing(0, np.empty(2, np.float32))
    for f in ("get_grid_x", "get_grid_y", "get_grid_z"):
        with pytest.raises(NotImplementedError, match="get_grid_origin"):
            getattr(bmi, f)(0, np.empty(NX))
    for f in ("get_grid_node_count", "get_grid_edge_count", "get_grid_face_count"):
        with pytest.raises(UnsupportedError):
            getattr(bmi, f)(0)
    for f in ("get_grid_edge_nodes", "get_grid_face_edges", "get_grid_face_nodes",
              "get_grid_nodes_per_face"):
        with pytest.raises(UnsupportedError):
            getattr(bmi, f)(0, np.empty(4, np.int32))


# ---- value -------------------------------------------------------------------

def test_value(bmi):
    for name in bmi.get_output_var_names():
        values = empty_var_buffer(bmi, name)
        values[...] = np.nan                          # bmi-tester: the call fills it
        assert bmi.get_value(name, values) is values
        assert np.all(np.isfinite(values)), name
    h = heights(bmi)
    h2 = np.empty((NY, NX))                           # any shape of the right size
    assert bmi.get_value(ELEV, h2) is h2 and same_bits(h2.ravel(), h)
    hf = np.empty((NY, NX), order="F")                # filled in C order all the same
    assert same_bits(bmi.get_value(ELEV, hf).ravel(), h)
    hl = np.empty(NX * NY, np.longdouble)             # float64 converts to it safely
    assert np.array_equal(bmi.get_value(ELEV, hl), h)
    with pytest.raises(sandslide.InputError, match="139 items, expected 140"):
        bmi.get_value(ELEV, np.empty(NX * NY - 1))
    with pytest.raises(sandslide.InputError, match="float32"):
        bmi.get_value(ELEV, np.empty(NX * NY, np.float32))
    with pytest.raises(sandslide.InputError, match="numpy array"):
        bmi.get_value(ELEV, [0.0] * (NX * NY))
    with pytest.raises(UnsupportedError, match="use get_value"):
        bmi.get_value_ptr(ELEV)
    inds = np.array([0, NX + 3, NX * NY - 1])
    some = np.empty(3)
    assert bmi.get_value_at_indices(ELEV, some, inds) is some
    assert same_bits(some, h[inds])
    with pytest.raises(sandslide.InputError, match="outside"):
        bmi.get_value_at_indices(ELEV, np.empty(2), [0, NX * NY])
    with pytest.raises(sandslide.InputError, match="outside"):
        bmi.get_value_at_indices(ELEV, np.empty(1), [-1])
    with pytest.raises(sandslide.InputError, match="integers"):
        bmi.get_value_at_indices(ELEV, np.empty(1), [0.5])
    vol = np.empty(2)
    assert same_bits(bmi.get_value_at_indices("sand__volume", vol, [0, 0]),
                     np.repeat(bmi.get_value("sand__volume", np.empty(1)), 2))
    assert np.sum(h) * DX * DY == pytest.approx(vol[0], rel=1e-12)


def test_set_value_round_trips(bmi):
    h = 0.3 + 0.001 * np.arange(NX * NY)
    assert bmi.set_value(ELEV, h) is None
    assert same_bits(heights(bmi), h)
    bmi.set_value(ELEV, h.reshape(NY, NX) + 0.5)      # [y][x], row 0 south
    assert same_bits(heights(bmi), h + 0.5)
    bmi.set_value(ELEV, np.arange(NX * NY))           # int64 to float64: safe
    assert same_bits(heights(bmi), np.arange(NX * NY, dtype=np.float64))
    assert bmi.set_value_at_indices(ELEV, [3, 4], np.array([9.0, 8.0])) is None
    got = bmi.get_value_at_indices(ELEV, np.empty(2), np.array([3, 4]))
    assert list(got) == [9.0, 8.0]
    with pytest.raises(sandslide.InputError, match="output only"):
        bmi.set_value("sand__volume", np.ones(1))


def test_a_refused_set_changes_nothing(case):
    """Bad sizes, dtypes, values, names and indices raise, and the model
    is where it was: its heights, its diagnostics and the bits of the
    update that follows are those of a model never asked."""
    with SandslideBmi() as m, SandslideBmi() as untouched:
        m.initialize(str(case))
        untouched.initialize(str(case))
        m.update()
        untouched.update()
        before = heights(m)
        vol = m.get_value("sand__volume", np.empty(1)).copy()
        good = before + 0.01
        bad_nan = good.copy()
        bad_nan[7] = np.nan
        refused = [
            (lambda: m.set_value(ELEV, good[:-1]), "139 items, expected 140"),
            (lambda: m.set_value(ELEV, np.append(good, 1.0)), "141 items"),
            (lambda: m.set_value(ELEV, good.astype(np.complex128)), "complex128"),
            (lambda: m.set_value(ELEV, good.astype(np.float128) if hasattr(np, "float128")
                                 else good.astype(object)), "convert"),
            (lambda: m.set_value(ELEV, ["a"] * (NX * NY)), "convert"),
            (lambda: m.set_value(ELEV, bad_nan), "item 7 is not finite"),
            (lambda: m.set_value("sea_water__depth", good), "no variable"),
            (lambda: m.set_value_at_indices(ELEV, [3, NX * NY], np.ones(2)), "outside"),
            (lambda: m.set_value_at_indices(ELEV, [3, 4], np.ones(3)), "3 items, expected 2"),
        ]
        for call, message in refused:
            with pytest.raises(sandslide.InputError, match=message):
                call()
            assert same_bits(heights(m), before), f"a refused set ({message}) changed heights"
        assert same_bits(m.get_value("sand__volume", np.empty(1)), vol)
        m.update()
        untouched.update()
        assert same_bits(heights(m), heights(untouched)), \
            "the update after refused sets differs from the update of an untouched model"
        assert not same_bits(heights(m), before), "the heights moved (the test means something)"


# ---- the bits ----------------------------------------------------------------

def test_k_updates_are_what_run_writes(bmi, case, tmp_path):
    h5py = pytest.importorskip("h5py")
    sandslide.run(case, tmp_path / "cone.h5", threads=1)
    with h5py.File(tmp_path / "cone.h5", "r") as f:
        times, series = f["time"][:], f["height"][:]
    assert len(times) == 5 and series.shape == (5, NY, NX)
    assert not same_bits(series[0], series[-1]), "the cone moved"
    for k, t in enumerate(times):
        if k > 0:
            bmi.update()
        assert bmi.get_current_time() == t
        assert same_bits(heights(bmi), series[k].ravel()), \
            f"the heights after {k} updates are not run's at {t} s"


def write_asc(path, h, dx, x0, y0):
    """h [y][x], row 0 south, as an .asc (north row first, %.17g)."""
    ny, nx = h.shape
    rows = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in h[::-1])
    path.write_text(f"ncols {nx}\nnrows {ny}\nxllcorner {x0}\nyllcorner {y0}\n"
                    f"cellsize {dx:.17g}\n{rows}\n")


@pytest.mark.parametrize("integrator", ["euler", "rkl2"])
def test_set_value_then_update_until_is_a_run_from_a_file(tmp_path, integrator):
    """The issue's bits.  Square cells: a case's [initial] file must give
    dx = dy (src/model/setup.c)."""
    square = tmp_path / "square.ini"
    square.write_text(CASE.replace(f"dy = {DY}\n", "").replace(
        "output_every = 0.25\n", f"output_every = 0.25\nintegrator = {integrator}\n"))
    rng = np.random.default_rng(27)
    h = 0.2 + 0.15 * rng.random((NY, NX))            # slopes past the repose angle
    write_asc(tmp_path / "bumps.asc", h, DX, 2, -1)
    h5py = pytest.importorskip("h5py")
    sandslide.run(square, tmp_path / "bumps.h5", threads=1,
                  set={"initial.type": "file", "initial.file": "bumps.asc",
                       "time.end": 0.5, "time.output_every": 0.5})
    with h5py.File(tmp_path / "bumps.h5", "r") as f:
        series = f["height"][:]
    assert same_bits(series[0], h), "run read the file's bits"
    with SandslideBmi() as m:
        m.initialize(str(square))
        m.set_value(ELEV, h)
        m.update_until(0.5)
        got = heights(m)
    assert same_bits(got, series[1].ravel()), \
        f"{integrator}: set_value + update_until(0.5) is not run's bits from the file"
    assert not same_bits(got, h.ravel()), "the bumps moved"


# ---- the deposition rate, the ledger, the bedrock -------------------------------

RATE = "land_surface__net_deposition_rate"
SCALARS = ("sand__volume", "sand__time_integral_of_source_volume_flux",
           "sand__time_integral_of_outflow_volume_flux", "sand__external_volume_change")


def scalars(m):
    return [float(m.get_value(n, np.empty(1))[0]) for n in SCALARS]


def test_the_rate_input_and_the_ledger(bmi):
    assert bmi.get_input_var_names() == (ELEV, RATE, ANGLE)
    assert RATE not in bmi.get_output_var_names()
    assert bmi.get_var_units(RATE) == "m s-1" and bmi.get_var_grid(RATE) == 0
    assert bmi.get_var_location(RATE) == "node"
    assert np.all(bmi.get_value(RATE, np.ones(NX * NY)) == 0.0)      # 0 until set
    v0 = scalars(bmi)[0]
    rate = np.zeros((NY, NX))
    rate[2:5, 3:6] = 1e-3                            # [y][x], row 0 south
    bmi.set_value(RATE, rate)
    assert same_bits(bmi.get_value(RATE, np.empty((NY, NX))), rate)
    bad = rate.copy()
    bad[4, 4] = np.nan
    with pytest.raises(sandslide.InputError, match="rate"):
        bmi.set_value(RATE, bad)
    with pytest.raises(sandslide.InputError, match="139 items"):
        bmi.set_value(RATE, rate.ravel()[:-1])
    assert same_bits(bmi.get_value(RATE, np.empty((NY, NX))), rate), "refused: unchanged"
    bmi.update()
    volume, inflow, outflow, external = scalars(bmi)
    assert inflow == pytest.approx(9 * 1e-3 * 0.25 * DX * DY, rel=1e-12)
    assert external == 0.0
    bmi.set_value(ELEV, heights(bmi) + 0.01)         # every cell is a flow cell here
    volume, inflow, outflow, external = scalars(bmi)
    assert external == pytest.approx(0.01 * NX * NY * DX * DY, rel=1e-12)
    bmi.update()
    volume, inflow, outflow, external = scalars(bmi)
    assert outflow > 0.0
    assert volume - v0 == pytest.approx(inflow - outflow + external, rel=1e-12, abs=1e-15)


ANGLE = "sand__angle_of_repose"


def test_the_angle_input_changes_the_law(bmi):
    """The cone's 50-degree flanks at 35 degrees slide; at 60 they hold to
    the bit, and the angles read back are those set (row 0 south)."""
    assert bmi.get_var_units(ANGLE) == "deg" and ANGLE in bmi.get_output_var_names()
    angles = bmi.get_value(ANGLE, np.empty((NY, NX)))
    assert np.all(angles == 35.0)
    steep = np.full((NY, NX), 60.0)
    steep[0, :] = 61.0                               # the south row: read back there
    bmi.set_value(ANGLE, steep)
    assert same_bits(bmi.get_value(ANGLE, np.empty((NY, NX))), steep)
    before = heights(bmi)
    bmi.update()
    assert same_bits(heights(bmi), before), "the cone moved under a 60-degree angle"
    bad = steep.copy()
    bad[3, 4] = 90.0
    with pytest.raises(sandslide.InputError, match=ANGLE + ".*item 46"):
        bmi.set_value(ANGLE, bad)
    assert same_bits(bmi.get_value(ANGLE, np.empty((NY, NX))), steep), "refused: unchanged"
    bmi.set_value(ANGLE, np.full((NY, NX), 35.0))
    bmi.update()
    assert not same_bits(heights(bmi), before), "the cone did not slide at 35 degrees"


def test_a_bedrock_is_an_output(tmp_path):
    (tmp_path / "rock.asc").write_text("ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\n"
                                       "cellsize 1\n0 0 0 0\n0 0.1 0.1 0\n0 0 0 0\n")
    (tmp_path / "rock.ini").write_text(
        "[grid]\nnx = 4\nny = 3\ndx = 1\n\n[model]\nclosure = coulomb\nrepose_angle = 35\n"
        "nu = 0.1\n\n[time]\nend = 10\noutput_every = 1\n\n"
        "[initial]\ntype = flat\nheight = 0.3\nbedrock = rock.asc\n")
    with SandslideBmi() as m:
        m.initialize(str(tmp_path / "rock.ini"))
        assert m.get_output_var_names()[:3] == (ELEV, ANGLE, "bedrock_surface__elevation")
        rock = m.get_value("bedrock_surface__elevation", np.empty((3, 4)))
        assert rock[1, 1] == 0.1 and rock[1, 2] == 0.1 and rock[0, 0] == 0.0
        rate = np.zeros(12)
        rate[5] = -1e-3
        with pytest.raises(sandslide.InputError):     # erosion over a bedrock
            m.set_value(RATE, rate)
        with pytest.raises(sandslide.InputError, match="output only"):
            m.set_value("bedrock_surface__elevation", rock)
        with pytest.raises(sandslide.InputError, match="below the bedrock"):
            m.set_value(ELEV, np.full(12, 0.05))


def test_a_config_naming_a_dem_is_relax(tmp_path):
    """[bmi] dem = ...: update_until(T) gives sandslide.relax's bits with
    max_time = T (relax's rows are north first, the BMI's south first)."""
    ny, nx = 9, 12
    r, c = np.mgrid[0:ny, 0:nx]
    dem = 0.1 + 0.6 * np.maximum(0.0, 3.0 - np.hypot(c - 5.5, r - 3.0))   # north first
    rows = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in dem)
    (tmp_path / "pile.asc").write_text(f"ncols {nx}\nnrows {ny}\nxllcorner 100\n"
                                       f"yllcorner 200\ncellsize 0.5\n{rows}\n")
    (tmp_path / "dem.cfg").write_text("[bmi]\ndem = pile.asc\ntime_step = 0.5\nangle = 33\n"
                                      "nu = 0.1\nsides = open\n")
    want, _ = sandslide.relax(dem, 0.5, angle=33, nu=0.1, sides="open", max_time=1.0)
    with SandslideBmi() as m:
        m.initialize(str(tmp_path / "dem.cfg"))
        assert m.get_time_step() == 0.5 and m.get_end_time() == math.inf
        assert list(m.get_grid_origin(0, np.empty(2))) == [200.25, 100.25]
        m.update_until(1.0)
        got = m.get_value(ELEV, np.empty((ny, nx)))
    assert same_bits(got[::-1], want), "update_until(1) is not relax with max_time = 1"
    assert not same_bits(got[::-1], dem), "the pile slid"
    (tmp_path / "bad.cfg").write_text("[bmi]\ndem = pile.asc\ntime_step = 1\nangel = 33\n")
    with pytest.raises(sandslide.InputError, match="angel"):
        SandslideBmi().initialize(str(tmp_path / "bad.cfg"))
