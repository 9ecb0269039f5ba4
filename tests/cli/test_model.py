# SPDX-License-Identifier: BSD-3-Clause
"""nu from the sliding layer's parameters (doc/model.md#nu-from-the-sliding-layer):

    tau = density * gravity * delta * sin(a_cr)
    bingham           nu = tau delta^2 / (6 mu)
    herschel-bulkley  nu = (tau/k)^(1/gamma) gamma / ((1+gamma)(1+2 gamma)) delta^2
    casson            nu = tau delta^2 / (30 mu)

The file's nu attribute must equal the formula evaluated here, and the
parameters that do not belong to a closure are rejected with file:line.
"""
import math

import pytest

from conftest import edit, h5open, line_of, run, run_ok


def physical_case(base, closure, params):
    lines = "".join(f"{k} = {v}\n" for k, v in params.items())
    return edit(base, "closure = coulomb\nrepose_angle = 35\nnu = 0.1\n",
                f"closure = {closure}\nrepose_angle = 35\n{lines}")


def tau(density, gravity, delta, angle_deg=35.0):
    return density * gravity * delta * math.sin(math.radians(angle_deg))


@pytest.mark.parametrize("closure, params, expected", [
    ("bingham", {"delta": 0.004, "density": 1600, "viscosity": 0.05},
     tau(1600, 9.81, 0.004) * 0.004 ** 2 / (6 * 0.05)),
    ("casson", {"delta": 0.004, "density": 1600, "viscosity": 0.05, "gravity": 9.8},
     tau(1600, 9.8, 0.004) * 0.004 ** 2 / (30 * 0.05)),
    ("herschel-bulkley", {"gamma": 0.5, "delta": 0.004, "density": 1600, "consistency": 2.0},
     (tau(1600, 9.81, 0.004) / 2.0) ** 2 * 0.5 / (1.5 * 2.0) * 0.004 ** 2),
    ("herschel-bulkley", {"gamma": 2.0, "delta": 0.01, "density": 1500, "consistency": 0.3},
     (tau(1500, 9.81, 0.01) / 0.3) ** 0.5 * 2.0 / (3.0 * 5.0) * 0.01 ** 2),
])
def test_nu_from_physical_parameters(tmp_path, base_case, closure, params, expected):
    case = tmp_path / "case.ini"
    case.write_text(physical_case(base_case, closure, params))
    out = tmp_path / "run.h5"
    run_ok(["run", case, "-o", out, "-q"])
    with h5open(out) as f:
        nu = float(f.attrs["nu"])
    assert nu == pytest.approx(expected, rel=1e-13), (
        f"{closure} {params}: nu attribute {nu!r}, the formula gives {expected!r}")


@pytest.mark.parametrize("closure, params, bad_key, words", [
    ("coulomb", {"delta": 0.004, "density": 1600, "viscosity": 0.05}, "delta", "nu directly"),
    ("bingham", {"delta": 0.004, "density": 1600, "consistency": 0.05}, "consistency",
     "viscosity"),
    ("herschel-bulkley", {"gamma": 0.5, "delta": 0.004, "density": 1600, "viscosity": 0.05},
     "viscosity", "consistency"),
])
def test_parameters_of_another_closure_are_rejected(tmp_path, base_case, closure, params,
                                                    bad_key, words):
    text = physical_case(base_case, closure, params)
    case = tmp_path / "case.ini"
    case.write_text(text)
    r = run(["run", case, "-o", tmp_path / "run.h5", "-q"])
    assert r.returncode == 2, f"{closure} with {bad_key}: exit {r.returncode}, {r.stderr}"
    assert f"case.ini:{line_of(text, bad_key + ' =')}" in r.stderr, r.stderr
    assert words in r.stderr, r.stderr
    assert not (tmp_path / "run.h5").exists(), "a rejected case wrote its output"


def test_nu_and_physical_parameters_together_are_rejected(tmp_path, base_case):
    text = edit(base_case, "nu = 0.1\n", "nu = 0.1\ndelta = 0.004\n")
    text = edit(text, "closure = coulomb", "closure = bingham")
    case = tmp_path / "case.ini"
    case.write_text(text)
    r = run(["run", case, "-o", tmp_path / "run.h5", "-q"])
    assert r.returncode == 2 and "both nu and delta" in r.stderr, r.stderr


def test_missing_physical_parameter_is_named(tmp_path, base_case):
    case = tmp_path / "case.ini"
    case.write_text(physical_case(base_case, "casson", {"delta": 0.004, "viscosity": 0.05}))
    r = run(["run", case, "-o", tmp_path / "run.h5", "-q"])
    assert r.returncode == 2 and "density" in r.stderr, r.stderr
