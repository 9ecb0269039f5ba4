# SPDX-License-Identifier: BSD-3-Clause
"""python/examples/wind_deposition.py, the coupled example of doc/bmi.md:
a wind model sets sandslide's deposition rate through the BMI every 2 s.

Run from the top of the repository after `make` (a few seconds):

    SANDSLIDE_LIBRARY=$PWD/build/libsandslide.so.0 PYTHONPATH=python \
        /usr/bin/python3 -m pytest -q tests/python/test_wind_example.py

The example runs once, as its command line does but without the picture;
then: the volume balance, the drift in the lee and nothing upwind, the
steepest face at the repose angle, and the picture drawn from the same
results when matplotlib is there.
"""
import importlib.util
import math
import os

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
EXAMPLE = os.path.join(ROOT, "python", "examples", "wind_deposition.py")
TAN = math.tan(math.radians(35.0))   # cases/wind_wall.ini's repose angle
SLOPE_TOL = 1e-6                     # the case's steady_slope_tol (its default)


def load_example():
    spec = importlib.util.spec_from_file_location("wind_deposition", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example():
    return load_example()


@pytest.fixture(scope="module")
def result(example):
    return example.main([])          # the command line, no --png


def test_the_volume_balance(result):
    """What the wind delivered is what sandslide holds more, plus what left
    by the open end, to 1e-12 of the delivered volume: both sides are
    roundings of sums (compensated ledgers, and the volume summed over 480
    cells, each term within an ulp), and doc/model.md#conservation holds
    any run to 1e-12."""
    d = result["delivered"]
    held = result["sand__volume"] - result["v0"] + \
        result["sand__time_integral_of_outflow_volume_flux"]
    assert d > 0.1, f"the wind delivered only {d} m3"
    assert abs(held - d) <= 1e-12 * d, f"held + outflow {held!r}, delivered {d!r}"
    assert abs(result["sand__time_integral_of_source_volume_flux"] - d) <= 1e-12 * d
    assert result["sand__external_volume_change"] == 0.0   # nothing set but the rate
    assert result["sand__time_integral_of_outflow_volume_flux"] > 0.0, \
        "no sand reached the open east end (the balance's outflow term is untested)"


def test_the_drift_is_in_the_lee(result):
    rise = result["h"] - result["h0"]
    upwind = ~result["lee"] & ~result["wall"]
    assert upwind.any() and np.all(rise[upwind] == 0.0), \
        f"sand rose upwind of the wall: {rise[upwind].max()} m"
    lee = rise[:, result["lee"][0]].mean(axis=0)     # along the strip
    assert lee.max() > 0.3, f"the drift is only {lee.max()} m high"
    assert lee[0] >= lee[-1] and np.argmax(lee) < len(lee) // 2, \
        "the drift is not highest near the wall"


def test_the_steepest_face_is_at_repose(result):
    slope = result["sand_surface__max_of_slope_angle"]
    assert abs(math.tan(math.radians(slope)) - TAN) <= SLOPE_TOL, \
        f"steepest face {slope!r} deg, the repose angle 35"
    # and from the heights: no face between two flow cells is steeper
    h, flow = result["h"], ~result["wall"]
    gx = np.abs(np.diff(h, axis=1)) / result["dx"]
    gx = gx[flow[:, 1:] & flow[:, :-1]]
    gy = (np.abs(np.diff(h, axis=0)) / result["dy"])[flow[1:] & flow[:-1]]
    assert max(gx.max(), gy.max()) <= TAN + SLOPE_TOL


def test_the_picture(example, result, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "wind.png"
    example.draw(result, str(png))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
