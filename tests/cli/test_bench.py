# SPDX-License-Identifier: BSD-3-Clause
"""`sandslide bench` (doc/performance.md#the-sweep): the JSON document parses, names every
case asked for, and its figures are positive and consistent; bad options
exit 2.  Throughput itself is never asserted: the machines are shared."""
import json

import pytest

from conftest import run, run_ok

SMALL = ["bench", "--nx", "1100", "--ny", "1000", "--tile", "64x16", "--repeats", "2", "--steps", "2",
         "--threads", "1,2", "--json"]


@pytest.fixture(scope="module")
def report():
    out = run_ok(SMALL + ["--closure", "all"], timeout=300)
    return json.loads(out.stdout)


def test_json_names_every_case(report):
    cases = {(c["surface"], c["closure"], c["threads"]) for c in report["cases"]}
    closures = ["coulomb", "bingham", "herschel-bulkley(0.5)", "herschel-bulkley(2)",
                "casson"]
    want = {(s, c, t) for s in ("supercritical", "subcritical", "patch", "room")
            for c in closures for t in (1, 2)}
    assert cases == want, f"cases missing or extra: {sorted(want ^ cases)}"
    assert (report["nx"], report["ny"], report["tile_nx"], report["tile_ny"]) == (1100, 1000, 64, 16), \
        "grid or tile size not reported as asked"


def test_json_figures_positive(report):
    assert set(report["bandwidth_bytes_per_s"]) == {"1", "2"}, \
        "the bandwidth probe must report each thread count"
    for t, bw in report["bandwidth_bytes_per_s"].items():
        assert bw > 0, f"bandwidth for {t} threads is not positive: {bw}"
    for c in report["cases"]:
        name = f"{c['surface']} {c['closure']} {c['threads']} threads"
        r = c["cell_updates_per_s"]
        assert 0 < r["min"] <= r["median"] <= r["max"], f"{name}: min/median/max {r}"
        assert c["bytes_per_cell"] >= 16, f"{name}: an in-place sweep moves >= 16 B per cell"
        assert c["roofline_cell_updates_per_s"] > 0, f"{name}: roofline not positive"
        # each figure is printed to 6 significant digits (relative error
        # <= 5e-6), so the quotient of two of them is within 1.5e-5; with
        # 4 digits it was not within 1e-3 for some figures
        ratio = r["median"] / c["roofline_cell_updates_per_s"]
        assert abs(ratio - c["roofline_fraction"]) <= 1e-4 * ratio, \
            f"{name}: roofline_fraction {c['roofline_fraction']} != median/roofline {ratio}"
        assert c["steps_per_repeat"] == 2, f"{name}: --steps 2 not honoured"


def test_active_fraction_follows_the_surface(report):
    for c in report["cases"]:
        name = f"{c['surface']} {c['closure']} {c['threads']} threads"
        a = c["active_fraction"]
        if c["surface"] == "supercritical":
            assert a == 1.0, f"{name}: every tile slides, yet active_fraction = {a}"
        elif c["surface"] == "subcritical":
            assert a == 0.0, f"{name}: nothing slides, yet active_fraction = {a}"
        elif c["surface"] == "room":
            # the heap and the source keep the room's tiles awake; the
            # floor beyond the door stays bare for the few super-steps
            assert 0.0 < a < 1.0, f"{name}: a room and a bare floor, active {a}"
        else:
            assert 0.0 < a < 0.5, f"{name}: a 512^2 patch in 1100x1000 cells, active {a}"


def test_table_output():
    out = run_ok(["bench", "--nx", "600", "--ny", "600", "--closure", "casson",
                  "--surface", "supercritical", "--threads", "1", "--repeats", "1",
                  "--steps", "1"])
    assert "memory bandwidth" in out.stdout and "casson" in out.stdout, \
        f"table output: {out.stdout}"


@pytest.mark.parametrize("args, what", [
    (["--closure", "sand"], "--closure"),
    (["--surface", "flat"], "--surface"),
    (["--threads", "1,,2"], "--threads"),
    (["--threads", "0"], "--threads"),
    (["--nx", "0"], "--nx"),
    (["--repeats", "100"], "--repeats"),
    (["--tile", "64"], "--tile"),
    (["--frobnicate"], "--frobnicate"),
])
def test_bad_options_exit_2(args, what):
    p = run(["bench"] + args)
    assert p.returncode == 2, f"bench {args}: exit {p.returncode}, expected 2"
    assert what in p.stderr, f"bench {args}: the message must name {what}: {p.stderr}"


def test_room_is_the_video_grid_with_rkl2_stages():
    """The room runs at 480 x 320 whatever --nx and --ny (a grid smaller
    than the patch needs is fine for it), counts the 33 evaluations of each
    super-step, and moves the stage arrays besides the heights."""
    out = run_ok(["bench", "--nx", "64", "--ny", "64", "--surface", "room", "--closure",
                  "coulomb", "--threads", "1", "--repeats", "1", "--steps", "3", "--json"])
    report = json.loads(out.stdout)
    (case,) = report["cases"]
    assert case["surface"] == "room" and case["steps_per_repeat"] == 3, case
    assert case["bytes_per_cell"] >= 16 + 48, \
        f"an RKL2 stage reads and writes 48 B more per cell: {case['bytes_per_cell']}"


def test_patch_needs_room():
    p = run(["bench", "--nx", "300", "--ny", "300", "--surface", "patch"])
    assert p.returncode == 2, f"a 300x300 grid cannot hold the 512^2 patch: exit {p.returncode}"
    assert "512" in p.stderr, f"the message must say what is needed: {p.stderr}"
