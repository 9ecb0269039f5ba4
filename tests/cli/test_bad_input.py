# SPDX-License-Identifier: BSD-3-Clause
"""Bad input (doc/case-file.md#errors): exit status 2, one 'sandslide: ' line on
stderr naming file:line (or the --set argument) and what would be accepted,
and nothing written: an existing output keeps its bytes, no new file appears.
"""
import os
import re
import shutil
import struct
import subprocess

import h5py
import numpy as np
import pytest

from conftest import (BASE, SANDSLIDE, asc_text, drop_line, edit, files_under, line_of,
                      png_bytes, run, without_root_powers)

CASE = "case.ini"
SENTINEL = b"SENTINEL: sandslide must not touch this file\n" + bytes(range(256))

WALL_RECT = "\n[wall block]\nrect = 0.5 0.5 0.9 0.9\n"


class Bad:
    """One bad input: the case text, extra arguments, words the message must
    contain, the line it must name (None: no line, only the file), extra files."""

    def __init__(self, ident, text, words, at=None, args=(), files=None, names_case=True):
        self.ident = ident
        self.text = text
        self.words = words
        self.at = at
        self.args = list(args)
        self.files = files or {}
        self.names_case = names_case


def with_line(text, needle, occurrence=1):
    return line_of(text, needle, occurrence)


def b_unknown_section():
    t = BASE + "\n[grids]\nnx = 3\n"
    return Bad("unknown-section", t, ["grids", "grid", "wall NAME"], with_line(t, "[grids]"))


def b_unknown_key_fixed():
    t = edit(BASE, "dx = 0.1\n", "dx = 0.1\nnz = 4\n")
    return Bad("unknown-key-grid", t, ["nz", "nx", "origin"], with_line(t, "nz = 4"))


def b_unknown_key_region():
    t = BASE + WALL_RECT + "colour = red\n"
    return Bad("unknown-key-wall", t, ["colour", "rect", "polygon"], with_line(t, "colour"))


def b_unknown_key_source():
    t = BASE + "\n[source s]\nrect = 0.5 0.5 0.9 0.9\nrate = 0.001\nduration = 3\n"
    return Bad("unknown-key-source", t, ["duration", "rate", "stop"],
               with_line(t, "duration"))


def b_missing(key, section_word):
    t = drop_line(BASE, key + " =")
    return Bad(f"missing-{key}", t, [key, "missing", section_word], None)


def b_value(ident, old, new, words, needle=None):
    t = edit(BASE, old, new)
    return Bad(ident, t, words, with_line(t, needle or new.strip().splitlines()[-1]))


def b_added(ident, after, added, words):
    t = edit(BASE, after, after + added)
    return Bad(ident, t, words, with_line(t, added.strip()))


def b_twice():
    t = edit(BASE, "ny = 16\n", "ny = 16\nnx = 30\n")
    return Bad("key-twice", t, ["nx", "twice", f"{CASE}:{line_of(t, 'nx = 20')}"],
               with_line(t, "nx = 30"))


def b_region_twice():
    t = BASE + "\n[source s]\nrect = 0.5 0.5 0.9 0.9\nrate = 0.001\nrate = 0.002\n"
    return Bad("source-rate-twice", t, ["rate", "twice"], with_line(t, "rate = 0.002"))


def b_section_twice():
    t = BASE + "\n[grid]\ndy = 0.1\n"
    return Bad("section-twice", t, ["grid", "twice"], with_line(t, "[grid]", 2))


def b_no_equals():
    t = edit(BASE, "ny = 16\n", "ny 16\n")
    return Bad("no-equals", t, ["key = value"], with_line(t, "ny 16"))


def b_key_before_section():
    t = "nx = 20\n" + BASE
    return Bad("key-before-section", t, ["section", "[grid]"], 1)


def b_header_no_bracket():
    t = edit(BASE, "[model]\n", "[model\n")
    return Bad("section-no-bracket", t, ["]"], with_line(t, "[model"))


def b_periodic(side, other):
    t = edit(BASE, f"{side} = ", f"{side} = periodic\n# was: ")
    return Bad(f"periodic-{side}-only", t, [side, other, "periodic"],
               with_line(t, f"{side} = periodic"))


def b_shape(ident, section, shape_line, words):
    t = BASE + f"\n[{section}]\n{shape_line}\n"
    if section.startswith("source"):
        t += "rate = 0.001\n"
    return Bad(ident, t, words, with_line(t, shape_line))


def b_two_shapes():
    t = BASE + "\n[wall w]\nrect = 0.5 0.5 0.9 0.9\ndisk = 1.5 0.8 0.2\n"
    return Bad("two-shapes", t, ["two shapes", "rect", "disk", "mask",
                                 f"{CASE}:{line_of(t, 'rect = 0.5')}"],
               with_line(t, "disk = 1.5"))


def b_source_no_shape():
    t = BASE + "\n[source pour]\nrate = 0.001\n"
    return Bad("source-no-shape", t, ["pour", "no shape", "rect", "polygon"],
               (line_of(t, "[source pour]"), line_of(t, "rate = 0.001")))


def b_empty_region():
    t = BASE + "\n[wall empty]\n\n[open nothing]\n"
    return Bad("region-without-keys", t, ["empty", "shape", "rect"], line_of(t, "[wall empty]"))


def b_no_cell_centre():
    # cell centres are at 0.05 + 0.1 k: this rect lies between them
    t = BASE + "\n[wall thin]\nrect = 0.56 0.56 0.64 0.64\n"
    return Bad("covers-no-cell", t, ["thin", "no cell", "dx"], with_line(t, "rect = 0.56"))


def b_source_no_rate():
    t = BASE + "\n[source pour]\nrect = 0.5 0.5 0.9 0.9\nstart = 0\n"
    return Bad("source-no-rate", t, ["pour", "rate"],
               (line_of(t, "[source pour]"), line_of(t, "rect = 0.5"), line_of(t, "start = 0")))


def b_source_stop(stop, start):
    t = BASE + f"\n[source pour]\nrect = 0.5 0.5 0.9 0.9\nrate = 0.001\nstart = {start}\nstop = {stop}\n"
    lines = tuple(range(line_of(t, "[source pour]"), line_of(t, f"stop = {stop}") + 1))
    return Bad(f"source-stop-{stop}-start-{start}", t, ["pour", "stop", "start"], lines)


def b_polygon_short():
    t = BASE + "\n[wall tri]\npolygon = 0.2 0.2 1.0 0.2\n"
    return Bad("polygon-2-points", t, ["tri", "polygon", "3"], with_line(t, "polygon ="))


def b_polygon_odd():
    t = BASE + "\n[wall tri]\npolygon = 0.2 0.2 1.0 0.2 0.5\n"
    return Bad("polygon-odd-count", t, ["polygon", "pairs"], with_line(t, "polygon ="))


def b_mask(ident, data, words, name="mask.png", write=True):
    t = BASE + f"\n[wall m]\nmask = {name}\n"
    files = {name: data} if write else {}
    return Bad(ident, t, [name] + words, with_line(t, "mask ="), files=files)


def long_chunk_png():
    """A 20 x 16 mask with a tEXt chunk that claims 1.7 GB (fuzz_mask): refused
    before libpng allocates that much."""
    good = png_bytes([[255] * 20] * 16)
    head = struct.pack(">I", 0x64785F6D) + b"tEXt" + b"zmin_m\x000"
    return good[:33] + head + good[33:]


def b_initial_file(ident, name, data, words, at_case=True):
    t = edit(BASE, "type = flat\nheight = 0.2\n", f"type = file\nfile = {name}\n")
    files = {name: data} if data is not None else {}
    return Bad(ident, t, [name] + words, with_line(t, "file =") if at_case else None,
               files=files, names_case=at_case)


def asc_grid(nx=20, ny=16, bad=None):
    rows = [["0.1"] * nx for _ in range(ny)]
    if bad:
        (row, col), token = bad
        rows[row - 1][col - 1] = token
    return asc_text(rows).encode()


def b_asc_nonfinite(token):
    # row 3, column 5 counted from the north-west corner, as in the file:
    # cell (4, 13) from the south-west of 16 rows, as every message names it
    t = edit(BASE, "type = flat\nheight = 0.2\n", "type = file\nfile = init.asc\n")
    data = asc_grid(bad=((3, 5), token))
    asc_line = 5 + 3   # five header lines, then the rows
    return Bad(f"asc-{token}", t, ["init.asc", "finite",
                                   "(cell (4, 13) at x = 0.45 m, y = 1.35 m)",
                                   f"init.asc:{asc_line}"],
               None, files={"init.asc": data}, names_case=False)


def b_set(ident, setarg, words):
    return Bad(ident, BASE, ["--set", setarg] + words, None, args=["--set", setarg],
               names_case=False)


def bad_inputs():
    out = [
        b_unknown_section(),
        b_unknown_key_fixed(),
        b_unknown_key_region(),
        b_unknown_key_source(),
        b_value("unknown-key-model", "nu = 0.1\n", "nu = 0.1\nfriction = 0.3\n",
                ["friction", "repose_angle", "closure"]),
    ]
    for key, word in [("nx", "grid"), ("ny", "grid"), ("dx", "grid"),
                      ("repose_angle", "model"), ("nu", "model"),
                      ("end", "time"), ("output_every", "time")]:
        out.append(b_missing(key, word))
    out += [
        b_value("dx-negative", "dx = 0.1\n", "dx = -0.1\n", ["dx", "-0.1", "> 0"]),
        b_value("dx-zero", "dx = 0.1\n", "dx = 0\n", ["dx", "> 0"]),
        b_added("dy-negative", "dx = 0.1\n", "dy = -0.05\n", ["dy", "> 0"]),
        b_value("nx-zero", "nx = 20\n", "nx = 0\n", ["nx", "integer >= 1"]),
        b_value("nx-fraction", "nx = 20\n", "nx = 2.5\n", ["nx", "integer >= 1"]),
        b_value("origin-one-number", "origin = 0 0\n", "origin = 0\n", ["origin", "X Y"]),
        b_value("angle-0", "repose_angle = 35\n", "repose_angle = 0\n",
                ["repose_angle", "(0, 90)"]),
        b_value("angle-90", "repose_angle = 35\n", "repose_angle = 90\n",
                ["repose_angle", "(0, 90)"]),
        b_value("angle-95", "repose_angle = 35\n", "repose_angle = 95\n",
                ["repose_angle", "(0, 90)"]),
        # not a number: a raster of angles (doc/model.md#materials)
        b_value("angle-abc", "repose_angle = 35\n", "repose_angle = abc\n",
                ["repose_angle", "abc", "cannot open"]),
        b_value("angle-junk", "repose_angle = 35\n", "repose_angle = 35x\n",
                ["repose_angle", "35x", "(0, 90)"]),
        b_value("angle-nan", "repose_angle = 35\n", "repose_angle = nan\n",
                ["repose_angle", "(0, 90)"]),
        b_added("cfl-0", "output_every = 0.5\n", "cfl = 0\n", ["cfl", "(0, 1]"]),
        b_added("cfl-1.5", "output_every = 0.5\n", "cfl = 1.5\n", ["cfl", "(0, 1]"]),
        b_value("end-negative", "end = 1\n", "end = -1\n", ["end", "steady"]),
        b_value("output-every-zero", "output_every = 0.5\n", "output_every = 0\n",
                ["output_every", "> 0"]),
        b_value("nu-negative", "nu = 0.1\n", "nu = -0.1\n", ["nu", "> 0"]),
        b_value("closure-bad", "closure = coulomb\n", "closure = mohr\n",
                ["closure", "mohr", "coulomb", "casson", "herschel-bulkley"]),
        b_value("side-bad", "west = wall\n", "west = sticky\n",
                ["west", "sticky", "wall", "open", "periodic"]),
        b_value("initial-type-bad", "type = flat\n", "type = heap\n",
                ["type", "heap", "flat", "cone", "file"]),
        b_twice(),
        b_region_twice(),
        b_section_twice(),
        b_no_equals(),
        b_key_before_section(),
        b_header_no_bracket(),
        b_periodic("west", "east"),
        b_periodic("north", "south"),
        b_shape("rect-outside", "wall w", "rect = 1.5 0.5 2.5 0.9", ["w", "outside"]),
        b_shape("rect-below-origin", "open o", "rect = 0.5 -0.3 0.9 0.4", ["o", "outside"]),
        b_shape("disk-outside", "wall d", "disk = 1.9 0.8 0.3", ["d", "outside"]),
        b_shape("polygon-outside", "source p", "polygon = 0.2 0.2 1.0 0.2 0.6 1.9",
                ["p", "outside"]),
        b_shape("rect-reversed", "wall r", "rect = 0.9 0.5 0.5 0.9", ["rect", "X0 < X1"]),
        b_shape("disk-zero-radius", "wall d", "disk = 1 0.8 0", ["disk", "R > 0"]),
        b_two_shapes(),
        b_source_no_shape(),
        b_empty_region(),
        b_no_cell_centre(),
        b_source_no_rate(),
        b_source_stop(1, 2),
        b_source_stop(2, 2),
        b_polygon_short(),
        b_polygon_odd(),
        b_set("set-bad-value", "model.closure=mohr", ["coulomb"]),
        b_set("set-bad-number", "model.repose_angle=95", ["(0, 90)"]),
        b_set("set-no-equals", "model.closure", ["SECTION.KEY=VALUE"]),
        b_set("set-no-dot", "closure=casson", ["SECTION.KEY=VALUE"]),
        b_set("set-unknown-key", "model.friction=0.3", ["friction", "nu"]),
        b_set("set-unknown-section", "physics.nu=0.3", ["physics", "grid"]),
        b_mask("mask-missing", None, ["cannot open"], write=False),
        b_mask("mask-wrong-size", png_bytes([[255] * 10] * 8), ["10 x 8", "20 x 16"]),
        b_mask("mask-not-png", b"GIF89a this is not a PNG at all\n" * 4, ["PNG"]),
        b_mask("mask-chunk-too-long", long_chunk_png(), ["tEXt", "1685610349 bytes", "corrupt"]),
        b_initial_file("initial-file-missing", "nothere.asc", None, []),
        b_initial_file("initial-file-wrong-size", "small.asc",
                       asc_grid(nx=10, ny=8), ["10 x 8", "20 x 16"]),
        b_initial_file("initial-file-wrong-cellsize", "cell.asc",
                       asc_text([["0.1"] * 20] * 16, cellsize=0.2).encode(),
                       ["cellsize", "0.2"]),
        b_asc_nonfinite("nan"),
        b_asc_nonfinite("inf"),
        b_initial_file("initial-file-not-a-number", "word.asc",
                       asc_grid(bad=((2, 3), "sand")),
                       ["sand", "(cell (2, 14) at x = 0.25 m, y = 1.45 m)", "word.asc:7"], at_case=False),
        b_initial_file("initial-file-unknown-extension", "init.tif", b"II*\0", [".asc", ".h5"]),
        b_value("grid-too-large", "nx = 20\nny = 16\n", "nx = 2000000\nny = 2000000\n",
                ["memory", "2000000", "TiB"], needle="nx = 2000000"),
        b_value("grid-extent-not-finite", "dx = 0.1\n", "dx = 1e307\n",
                ["[grid]", "20 x 16 cells", "finite extent"], needle="nx = 20"),
    ]
    return out


BAD = bad_inputs()


def check_rejected(r, bad, case_name=CASE):
    msg = r.stderr
    assert r.returncode == 2, (
        f"[{bad.ident}] expected exit status 2 (bad input), got {r.returncode}\n"
        f"stderr: {msg!r}\nstdout: {r.stdout!r}")
    lines = msg.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sandslide: "), (
        f"[{bad.ident}] expected one stderr line starting 'sandslide: ', got {msg!r}")
    for w in bad.words:
        assert w in msg, f"[{bad.ident}] message does not contain {w!r}: {msg!r}"
    if bad.names_case:
        assert case_name in msg, f"[{bad.ident}] message does not name {case_name}: {msg!r}"
    if bad.at is not None:
        allowed = bad.at if isinstance(bad.at, tuple) else (bad.at,)
        named = re.findall(re.escape(case_name) + r":(\d+)", msg)
        assert any(int(n) in allowed for n in named), (
            f"[{bad.ident}] message should name {case_name}:{allowed[0] if len(allowed) == 1 else allowed}"
            f" (the line at fault), it names lines {named}: {msg!r}")
    assert r.stdout == "", f"[{bad.ident}] nothing should go to stdout: {r.stdout!r}"


def setup_case(tmp_path, bad):
    (tmp_path / CASE).write_text(bad.text)
    for name, data in bad.files.items():
        (tmp_path / name).write_bytes(data)


@pytest.mark.parametrize("bad", BAD, ids=[b.ident for b in BAD])
def test_rejected_existing_output_untouched(tmp_path, bad):
    setup_case(tmp_path, bad)
    out = tmp_path / "result.h5"
    out.write_bytes(SENTINEL)
    before = files_under(tmp_path)
    r = run(["run", CASE, "-o", "result.h5"] + bad.args, cwd=tmp_path)
    check_rejected(r, bad)
    assert out.read_bytes() == SENTINEL, f"[{bad.ident}] existing output was modified"
    new = files_under(tmp_path) - before
    assert not new, f"[{bad.ident}] bad input created {sorted(new)}"


@pytest.mark.parametrize("bad", BAD, ids=[b.ident for b in BAD])
def test_rejected_default_output_not_created(tmp_path, bad):
    setup_case(tmp_path, bad)
    before = files_under(tmp_path)
    r = run(["run", CASE] + bad.args, cwd=tmp_path)
    check_rejected(r, bad)
    new = {p for p in files_under(tmp_path) - before
           if not os.path.isdir(tmp_path / p)}
    assert not new, f"[{bad.ident}] bad input created {sorted(new)}"


def test_set_bad_value_names_the_argument(tmp_path):
    """The --set message names the argument, not a line of the case file."""
    (tmp_path / CASE).write_text(BASE)
    r = run(["run", CASE, "-o", "o.h5", "--set", "time.cfl=1.5"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "--set time.cfl=1.5" in r.stderr and "(0, 1]" in r.stderr, r.stderr
    assert not (tmp_path / "o.h5").exists()


def test_set_unknown_region_has_no_shape(tmp_path):
    (tmp_path / CASE).write_text(BASE)
    r = run(["run", CASE, "-o", "o.h5", "--set", "source nowhere.rate=0.002"], cwd=tmp_path)
    assert r.returncode == 2, f"exit {r.returncode}: {r.stderr}"
    assert "--set" in r.stderr and "nowhere" in r.stderr, r.stderr
    assert not (tmp_path / "o.h5").exists()


# ---- files and the command line ------------------------------------------

def assert_usage_error(r, *words):
    assert r.returncode == 2, f"expected exit 2, got {r.returncode}: {r.stderr!r}"
    first = r.stderr.splitlines()[0] if r.stderr else ""
    assert first.startswith("sandslide: "), f"first stderr line: {r.stderr!r}"
    for w in words:
        assert w in first, f"{w!r} not in the error line {first!r}"


def assert_input_error(r, *words):
    """A bad file (not bad usage): exactly one 'sandslide: ' line."""
    assert_usage_error(r, *words)
    assert len(r.stderr.splitlines()) == 1, f"expected one stderr line: {r.stderr!r}"
    assert r.stdout == "", r.stdout


def test_missing_case_file(tmp_path):
    r = run(["run", "nothere.ini", "-o", "o.h5"], cwd=tmp_path)
    assert_input_error(r, "nothere.ini")
    assert files_under(tmp_path) == set()


def test_unreadable_case_file(tmp_path):
    case = tmp_path / CASE
    case.write_text(BASE)
    os.chmod(case, 0)
    try:
        r = subprocess.run(without_root_powers() + [SANDSLIDE, "run", CASE, "-o", "o.h5"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert_input_error(r, CASE)
        assert "ermission denied" in r.stderr, r.stderr
        assert not (tmp_path / "o.h5").exists()
    finally:
        os.chmod(case, 0o644)


def test_case_is_a_folder(tmp_path):
    (tmp_path / "dir.ini").mkdir()
    r = run(["run", "dir.ini", "-o", "o.h5"], cwd=tmp_path)
    assert_input_error(r, "dir.ini")
    assert not (tmp_path / "o.h5").exists()


def test_output_in_missing_folder(tmp_path):
    (tmp_path / CASE).write_text(BASE)
    r = run(["run", CASE, "-o", "nodir/x.h5"], cwd=tmp_path)
    assert_input_error(r, "nodir")
    assert not (tmp_path / "nodir").exists(), "the output folder must not be created"
    assert files_under(tmp_path) == {CASE}


def test_output_is_a_folder(tmp_path):
    (tmp_path / CASE).write_text(BASE)
    (tmp_path / "x.h5").mkdir()
    r = run(["run", CASE, "-o", "x.h5"], cwd=tmp_path)
    assert_input_error(r, "x.h5")
    assert files_under(tmp_path) == {CASE, "x.h5"}


@pytest.mark.parametrize("args,words", [
    (["run", CASE, "--bogus"], ["--bogus"]),
    (["run", CASE, "--threads", "0"], ["--threads", "0"]),
    (["run", CASE, "--threads", "two"], ["--threads", "two"]),
    (["run", CASE, "--threads"], ["--threads"]),
    (["run", CASE, "--tile", "8"], ["--tile", "NXxNY"]),
    (["run", CASE, "--tile", "0x8"], ["--tile"]),
    (["run", CASE, "--deflate", "10"], ["--deflate"]),
    (["run", CASE, "-o"], ["-o"]),
    (["run", CASE, "--set"], ["--set"]),
    (["run", CASE, "other.ini"], ["other.ini"]),
    (["run"], ["case"]),
    (["run", "-o", "x.h5"], ["case"]),
    (["frobnicate"], ["frobnicate", "run", "info"]),
    ([], ["command"]),
    (["info"], ["file"]),
    (["info", "--bogus"], ["--bogus"]),
], ids=["unknown-option", "threads-0", "threads-word", "threads-no-value",
        "tile-no-x", "tile-zero", "deflate-10", "o-no-value", "set-no-value",
        "two-cases", "run-no-case", "run-only-output", "unknown-command",
        "no-command", "info-no-file", "info-unknown-option"])
def test_usage_errors(tmp_path, args, words):
    (tmp_path / CASE).write_text(BASE)
    r = run(args, cwd=tmp_path)
    assert_usage_error(r, *words)
    assert files_under(tmp_path) == {CASE}, "a usage error must not write anything"


def test_info_missing_file(tmp_path):
    r = run(["info", "nothere.h5"], cwd=tmp_path)
    assert_input_error(r, "nothere.h5")


def test_info_not_hdf5(tmp_path):
    (tmp_path / "fake.h5").write_text("this is not HDF5\n" * 10)
    r = run(["info", "fake.h5"], cwd=tmp_path)
    assert_input_error(r, "fake.h5", "HDF5")


def test_info_hdf5_not_sandslide(tmp_path):
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["height"] = np.zeros((2, 3))
        f.attrs["source"] = "something else"
    r = run(["info", "other.h5"], cwd=tmp_path)
    assert_input_error(r, "other.h5", "sandslide")
    with h5py.File(tmp_path / "plain.h5", "w") as f:
        f["data"] = np.arange(5.0)
    r = run(["info", "plain.h5"], cwd=tmp_path)
    assert_input_error(r, "plain.h5", "sandslide")


def test_info_empty_file(tmp_path):
    (tmp_path / "empty.h5").write_bytes(b"")
    r = run(["info", "empty.h5"], cwd=tmp_path)
    assert_input_error(r, "empty.h5")


def test_initial_file_relative_to_case_folder(tmp_path):
    """A file named in the case is found beside the case, not in the cwd; a
    missing one is still an input error naming the case file."""
    sub = tmp_path / "sub"
    sub.mkdir()
    text = edit(BASE, "type = flat\nheight = 0.2\n", "type = file\nfile = init.asc\n")
    (sub / CASE).write_text(text)
    (sub / "init.asc").write_bytes(asc_grid())
    run_r = run(["run", f"sub/{CASE}", "-o", "ok.h5", "-q"], cwd=tmp_path)
    assert run_r.returncode == 0, run_r.stderr
    shutil.move(str(sub / "init.asc"), str(tmp_path / "init.asc"))
    r = run(["run", f"sub/{CASE}", "-o", "again.h5"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "init.asc" in r.stderr, r.stderr
    assert not (tmp_path / "again.h5").exists()
