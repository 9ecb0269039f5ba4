# SPDX-License-Identifier: BSD-3-Clause
"""How the module's calls behave as calls (issue 27, items 5 and 6):
Ctrl-C stops them, calls in two threads run at once and give the bits
of a lone call, progress=True shows a line, messages name Python's
keywords, open keeps time in seconds, relax_raster gives the CLI's bits.

Run from the top of the repository after `make`:

    PYTHONPATH=python /usr/bin/python3 -m pytest -q tests/python

Ctrl-C is shown on a child process (a SIGINT sent to it once it is in
the library), timed from the signal to its exit.  Random surfaces use
fixed seeds (printed in the messages that need them).
"""
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
import sandslide  # conftest.py: this checkout's when not installed
from sandslide import _native

SANDSLIDE = os.environ.get("SANDSLIDE", os.path.join(ROOT, "build", "sandslide"))
with open(os.path.join(ROOT, "tests", "base.ini")) as _f:
    CASE = _f.read()


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def rough(n, seed):
    """n x n heights up to 100 m on 1 m cells: far above the repose angle
    everywhere, so that relaxing it takes many substeps."""
    return np.random.default_rng(seed).random((n, n)) * 100.0


# ---- Ctrl-C ---------------------------------------------------------------

def interrupt(code, tmp_path):
    """Run code in a child Python that prints "started" just before its
    long call; SIGINT it half a second later; (seconds from the signal to
    its exit, its exit status, its stderr, its stdout)."""
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "python"))
    prologue = ("import signal, sys, numpy as np, sandslide\n"
                # a shell may start a background job with SIGINT ignored
                "signal.signal(signal.SIGINT, signal.default_int_handler)\n")
    child = subprocess.Popen([sys.executable, "-c", prologue + code], cwd=tmp_path, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = child.stdout.readline()
        assert line.strip() == "started", \
            f"the child did not start: {line!r}\n{child.stderr.read()}"
        time.sleep(0.5)   # in the library by now
        assert child.poll() is None, \
            f"the child's call ended before the signal: {child.communicate()}"
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=30)
        return time.monotonic() - sent, child.returncode, err, out
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def test_ctrl_c_stops_relax_within_a_second(tmp_path):
    took, status, err, out = interrupt(
        "h = np.random.default_rng(5).random((300, 300)) * 100\n"
        "print('started', flush=True)\n"
        "sandslide.relax(h, 1.0, threads=1)\n"
        "print('finished', flush=True)\n", tmp_path)
    assert "finished" not in out, "the relax was not interrupted: it finished"
    # Python ends on an uncaught KeyboardInterrupt by SIGINT (not a crash:
    # the library must not run on after the call's memory is freed)
    assert status == -signal.SIGINT and "Traceback" in err and \
        err.rstrip().splitlines()[-1] == "KeyboardInterrupt", \
        f"exit status {status}, expected KeyboardInterrupt's traceback and " \
        f"-SIGINT; stderr:\n{err}"
    assert took < 1.0, f"the relax took {took:.2f} s after SIGINT to stop, expected < 1 s"


def test_ctrl_c_stops_run_with_complete_snapshots(tmp_path):
    h5py = pytest.importorskip("h5py", reason="python3-h5py is not installed")
    (tmp_path / "big.ini").write_text(CASE)
    took, status, err, out = interrupt(
        "print('started', flush=True)\n"
        "sandslide.run('big.ini', 'big.h5', set={'grid.nx': 300, 'grid.ny': 300, "
        "'time.end': 1e5, 'time.output_every': 10}, threads=1)\n"
        "print('finished', flush=True)\n", tmp_path)
    assert "finished" not in out, "the run was not interrupted: it finished"
    assert status == -signal.SIGINT and err.rstrip().splitlines()[-1] == "KeyboardInterrupt", \
        f"exit status {status}, expected KeyboardInterrupt's traceback and -SIGINT; " \
        f"stderr:\n{err}"
    assert took < 1.0, f"the run took {took:.2f} s after SIGINT to stop, expected < 1 s"
    with h5py.File(tmp_path / "big.h5", "r") as f:
        t = f["time"][...]
        height = f["height"][...]
        volume = f["volume"][...] if "volume" in f else None
    assert len(t) >= 2 and height.shape == (len(t), 300, 300), \
        f"{len(t)} times and /height {height.shape}: expected the same count, at least 2"
    assert np.all(np.diff(t) > 0), f"/time does not rise: {t}"
    assert np.isfinite(height).all(), "a snapshot holds non-finite heights: half written"
    assert volume is None or len(volume) == len(t), \
        f"/volume has {len(volume)} entries for {len(t)} snapshots"
    assert not os.path.exists(tmp_path / "big.h5.lock"), "the run's claim was left behind"


# ---- threads --------------------------------------------------------------

def test_two_threads_run_at_once_and_give_the_bits_of_a_lone_call():
    a, b = rough(120, 1), rough(120, 2)
    want_a, _ = sandslide.relax(a, 1.0, threads=1, max_time=600)
    want_b, _ = sandslide.relax(b, 0.5, threads=1, max_time=600)
    got, spans, errors = {}, {}, []

    def work(name, h, dx):
        try:
            t0 = time.monotonic()
            got[name], _ = sandslide.relax(h, dx, threads=1, max_time=600)
            spans[name] = (t0, time.monotonic())
        except BaseException as e:   # noqa: B902 (reported below)
            errors.append(e)

    threads = [threading.Thread(target=work, args=("a", a, 1.0)),
               threading.Thread(target=work, args=("b", b, 0.5))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, f"a thread failed: {errors!r}"
    (a0, a1), (b0, b1) = spans["a"], spans["b"]
    overlap = min(a1, b1) - max(a0, b0)
    assert overlap > 0.5 * min(a1 - a0, b1 - b0), \
        f"the calls hardly overlapped ({overlap:.3f} s of {a1 - a0:.3f} and " \
        f"{b1 - b0:.3f} s): they ran one after the other"
    assert same_bits(got["a"], want_a), "thread a's relax differs from a lone call"
    assert same_bits(got["b"], want_b), "thread b's relax differs from a lone call"


def test_each_call_has_its_own_thread_count(tmp_path, monkeypatch):
    (tmp_path / "tiny.ini").write_text(CASE)
    summaries = {}

    def work(n):
        summaries[n] = sandslide.run(tmp_path / "tiny.ini", tmp_path / f"t{n}.h5",
                                     set={"grid.nx": 120, "grid.ny": 120}, threads=n)

    threads = [threading.Thread(target=work, args=(n,)) for n in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert [summaries[n]["threads"] for n in (1, 2)] == [1, 2], \
        f"threads=1 and threads=2 side by side ran with {summaries[1]['threads']} and " \
        f"{summaries[2]['threads']}"
    # None: OMP_NUM_THREADS, read at the call, not a count left by a call before
    monkeypatch.setenv("OMP_NUM_THREADS", "3")
    s = sandslide.run(tmp_path / "tiny.ini", tmp_path / "t3.h5")
    assert s["threads"] == 3, f"threads=None with OMP_NUM_THREADS=3 ran with {s['threads']}"


def test_a_small_grid_runs_on_one_thread_unless_asked(tmp_path, monkeypatch):
    """threads=None on a 20 x 16 grid: one thread, as a second one would
    only wait at the barriers of each step (doc/running.md#threads)."""
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("this process may use one CPU: one thread anyway")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    (tmp_path / "tiny.ini").write_text(CASE)
    s = sandslide.run(tmp_path / "tiny.ini", tmp_path / "a.h5")
    assert s["threads"] == 1, f"threads=None on a 20 x 16 grid ran with {s['threads']}"
    s = sandslide.run(tmp_path / "tiny.ini", tmp_path / "b.h5", threads=2)
    assert s["threads"] == 2, f"threads=2 ran with {s['threads']}"


def test_importing_makes_idle_threads_sleep_unless_the_user_chose(tmp_path):
    """OMP_WAIT_POLICY=passive is set before the library (and libgomp with
    it) loads; libgomp's OMP_DISPLAY_ENV shows what it read."""
    code = "import os, sandslide; print(os.environ.get('OMP_WAIT_POLICY'))"

    def start(**extra):
        env = {k: v for k, v in os.environ.items()
               if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
        env.update(extra, OMP_DISPLAY_ENV="verbose",
                   PYTHONPATH=os.path.dirname(os.path.dirname(sandslide.__file__)))
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        spin = re.search(r"GOMP_SPINCOUNT = '(\d+)'", r.stderr)
        return r.stdout.strip(), int(spin.group(1)) if spin else None

    said, spin = start()
    assert said == "passive", f"OMP_WAIT_POLICY after the import: {said}"
    if spin is not None:    # libgomp (another runtime does not show it)
        assert spin == 0, f"libgomp read a spin count of {spin}: not passive"
    said, spin = start(OMP_WAIT_POLICY="active")
    assert said == "active" and spin in (None, 30000000000), "the user's policy not kept"
    said, spin = start(GOMP_SPINCOUNT="1000")
    assert said == "None" and spin in (None, 1000), "the user's GOMP_SPINCOUNT not kept"


def test_without_a_thread_safe_hdf5_runs_take_turns(tmp_path, monkeypatch):
    """The lock that an HDF5 built without thread safety needs (Debian's
    is thread-safe, so it is forced here): runs do not overlap, and a
    refused run lets go of it."""
    monkeypatch.setattr(_native, "HDF5_THREADSAFE", False)
    (tmp_path / "tiny.ini").write_text(CASE)
    spans, errors = {}, []

    def work(n):
        try:
            t0 = time.monotonic()
            sandslide.run(tmp_path / "tiny.ini", tmp_path / f"r{n}.h5", threads=1,
                          set={"grid.nx": 150, "grid.ny": 150, "time.end": 20})
            spans[n] = (t0, time.monotonic())
        except BaseException as e:   # noqa: B902 (reported below)
            errors.append(e)

    with pytest.raises(sandslide.InputError):   # refused inside the lock
        sandslide.run(tmp_path / "tiny.ini", tmp_path / "no" / "such" / "r.h5")
    threads = [threading.Thread(target=work, args=(n,)) for n in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not errors and len(spans) == 2, f"runs failed or hung: {errors!r}"
    # by the time they ended (whichever took the lock first, which need not
    # be the one started first): the second waited for the first, so it
    # ended at least about its own run time, the first's, after it
    first, second = sorted(spans.values(), key=lambda span: span[1])
    assert second[1] - first[1] > 0.5 * (first[1] - first[0]), \
        f"the runs overlapped under the HDF5 lock: {spans}"


def test_errors_in_two_threads_keep_their_own_message():
    said, barrier = {}, threading.Barrier(2)

    def work(name, angle):
        barrier.wait()
        for _ in range(50):
            try:
                sandslide.relax(np.zeros((4, 4)), 1.0, angle=angle)
            except sandslide.InputError as e:
                if f"'{angle}'" not in str(e):
                    said[name] = str(e)

    threads = [threading.Thread(target=work, args=("a", 95)),
               threading.Thread(target=work, args=("b", -5))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not said, f"a thread read the other's message: {said}"


# ---- progress -------------------------------------------------------------

def test_progress_prints_a_line_without_tqdm(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "tqdm", None)   # import tqdm fails
    sandslide.relax(rough(120, 3), 1.0, threads=1, max_time=300, progress=True)
    err = capsys.readouterr().err
    assert err.startswith("\rrelax: ") and err.endswith("\n"), \
        f"expected a line rewritten with \\r and ended with a newline: {err!r}"
    assert "%" in err and "steps" in err, f"the line says no fraction or steps: {err!r}"
    sandslide.relax(rough(20, 3), 1.0, threads=1)
    assert capsys.readouterr().err == "", "progress is shown without progress=True"


def test_progress_line_ends_on_an_error(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    (tmp_path / "tiny.ini").write_text(CASE)
    (tmp_path / "tiny.h5").write_text("")
    with pytest.raises(sandslide.InputError):
        sandslide.run(tmp_path / "tiny.ini", tmp_path / "tiny.h5", progress=True)
    err = capsys.readouterr().err
    assert err == "" or err.endswith("\n"), f"a progress line left open: {err!r}"


# ---- messages name the keyword ----------------------------------------------

def test_messages_name_the_keyword_not_the_flag(tmp_path):
    (tmp_path / "tiny.ini").write_text(CASE)
    out = tmp_path / "tiny.h5"
    sandslide.run(tmp_path / "tiny.ini", out, threads=1)
    with pytest.raises(sandslide.InputError) as e:
        sandslide.run(tmp_path / "tiny.ini", out)
    assert "force=True" in str(e.value) and "--" not in str(e.value), \
        f"an existing output without force: {str(e.value)!r} should name force=True"
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax(np.zeros((4, 4)), 1.0, tile="0x3")
    assert str(e.value).startswith("tile='0x3': expected NXxNY"), \
        f"a bad tile: {str(e.value)!r} should start with the keyword tile="
    with pytest.raises(sandslide.InputError) as e:
        sandslide.fit(tmp_path / "tiny.ini", out, {"nu": "0.1:1"}, grid_points=-3)
    assert str(e.value).startswith("grid_points='-3'"), str(e.value)
    # the translation itself, on the words the library uses
    keys = sandslide._keywords("relax")
    said = _native.translate_message("give --force to replace it; --rkl2-tol 0.5 or "
                                     "--max-time; --nosuch stays", keys)
    assert said == "give force=True to replace it; rkl2_tol=0.5 or max_time=; --nosuch " \
                   "stays", said


# ---- open -----------------------------------------------------------------

@pytest.mark.filterwarnings("ignore:numpy.ndarray size changed")
def test_open_time_is_float_seconds(tmp_path):
    pytest.importorskip("xarray", reason="python3-xarray is not installed")
    (tmp_path / "tiny.ini").write_text(CASE)
    out = tmp_path / "tiny.h5"
    sandslide.run(tmp_path / "tiny.ini", out, set={"time.end": 0.75,
                                                   "time.output_every": 0.25}, threads=1)
    with sandslide.open(out) as ds:
        t = ds["time"].values
        assert t.dtype == np.float64 and list(t) == [0.0, 0.25, 0.5, 0.75], \
            f"time {t!r} ({t.dtype}): expected float seconds"
        assert ds["time"].attrs.get("units") == "seconds", ds["time"].attrs
    with sandslide.open(out, timedelta=True) as ds:
        assert ds["time"].dtype.kind == "m", f"timedelta=True gives {ds['time'].dtype}"
        assert list(ds["time"].values / np.timedelta64(250, "ms")) == [0, 1, 2, 3], \
            f"timedelta=True gives {ds['time'].values}"


@pytest.mark.filterwarnings("ignore:numpy.ndarray size changed")
def test_open_leaves_out_the_unfinished_snapshot_of_a_killed_run(tmp_path):
    """A kill between a snapshot's two flushes leaves height and the
    diagnostics one longer than /time (doc/output.md); netCDF reads that
    as one more time, never written: open gives the complete ones."""
    pytest.importorskip("xarray", reason="python3-xarray is not installed")
    h5py = pytest.importorskip("h5py", reason="python3-h5py is not installed")
    (tmp_path / "tiny.ini").write_text(CASE)
    out = tmp_path / "tiny.h5"
    sandslide.run(tmp_path / "tiny.ini", out, set={"time.end": 0.5,
                                                   "time.output_every": 0.25}, threads=1)
    with h5py.File(out, "a") as f:        # the state a kill can leave
        grown = [k for k in f if k != "time" and f[k].maxshape and f[k].maxshape[0] is None]
        for k in grown:
            f[k].resize(f[k].shape[0] + 1, axis=0)
    assert "height" in grown, grown
    for timedelta in (False, True):
        with sandslide.open(out, timedelta=timedelta) as ds:
            assert ds.sizes["time"] == 3 and ds["height"].shape[0] == 3, \
                f"timedelta={timedelta}: {ds.sizes['time']} snapshots, expected the 3 complete"


# ---- relax_raster ---------------------------------------------------------

def gdal():
    g = pytest.importorskip("osgeo.gdal", reason="python3-gdal is not installed")
    g.UseExceptions()
    return g


def geotiff(path, h, gt=(500000.0, 2.0, 0.0, 5200000.0, 0.0, -2.0), epsg=32633,
            nodata=-9999.0):
    """h [row, column] row 0 north as a Float64 GeoTIFF."""
    g = gdal()
    from osgeo import osr
    ds = g.GetDriverByName("GTiff").Create(str(path), h.shape[1], h.shape[0], 1,
                                           g.GDT_Float64)
    ds.SetGeoTransform(gt)
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(epsg)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.WriteArray(h)
    ds = None


def cli_available():
    return os.access(SANDSLIDE, os.X_OK)


def test_relax_raster_gives_the_clis_bits_and_keeps_the_georeferencing(tmp_path):
    g = gdal()
    if not cli_available():
        pytest.skip(f"no {SANDSLIDE}: run make")
    h = rough(48, 7)[:40] * 0.2
    h[5, 6] = h[30, 40] = -9999.0           # no data
    geotiff(tmp_path / "dem.tif", h)
    r = subprocess.run([SANDSLIDE, "relax", "dem.tif", "-o", "cli.tif", "--threads", "1",
                        "-q", "--angle", "33"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    report = sandslide.relax_raster(tmp_path / "dem.tif", tmp_path / "py.tif", threads=1,
                                    angle=33)
    assert report["steady"] and report["input"] == str(tmp_path / "dem.tif"), report
    src = g.Open(str(tmp_path / "dem.tif"))
    report = sandslide.relax_raster(src, tmp_path / "ds.tif", threads=1, angle=33)
    assert report["input"] == str(tmp_path / "dem.tif"), \
        f"a dataset's report names {report['input']!r}, expected its description"
    want = g.Open(str(tmp_path / "cli.tif"))
    for name in ("py.tif", "ds.tif"):
        got = g.Open(str(tmp_path / name))
        assert same_bits(got.ReadAsArray(), want.ReadAsArray()), \
            f"{name} differs from sandslide relax's output"
        assert got.GetGeoTransform() == src.GetGeoTransform(), \
            f"{name}: geotransform {got.GetGeoTransform()}, source {src.GetGeoTransform()}"
        assert got.GetProjection() == src.GetProjection(), f"{name}: the CRS was not kept"
        band = got.GetRasterBand(1)
        assert band.GetNoDataValue() == -9999.0, f"{name}: nodata {band.GetNoDataValue()}"
        a = band.ReadAsArray()
        assert a[5, 6] == -9999.0 and a[30, 40] == -9999.0, f"{name}: nodata cells changed"


def test_relax_raster_refuses_degrees_and_an_existing_output(tmp_path):
    g = gdal()
    h = rough(20, 8)
    geotiff(tmp_path / "deg.tif", h, gt=(10.0, 0.001, 0.0, 45.0, 0.0, -0.001), epsg=4326)
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax_raster(tmp_path / "deg.tif", tmp_path / "out.tif")
    said = str(e.value)
    assert "degrees, not metres" in said and "gdalwarp -t_srs EPSG:32632" in said, said
    assert not os.path.exists(tmp_path / "out.tif"), "a refused source left an output"
    mem = g.GetDriverByName("MEM").Create("", 20, 20, 1, g.GDT_Float64)
    mem.SetGeoTransform((10.0, 0.001, 0.0, 45.0, 0.0, -0.001))
    mem.SetProjection(g.Open(str(tmp_path / "deg.tif")).GetProjection())
    mem.GetRasterBand(1).WriteArray(h)
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax_raster(mem, tmp_path / "out.tif")
    assert "gdalwarp -t_srs" in str(e.value) and "sandslide-" not in str(e.value), \
        f"a dataset in degrees: {str(e.value)!r} (no temporary path expected)"

    geotiff(tmp_path / "dem.tif", h)
    (tmp_path / "out.tif").write_bytes(b"keep")
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax_raster(tmp_path / "dem.tif", tmp_path / "out.tif", threads=1)
    assert "exists" in str(e.value) and "force=True" in str(e.value), str(e.value)
    assert (tmp_path / "out.tif").read_bytes() == b"keep", "the existing output was touched"
    sandslide.relax_raster(tmp_path / "dem.tif", tmp_path / "out.tif", threads=1, force=True)
    assert g.Open(str(tmp_path / "out.tif")).RasterXSize == 20, "force=True did not replace it"


# ---- device ---------------------------------------------------------------

def test_device_keyword_refuses_a_gpu_it_cannot_have(tmp_path):
    """device= of relax, run, relax_raster and fit: "cpu" is the default
    and changes no bit; a GPU this build or machine cannot give is an
    InputError naming the keyword and the reason (doc/gpu.md)."""
    h = rough(12, 3)
    plain, _ = sandslide.relax(h, 1.0)
    on_cpu, _ = sandslide.relax(h, 1.0, device="cpu")
    assert same_bits(plain, on_cpu), "device='cpu' gives other bits than the default"
    (tmp_path / "tiny.ini").write_text(CASE)
    calls = {
        "relax": lambda d: sandslide.relax(h, 1.0, device=d),
        "run": lambda d: sandslide.run(tmp_path / "tiny.ini", tmp_path / "t.h5", device=d),
        "fit": lambda d: sandslide.fit(tmp_path / "tiny.ini", tmp_path / "obs.h5",
                                       {"nu": "0.1:1"}, device=d),
    }
    for name, call in calls.items():
        with pytest.raises(sandslide.InputError) as e:
            call("cuda")
        said = str(e.value)
        assert said.startswith("device=cuda:0: ") and ("no CUDA" in said or "GPU" in said), \
            f"{name}(device='cuda'): {said!r} should name device= and the reason"
        with pytest.raises(sandslide.InputError) as e:
            call("gpu")
        assert str(e.value).startswith("device='gpu': expected cpu, cuda or cuda:N"), \
            f"{name}(device='gpu'): {str(e.value)!r}"
    assert not (tmp_path / "t.h5").exists(), "a refused run wrote its output"
