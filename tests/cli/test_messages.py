# SPDX-License-Identifier: BSD-3-Clause
"""Messages that point at the real mistake (issue 16): a usage error is one
line that ends with where the options are; `sandslide help CMD` prints that
command's help; a missing GDAL raster says so."""
import re

import pytest

from conftest import BASE, asc_text, run, run_ok


@pytest.mark.parametrize("args,where", [
    (["run", "--threads", "0", "x.ini"], "sandslide run --help"),
    (["relax", "--bogus"], "sandslide relax --help"),
    (["render", "x.h5", "--fps", "0"], "sandslide render --help"),
    (["bench", "--threads", "x"], "sandslide bench --help"),
    (["info"], "sandslide info --help"),
    (["frob"], "sandslide --help"),
    ([], "sandslide --help"),
    (["help", "nosuch"], "sandslide --help"),
])
def test_usage_error_is_one_line_with_where_to_look(tmp_path, args, where):
    r = run(args, cwd=tmp_path)
    assert r.returncode == 2, (args, r.returncode, r.stderr)
    assert r.stderr.count("\n") == 1, f"{args}: not one line:\n{r.stderr}"
    assert r.stderr.startswith("sandslide: ") and f"(see '{where}')" in r.stderr, r.stderr
    assert r.stdout == "", f"{args}: printed on stdout: {r.stdout!r}"


@pytest.mark.parametrize("cmd", ["run", "relax", "info", "render", "bench"])
def test_help_cmd_is_the_commands_help(tmp_path, cmd):
    a, b = run(["help", cmd], cwd=tmp_path), run([cmd, "--help"], cwd=tmp_path)
    assert a.returncode == 0 and a.stdout == b.stdout, \
        f"'sandslide help {cmd}' is not '{cmd} --help':\n{a.stdout[:300]}"
    assert a.stdout.startswith(f"usage: sandslide {cmd}"), a.stdout[:200]


@pytest.mark.parametrize("name", ["nosuch.tif", "nosuch.xyz", "nosuch.asc", "nosuch.png",
                                  "nosuch.h5", "nosuch.h5:/height"])
def test_missing_dem_says_no_such_file(tmp_path, name):
    r = run(["relax", name], cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    want = name.split(":")[0]
    assert f"cannot open '{want}': No such file or directory" in r.stderr, r.stderr


def test_missing_bedrock_is_blamed_on_bedrock(tmp_path):
    (tmp_path / "dem.asc").write_text("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\n"
                                      "cellsize 1\n0 0\n0 0\n")
    r = run(["relax", "dem.asc", "--bedrock", "rock.tif"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert re.match(r"sandslide: --bedrock: cannot open 'rock.tif': No such file", r.stderr), \
        r.stderr


DOOR = ["run", "door.ini", "-o", "x.h5"]


@pytest.fixture
def door(tmp_path):
    import shutil
    from conftest import CASES
    shutil.copy(f"{CASES}/door.ini", tmp_path / "door.ini")
    return tmp_path


@pytest.mark.parametrize("setting,want", [
    ("source nosuch.rate=1e-3", "the case has no [source nosuch]: its source sections are room"),
    ("wall nosuch.rect=0 0 1 1", "the case has no [wall nosuch]: its wall sections are "
                                 "room_south, room_north, jamb_south, jamb_north"),
    ("open x.rect=0 0 1 1", "the case has no [open x], and no open section at all"),
])
def test_set_on_a_missing_section_names_those_there_are(door, setting, want):
    r = run(DOOR + ["--set", setting], cwd=door)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert r.stderr == f"sandslide: --set {setting}: {want}\n", r.stderr
    assert not (door / "x.h5").exists()


def test_start_stop_error_blames_the_set_that_made_it(door):
    r = run(DOOR + ["--set", "source room.start=100", "--set", "source room.stop=50"], cwd=door)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("sandslide: --set source room.stop=50: [source room] stop = "
                               "50 s is not after start = 100 s"), r.stderr
    # from the file alone, the file's line of stop
    text = re.sub(r"(?m)^rate = 1e-3.*$", "rate = 1e-3\nstart = 9\nstop = 5",
                  (door / "door.ini").read_text())
    (door / "door.ini").write_text(text)
    r = run(DOOR, cwd=door)
    line = text.splitlines().index("stop = 5") + 1
    assert r.stderr.startswith(f"sandslide: door.ini:{line}: [source room] stop = 5 s"), r.stderr


# ---- an override wins (issue 23) ------------------------------------------

@pytest.mark.parametrize("case", ["cone.ini", "table.ini"])
def test_shortening_a_shipped_case_drops_its_max_time(tmp_path, case):
    """`--set time.end=5` on a case that runs to steady with a max_time:
    the override wins, the file's max_time is dropped, and the summary
    says so (it was refused, blaming the file's line)."""
    from conftest import CASES
    r = run(["run", f"{CASES}/{case}", "-o", "x.h5", "--set", "time.end=5",
             "--set", "time.output_every=5"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    notes = [line for line in r.stdout.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "[time] max_time" in notes[0] and \
        f"{case}:" in notes[0] and "--set time.end=5" in notes[0], r.stdout
    assert "to t = 5 s" in r.stdout, r.stdout


def test_unset_drops_a_key_and_a_section(door):
    r = run(DOOR + ["--unset", "source room", "--set", "time.end=10"], cwd=door)
    assert r.returncode == 0, r.stderr
    import h5py
    with h5py.File(door / "x.h5", "r") as f:
        assert f["inflow"][-1] == 0.0, "the source was not removed"
        assert "source room" in f.attrs["case_overrides"].decode(), \
            "the unset is not stored for --restart"
    r = run(DOOR + ["--force", "--unset", "model.nu"], cwd=door)
    assert r.returncode == 2 and "[model] is missing 'nu'" in r.stderr, r.stderr
    r = run(DOOR + ["--force", "--unset", "time.end=5"], cwd=door)
    assert r.returncode == 2 and r.stderr.startswith("sandslide: --unset 'time.end=5': expected "
                                                     "SECTION.KEY"), r.stderr
    r = run(DOOR + ["--force", "--set", "time.end"], cwd=door)
    assert r.returncode == 2 and "expected SECTION.KEY=VALUE" in r.stderr, r.stderr


@pytest.mark.parametrize("command", ["run", "relax"])
def test_help_names_the_sidecars_an_h5_output_writes(tmp_path, command):
    """An .h5 output leaves two more files beside it; --help says which,
    and they are what the command writes."""
    text = " ".join(run_ok([command, "--help"]).stdout.split())
    assert "OUT.xmf (XDMF, for ParaView) and OUT.h5.aux.xml (GDAL's georeferencing" in text \
        if command == "run" else "beside it OUT.xmf and OUT.h5.aux.xml as run writes" in text, text
    if command == "run":
        (tmp_path / "case.ini").write_text(BASE)
        run_ok(["run", "case.ini", "-o", "o.h5", "-q"], cwd=tmp_path)
    else:
        (tmp_path / "dem.asc").write_text(asc_text([[0.0, 0.0, 0.0], [0.0, 3.0, 0.0],
                                                    [0.0, 0.0, 0.0]]))
        run_ok(["relax", "dem.asc", "-o", "o.h5", "-q"], cwd=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("o.")) == \
        ["o.h5", "o.h5.aux.xml", "o.xmf"]
