# SPDX-License-Identifier: BSD-3-Clause
"""sandslide fit (doc/fit.md): twin experiments.

Observations are made by `sandslide run` with known parameters, then
degraded (Gaussian height noise, missing cells, a subset of the times, or
only the front traced from them), and the fit must find what made them:
the closure, nu within 5 % and the angle within 0.1 degree where the data
identify them, and "not identifiable" where they cannot (nu from states at
rest).  The cone is cases/cone.ini on a 41 x 41 grid (dx = 6 cm): a
forward run to t = 12 s takes about 10 ms.  SANDSLIDE_TEST_SCALE < 1 (the
sanitizers) fits fewer closures in the largest twins (SCALED below).
"""
import json
import os
import signal
import subprocess
import time

import h5py
import numpy as np
import pytest

from conftest import CASES, SANDSLIDE, edit, run, run_ok
from test_relax import write_asc

TIMING_KEYS = {"seconds", "seconds_per_run"}
# Under the sanitizers (SANDSLIDE_TEST_SCALE < 1, tests/scale.h) the largest
# twins fit two closures instead of four, with five points along each
# parameter: the same code, every check kept, a third of the forward runs.
SCALED = float(os.environ.get("SANDSLIDE_TEST_SCALE") or 1) < 1
CLOSURES = "bingham,casson" if SCALED else "all"
PROFILE = ["--profile-points", "5"] if SCALED else []


def cone_case(path, end=12, every=1):
    """cases/cone.ini at 41 x 41 cells, run to `end` seconds."""
    text = open(os.path.join(CASES, "cone.ini")).read()
    text = edit(text, "nx = 81", "nx = 41")
    text = edit(text, "ny = 81", "ny = 41")
    text = edit(text, "dx = 0.03 ", "dx = 0.06 ")
    text = edit(text, "origin = -1.215 -1.215", "origin = -1.23 -1.23")
    text = "\n".join(line for line in text.splitlines()
                     if not line.startswith(("end =", "steady_tol", "max_time", "output_every")))
    text = edit(text, "[time]\n", f"[time]\nend = {end}\noutput_every = {every}\n")
    path.write_text(text + "\n")
    return path


def twin(tmp_path, name, *sets, end=12, every=1):
    """A run of the cone with --set overrides: the truth."""
    case = cone_case(tmp_path / f"{name}.ini", end, every)
    run_ok(["run", str(case), "-o", str(tmp_path / f"{name}.h5"), "-q"] +
           [w for s in sets for w in ("--set", s)])
    return tmp_path / f"{name}.h5"


def degrade(src, dst, times, sigma=0.0, missing=0.0, seed=1):
    """The snapshots at `times` with N(0, sigma) noise and a fraction
    `missing` of the values NaN, as a plain HDF5 file (/time, /height, /x,
    /y, no sandslide attributes)."""
    rng = np.random.default_rng(seed)
    with h5py.File(src, "r") as f:
        t, h, x, y = f["time"][:], f["height"][:], f["x"][:], f["y"][:]
    idx = [int(np.argmin(abs(t - s))) for s in times]
    assert np.allclose(t[idx], times), f"test set-up: no snapshots at {times} in {src}"
    h = h[idx] + rng.normal(0.0, sigma, h[idx].shape) if sigma else h[idx]
    h[rng.random(h.shape) < missing] = np.nan
    with h5py.File(dst, "w") as g:
        g["time"], g["height"], g["x"], g["y"] = t[idx], h, x, y
    return dst


def trace_front(src, dst, times, threshold, points=180):
    """The front of the sand at `times`: `points` points where the
    thickness (bilinear between cell centres) falls to `threshold`, along
    rays from the cone's centre, as a CSV time,x,y."""
    with h5py.File(src, "r") as f:
        t, h, x, y = f["time"][:], np.nan_to_num(f["height"][:]), f["x"][:], f["y"][:]
    lines = ["time,x,y"]
    for s in times:
        d = h[int(np.argmin(abs(t - s)))]

        def at(px, py):
            fx, fy = (px - x[0]) / (x[1] - x[0]), (py - y[0]) / (y[1] - y[0])
            i, j = int(fx), int(fy)
            a, b = fx - i, fy - j
            return ((1 - a) * (1 - b) * d[j, i] + a * (1 - b) * d[j, i + 1] +
                    (1 - a) * b * d[j + 1, i] + a * b * d[j + 1, i + 1])
        for q in range(points):
            c, sn = np.cos(2 * np.pi * q / points), np.sin(2 * np.pi * q / points)
            lo, hi = 0.0, 1.2     # bisection: thicker than threshold at lo, not at hi
            for _ in range(40):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if at(mid * c, mid * sn) > threshold else (lo, mid)
            lines.append(f"{s!r},{lo * c!r},{lo * sn!r}")
    dst.write_text("\n".join(lines) + "\n")
    return dst


def fit(tmp_path, case, obs, *args):
    r = run(["fit", str(case), str(obs), "--json", "--threads", "2"] + list(args),
            cwd=tmp_path, timeout=600)
    assert r.returncode == 0, f"sandslide fit failed ({r.returncode}): {r.stderr}"
    try:
        return json.loads(r.stdout)
    except json.JSONDecodeError as e:
        raise AssertionError(f"the report is not JSON ({e}):\n{r.stdout}") from None


def closure_of(report, name):
    return next(c for c in report["closures"] if c["closure"] == name)


def test_transient_cone_gives_closure_nu_and_angle(tmp_path):
    """Casson, nu = 0.13 m^2/s, 33 degrees, observed during the collapse
    with 2 mm noise, a fifth of the values missing and six of the 13
    snapshots: all four closures fitted, Casson is best by more than 2 in
    AIC, nu within 5 %, the angle within 0.1 degree, both identifiable."""
    truth = twin(tmp_path, "truth", "model.closure=casson", "model.nu=0.13",
                 "model.repose_angle=33")
    obs = degrade(truth, tmp_path / "scan.h5", [1, 2, 3, 5, 8, 12], sigma=0.002, missing=0.2)
    report = fit(tmp_path, tmp_path / "truth.ini", obs, "--param", "nu=0.01:1:log",
                 "--param", "repose_angle=30:40", "--closures", CLOSURES,
                 "-o", "fit.json", "--plot", "fit.png", *PROFILE)
    assert report == json.loads((tmp_path / "fit.json").read_text()), \
        "FIT.json is not the report --json printed"
    best = report["best"]
    assert best["closure"] == "casson", f"the best closure is {best}, not casson"
    assert abs(best["params"]["nu"] / 0.13 - 1) < 0.05, f"nu {best['params']['nu']}, not 0.13"
    assert abs(best["params"]["repose_angle"] - 33) < 0.1, \
        f"angle {best['params']['repose_angle']}, not 33"
    assert report["indistinguishable"] == ["casson"], report["verdict"]
    c = closure_of(report, "casson")
    assert c["identifiable"] == {"nu": True, "repose_angle": True}, c["why"]
    for name, true in [("nu", 0.13), ("repose_angle", 33)]:
        u = c["uncertainty"][name]
        assert u["low"] < c["params"][name] < u["high"], f"{name}'s interval {u}"
        assert u["std"] > 0, f"{name}'s std {u['std']}"
    assert {x["closure"] for x in report["closures"]} == \
        ({"bingham", "casson"} if SCALED else {"coulomb", "bingham", "herschel-bulkley", "casson"})
    assert all(x["delta_aic"] > 2 for x in report["closures"] if x["closure"] != "casson")
    # the noise: the best cost is the noise's variance, sigma^2
    assert 0.8 * 0.002 ** 2 < best["cost"] < 1.2 * 0.002 ** 2, f"cost {best['cost']}"
    assert report["forward_runs"] == sum(x["evaluations"] for x in report["closures"])
    assert report["observations"]["times"] == 6
    png = (tmp_path / "fit.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000, "fit.png is not a figure"


def test_noise_free_twin_interval_holds_the_truth(tmp_path):
    """A noise-free twin made by `run` at the case's rkl2_tol 0.1, fitted
    at 0.01: the residual left at the best point is the forward model's
    error, not noise, and it moves the best nu off 0.13 by more than the
    noise's interval allows.  The 95 % interval counts that error (F7a)
    and holds the truth; the report gives both parts of the std."""
    truth = twin(tmp_path, "exact", "model.nu=0.13")
    obs = degrade(truth, tmp_path / "exact_scan.h5", [1, 2, 4])
    report = fit(tmp_path, tmp_path / "exact.ini", obs, "--param", "nu=0.01:1:log",
                 "--profile-points", "3")
    assert report["rkl2_tol"] == 0.01
    c = closure_of(report, "coulomb")
    u = c["uncertainty"]["nu"]
    assert u["low"] < 0.13 < u["high"], \
        f"nu {c['params']['nu']}: the 95 % interval {u['low']} .. {u['high']} misses 0.13"
    assert u["std"] ** 2 == pytest.approx(u["std_noise"] ** 2 + u["std_model"] ** 2,
                                          rel=1e-4), u
    assert u["std_noise"] > 0 and u["std_model"] > 0, u
    m = c["model_error"]
    assert m["reference"] == "rkl2_tol 0.1 (the case's)", m
    assert 0 < m["cost"] and m["noise_cost"] >= c["cost"], m
    assert c["identifiable"] == {"nu": True}, c


@pytest.mark.parametrize("setting, reference", [("rkl2_tol = 0.01", "rkl2_tol 0.001"),
                                                ("integrator = euler", "euler, cfl 0.45")])
def test_model_error_reference_when_the_fit_does_not_tighten(tmp_path, setting, reference):
    """A case already at the fit's tolerance, or on forward Euler: the
    model's error is measured against a tenth of the tolerance, or half
    the CFL number (F7a); a noise-free twin of the same case is fitted
    within its interval, and the model's part of it is not zero."""
    case = cone_case(tmp_path / "ref.ini")
    case.write_text(edit(case.read_text(), "[time]\n", f"[time]\n{setting}\n"))
    run_ok(["run", str(case), "-o", str(tmp_path / "ref.h5"), "-q", "--set", "model.nu=0.13"])
    obs = degrade(tmp_path / "ref.h5", tmp_path / "ref_scan.h5", [1, 2, 4])
    report = fit(tmp_path, case, obs, "--param", "nu=0.01:1:log", "--profile-points", "3")
    c = closure_of(report, "coulomb")
    assert c["model_error"]["reference"] == reference, c["model_error"]
    u = c["uncertainty"]["nu"]
    assert u["low"] < 0.13 < u["high"] and u["std_model"] > 0, u


@pytest.mark.parametrize("bounds, side, word", [("0.01:0.05", "hi", "upper"),
                                                 ("0.5:2", "lo", "lower")])
def test_best_on_a_bound_is_flagged_not_identified(tmp_path, bounds, side, word):
    """nu = 0.13 searched in a range that does not hold it: the best value
    is the bound nearest the truth, where the cost still falls outwards.
    The report flags it on that bound, never identifiable, and says to
    widen the range: in the JSON, the verdict and the summary line."""
    truth = twin(tmp_path, "edge", "model.nu=0.13")
    degrade(truth, tmp_path / "edge_scan.h5", [1, 2, 4])
    r = run_ok(["fit", "edge.ini", "edge_scan.h5", "--param", f"nu={bounds}:log",
                "--profile-points", "3", "-o", "f.json"], cwd=tmp_path)
    report = json.loads((tmp_path / "f.json").read_text())
    c = closure_of(report, "coulomb")
    lo, hi = (float(v) for v in bounds.split(":"))
    assert c["params"]["nu"] == pytest.approx(hi if side == "hi" else lo, rel=1e-3), c["params"]
    assert c["identifiable"] == {"nu": False}, \
        f"nu = {c['params']['nu']} on the {word} bound is called identifiable: {c}"
    assert c["at_bound"] == {"nu": side}, c
    assert f"{word} bound" in c["why"]["nu"] and "widen the range" in c["why"]["nu"], c["why"]
    assert f"nu not identifiable, on the {word} bound of its range: widen it" in \
        report["verdict"], report["verdict"]
    line = r.stdout.splitlines()[0]
    assert f"on the {word} bound: widen the range" in line and "not identifiable" in line, \
        r.stdout


def test_end_states_do_not_identify_nu(tmp_path):
    """States at rest (t = 150 and 200 s; the cone is still after 20 s)
    see the angle but not nu: the time scale L^2 / nu has gone."""
    truth = twin(tmp_path, "rest", "model.nu=0.13", "model.repose_angle=34", end=200,
                 every=50)
    obs = degrade(truth, tmp_path / "rest_scan.h5", [150, 200], sigma=0.002, missing=0.2)
    report = fit(tmp_path, tmp_path / "rest.ini", obs, "--param", "nu=0.05:0.5:log",
                 "--param", "repose_angle=30:40", *PROFILE)
    c = closure_of(report, "coulomb")
    assert c["identifiable"] == {"nu": False, "repose_angle": True}, c
    assert "nu" in c["why"] and "noise" in c["why"]["nu"], c["why"]
    assert abs(c["params"]["repose_angle"] - 34) < 0.1, c["params"]
    assert "nu not identifiable" in report["verdict"], report["verdict"]
    costs = c["profile"]["nu"]["costs"]
    assert max(costs) - min(costs) < 0.01 * min(costs), \
        f"the cost along nu is not flat at rest: {costs}"


def test_front_points_alone_recover_nu(tmp_path):
    """Only the front, traced where the sand is 2 cm thick at eight times
    of the collapse (180 points each): the support cost alone finds nu."""
    truth = twin(tmp_path, "spread", "model.nu=0.13", every=0.1)
    front = trace_front(truth, tmp_path / "front.csv",
                        [0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.5, 2.0], threshold=0.02)
    report = fit(tmp_path, tmp_path / "spread.ini", front, "--param", "nu=0.01:1:log",
                 "--threshold", "0.02")
    assert report["cost_functional"]["name"] == "support"
    assert report["observations"]["kind"] == "front"
    nu = report["best"]["params"]["nu"]
    assert abs(nu / 0.13 - 1) < 0.05, f"nu {nu} from the front, not 0.13"
    assert closure_of(report, "coulomb")["identifiable"] == {"nu": True}


def test_herschel_bulkley_with_gamma_1_is_reported_as_bingham(tmp_path):
    """Herschel-Bulkley with gamma = 1 is Bingham exactly: fitted to a
    Bingham twin with gamma free, the two closures are reported as a tie
    and gamma as 1, not one of them picked."""
    truth = twin(tmp_path, "bing", "model.closure=bingham", "model.nu=0.13")
    obs = degrade(truth, tmp_path / "bing_scan.h5", [1, 2, 4, 8], sigma=0.002, missing=0.2)
    report = fit(tmp_path, tmp_path / "bing.ini", obs, "--param", "nu=0.01:1:log",
                 "--param", "gamma=0.3:3:log", "--closures", "bingham,herschel-bulkley",
                 "--grid-points", "3", "--profile-points", "5")
    assert sorted(report["indistinguishable"]) == ["bingham", "herschel-bulkley"], report
    assert "gamma is 1 within its uncertainty: it is bingham" in report["verdict"], \
        report["verdict"]
    hb = closure_of(report, "herschel-bulkley")
    u = hb["uncertainty"]["gamma"]
    assert u["low"] < 1 < u["high"], f"gamma's interval {u} misses 1"


def test_rasters_listed_in_a_csv(tmp_path):
    """OBS as a CSV time,path of .asc rasters (north row first, as the
    format has it) gives what the same heights in an .h5 give."""
    truth = twin(tmp_path, "ras", "model.nu=0.2")
    with h5py.File(truth, "r") as f:
        t, h = f["time"][:], f["height"][:]
    rows = ["time,path"]
    for k in (1, 2, 4):
        body = "\n".join(" ".join(repr(float(v)) for v in row) for row in h[k][::-1])
        (tmp_path / f"scan_{k}.asc").write_text(
            "ncols 41\nnrows 41\nxllcorner -1.23\nyllcorner -1.23\ncellsize 0.06\n" + body + "\n")
        rows.append(f"{t[k]!r},scan_{k}.asc")
    (tmp_path / "scans.csv").write_text("\n".join(rows) + "\n")
    obs = degrade(truth, tmp_path / "scans.h5", [1, 2, 4])
    args = ["--param", "nu=0.01:1:log", "--profile-points", "3"]
    a = fit(tmp_path, tmp_path / "ras.ini", tmp_path / "scans.csv", *args)
    b = fit(tmp_path, tmp_path / "ras.ini", obs, *args)
    assert a["best"] == b["best"], f"rasters: {a['best']}, the same in .h5: {b['best']}"
    assert abs(a["best"]["params"]["nu"] / 0.2 - 1) < 0.02, a["best"]


def test_an_unfinished_snapshot_is_not_observed(tmp_path):
    """A run killed while it flushed a snapshot leaves /height one longer
    than /time (doc/output.md#written-as-the-run-goes): fit reads the
    snapshots /time counts, as sandslide's other readers do."""
    truth = twin(tmp_path, "kill", "model.nu=0.2")
    obs = degrade(truth, tmp_path / "kill_scan.h5", [1, 2, 4])
    with h5py.File(tmp_path / "killed.h5", "w") as g, h5py.File(obs, "r") as f:
        g["time"] = f["time"][:2]
        g["height"], g["x"], g["y"] = f["height"][:], f["x"][:], f["y"][:]
    report = fit(tmp_path, tmp_path / "kill.ini", tmp_path / "killed.h5", "--param",
                 "nu=0.01:1:log", "--profile-points", "3")
    assert report["observations"]["times"] == 2 and report["observations"]["last_time"] == 2, \
        report["observations"]


def test_same_fit_twice_gives_the_same_report(tmp_path):
    truth = twin(tmp_path, "again", "model.nu=0.2")
    obs = degrade(truth, tmp_path / "again_scan.h5", [1, 2, 4], sigma=0.001)
    args = ["--param", "nu=0.01:1:log", "--closures", "coulomb,bingham", *PROFILE]
    a = fit(tmp_path, tmp_path / "again.ini", obs, *args, "--threads", "1")
    b = fit(tmp_path, tmp_path / "again.ini", obs, *args)
    for r in (a, b):
        for key in TIMING_KEYS | {"threads"}:
            r.pop(key)
    assert a == b, "the same fit on 1 and 2 threads gave two reports"


def test_summary_and_outputs(tmp_path):
    """Without --json: a line per closure and where the report went; an
    existing FIT.json is refused without --force."""
    truth = twin(tmp_path, "sum", "model.nu=0.2")
    obs = degrade(truth, tmp_path / "sum_scan.h5", [1, 2, 4])
    args = ["fit", "sum.ini", "sum_scan.h5", "--param", "nu=0.01:1:log", "-o", "f.json"]
    r = run_ok(args, cwd=tmp_path)
    first = r.stdout.splitlines()[0]
    assert first.startswith("coulomb") and (" nu = 0.19" in first or " nu = 0.2" in first), \
        r.stdout
    assert "wrote f.json" in r.stdout, r.stdout
    r = run(args, cwd=tmp_path)
    assert r.returncode == 2 and "f.json" in r.stderr and "--force" in r.stderr, r.stderr
    run_ok(args + ["--force", "-q"], cwd=tmp_path)


def write_h5(path, time, height, x=None, y=None):
    with h5py.File(path, "w") as g:
        g["time"], g["height"] = np.asarray(time, float), np.asarray(height, float)
        if x is not None:
            g["x"], g["y"] = x, y


@pytest.mark.parametrize("what", ["times out of order", "another grid", "empty csv",
                                  "nan everywhere", "header only", "too few front points",
                                  "not a file"])
def test_bad_observations_exit_2_naming_the_file(tmp_path, what):
    cone_case(tmp_path / "c.ini")
    cells = np.zeros((2, 41, 41))
    name = {"empty csv": "obs.csv", "header only": "obs.csv",
            "too few front points": "obs.csv"}.get(what, "obs.h5")
    obs = tmp_path / name
    if what == "times out of order":
        write_h5(obs, [2.0, 1.0], cells)
    elif what == "another grid":
        write_h5(obs, [1.0, 2.0], np.zeros((2, 40, 41)))
    elif what == "nan everywhere":
        write_h5(obs, [1.0, 2.0], np.full((2, 41, 41), np.nan))
    elif what == "empty csv":
        obs.write_text("")
    elif what == "header only":
        obs.write_text("time,x,y\n")
    elif what == "too few front points":
        obs.write_text("time,x,y\n1,0,0\n1,1,0\n")
    r = run(["fit", "c.ini", name, "--param", "nu=0.01:1:log"], cwd=tmp_path)
    assert r.returncode == 2, (what, r.returncode, r.stderr)
    assert name in r.stderr and r.stderr.count("\n") == 1, (what, r.stderr)


@pytest.mark.parametrize("args, says", [
    ([], "--param"),
    (["--param", "nux=1:2"], "nux"),
    (["--param", "nu=2:1"], "LO < HI"),
    (["--param", "nu=0:1:log"], "LO > 0"),
    (["--param", "nu=0.1:1", "--param", "nu=0.2:1"], "twice"),
    (["--param", "gamma=0.5:2"], "coulomb takes none"),
    (["--param", "nu=0.1:1", "--param", "delta=0.01:0.1", "--closures", "bingham"],
     "exclude each other"),
    (["--param", "nu=0.1:1", "--closures", "coulomb,mud"], "mud"),
    (["--param", "nu=0.1:1", "--cost", "area"], "--cost"),
])
def test_bad_options_exit_2(tmp_path, args, says):
    truth = twin(tmp_path, "o", "model.nu=0.2")
    r = run(["fit", "o.ini", str(truth)] + args, cwd=tmp_path)
    assert r.returncode == 2 and says in r.stderr, (args, r.stderr)


def test_interrupt_writes_the_best_so_far(tmp_path):
    """SIGINT stops the fit between forward runs: exit 130 and FIT.json
    with "interrupted": true and the best point so far."""
    truth = twin(tmp_path, "int", "model.nu=0.2")
    obs = degrade(truth, tmp_path / "int_scan.h5", [1, 2, 4, 8, 12])
    p = subprocess.Popen([SANDSLIDE, "fit", "int.ini", "int_scan.h5", "--param",
                          "nu=0.01:1:log", "--param", "repose_angle=30:40", "--closures", "all",
                          "--grid-points", "50", "-o", "f.json", "--threads", "1"],
                         cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(1.0)   # 2500 grid points per closure: minutes, unless stopped
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130, (p.returncode, err)
    report = json.loads((tmp_path / "f.json").read_text())
    assert report["interrupted"] is True
    assert report["forward_runs"] > 0 and report["best"]["closure"] == "coulomb", report


HYSTERESIS_TWIN = """[grid]
nx = 60
ny = 8
dx = 0.025
origin = 0 0
[model]
closure = coulomb
repose_angle = 30
static_angle = 36
nu = 0.1
[time]
end = 12
output_every = 0.5
[boundary]
west = wall
east = open
south = periodic
north = periodic
[initial]
type = flat
height = 0
[source pour]
rect = 0 0 0.05 0.2
rate = 0.01
"""


def fit_twin(tmp_path, *params):
    """Run twin.ini into twin.h5, fit it freeing params ("NAME=LO:HI"); the
    best parameters found."""
    run_ok(["run", "twin.ini", "-o", "twin.h5", "-q"], cwd=tmp_path)
    args = [w for p in params for w in ("--param", p)]
    run_ok(["fit", "twin.ini", "twin.h5", *args, "-o", "fit.json", "-q"], cwd=tmp_path,
           timeout=300)
    return json.loads((tmp_path / "fit.json").read_text())["best"]["params"]


def test_a_poured_twin_gives_both_angles_of_hysteresis(tmp_path):
    """A pour against a wall under hysteresis (30 and 36 degrees): fit frees
    repose_angle and static_angle and finds each within 0.5 degree
    (doc/fit.md#parameters)."""
    (tmp_path / "twin.ini").write_text(HYSTERESIS_TWIN)
    best = fit_twin(tmp_path, "repose_angle=27:33", "static_angle=33.5:39")
    assert abs(best["repose_angle"] - 30.0) <= 0.5 and abs(best["static_angle"] - 36.0) <= 0.5, (
        f"fit found repose_angle {best['repose_angle']:.3f}, static_angle "
        f"{best['static_angle']:.3f}: the twin's are 30 and 36")


def test_a_class_with_hysteresis_gives_both_its_angles(tmp_path):
    """The poured twin above with its sand as a class ([material sand]
    static_angle) beside loose sand at 25 degrees in the east: fit frees
    the class's repose and static angles ('material NAME.static_angle')
    and finds each within 0.5 degree."""
    classes = np.full((8, 60), 3.0)
    classes[:, 40:] = 7.0
    write_asc(tmp_path / "classes.asc", classes, cellsize=0.025)
    case = HYSTERESIS_TWIN.replace("repose_angle = 30\nstatic_angle = 36\n",
                                   "materials = classes.asc\n")
    case += ("[material sand]\nclass = 3\nrepose_angle = 30\nstatic_angle = 36\n"
             "[material loose]\nclass = 7\nrepose_angle = 25\n")
    (tmp_path / "twin.ini").write_text(case)
    best = fit_twin(tmp_path, "material sand.repose_angle=27:33",
                    "material sand.static_angle=33.5:39")
    a_d, a_s = best["material sand.repose_angle"], best["material sand.static_angle"]
    assert abs(a_d - 30.0) <= 0.5 and abs(a_s - 36.0) <= 0.5, (
        f"fit found repose_angle {a_d:.3f}, static_angle {a_s:.3f}: the twin's are 30 and 36")


CLASS_TWIN = """[grid]
nx = 32
ny = 24
dx = 1
[model]
closure = coulomb
materials = classes.asc
nu = 1
[time]
end = 300
output_every = 50
[initial]
type = file
file = ridge.asc
[material sand]
class = 3
repose_angle = 30
[material gravel]
class = 7
repose_angle = 40
"""


def test_one_angle_per_class_of_a_twin(tmp_path):
    """A ridge half sand (30 degrees), half gravel (40): fit frees each
    class's angle ('material NAME.repose_angle') and finds both within 0.5
    degree (doc/fit.md#parameters)."""
    y = np.arange(24) - 11.5
    ridge = np.tile(np.maximum(0.0, 10.0 - np.tan(np.radians(60.0)) * np.abs(y))[:, None],
                    (1, 32))
    classes = np.full((24, 32), 7.0)
    classes[:, :16] = 3.0
    write_asc(tmp_path / "ridge.asc", ridge, cellsize=1.0)
    write_asc(tmp_path / "classes.asc", classes, cellsize=1.0)
    (tmp_path / "twin.ini").write_text(CLASS_TWIN)
    best = fit_twin(tmp_path, "material sand.repose_angle=27:33",
                    "material gravel.repose_angle=37:43")
    sand, gravel = best["material sand.repose_angle"], best["material gravel.repose_angle"]
    assert abs(sand - 30.0) <= 0.5 and abs(gravel - 40.0) <= 0.5, (
        f"fit found sand {sand:.3f}, gravel {gravel:.3f} degrees: the twin's are 30 and 40")
    r = run(["fit", "twin.ini", "twin.h5", "--param", "material rock.repose_angle=27:33"],
            cwd=tmp_path)
    assert r.returncode == 2 and "[material rock]" in r.stderr, r.stderr
