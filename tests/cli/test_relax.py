# SPDX-License-Identifier: BSD-3-Clause
"""`sandslide relax`: DEMs relaxed to the repose angle (issue 5).

Physical properties (steady slopes, volume, bedrock), round trips through
ESRI ASCII, 16-bit PNG and HDF5, the report, and bad input.
"""
import json
import math
import os
import re
import struct
import zlib

import numpy as np
import pytest

from conftest import h5open, run, text_attr

TAN35 = math.tan(math.radians(35.0))


def write_asc(path, h, cellsize=0.1, x0=0.0, y0=0.0, nodata=None):
    """h: array (ny, nx), row 0 = south (written north row first)."""
    ny, nx = h.shape
    head = (f"ncols {nx}\nnrows {ny}\nxllcorner {x0!r}\nyllcorner {y0!r}\n"
            f"cellsize {cellsize!r}\n")
    if nodata is not None:
        head += f"NODATA_value {nodata!r}\n"
    rows = [" ".join(repr(float(v)) for v in h[j]) for j in range(ny - 1, -1, -1)]
    with open(path, "w") as f:
        f.write(head + "\n".join(rows) + "\n")


def read_asc(path):
    """(header dict, array (ny, nx) south row first)."""
    with open(path) as f:
        tokens = f.read().split()
    head = {}
    k = 0
    while not _is_number(tokens[k]):
        head[tokens[k].lower()] = tokens[k + 1]
        k += 2
    nx, ny = int(head["ncols"]), int(head["nrows"])
    v = np.array([float(t) for t in tokens[k:k + nx * ny]]).reshape(ny, nx)
    return head, v[::-1]


def _is_number(t):
    try:
        float(t)
        return True
    except ValueError:
        return False


def face_slopes(h, dx):
    """Largest slope of the faces as doc/model.md#face-flux defines it (walls round
    the grid mirror; no interior walls): g_n across, g_t the mean of both
    cells' central differences along the face."""
    p = np.pad(h, 1, mode="edge")          # wall sides: mirror ghost
    cy = (p[2:, 1:-1] - p[:-2, 1:-1]) / (2 * dx)
    cx = (p[1:-1, 2:] - p[1:-1, :-2]) / (2 * dx)
    gn_x = (h[:, 1:] - h[:, :-1]) / dx
    gt_x = 0.5 * (cy[:, 1:] + cy[:, :-1])
    gn_y = (h[1:, :] - h[:-1, :]) / dx
    gt_y = 0.5 * (cx[1:, :] + cx[:-1, :])
    return max(np.sqrt(gn_x ** 2 + gt_x ** 2).max(), np.sqrt(gn_y ** 2 + gt_y ** 2).max())


def cliff(nx=48, ny=40, dx=0.1):
    """A 1.5 m plateau with a vertical cliff on a rough floor."""
    rng = np.random.default_rng(7)
    h = 0.02 * rng.random((ny, nx))
    h[:, : nx // 3] += 1.5
    return h


def relax(args, tmp_path, expect=0):
    r = run(["relax"] + [str(a) for a in args], cwd=tmp_path)
    assert r.returncode == expect, (
        f"relax {args} exited {r.returncode}, expected {expect}\n{r.stdout}\n{r.stderr}")
    return r


def test_cliff_relaxes_to_repose_with_volume_conserved(tmp_path):
    h0 = cliff()
    write_asc(tmp_path / "cliff.asc", h0)
    relax(["cliff.asc", "-o", "flat.asc", "--report", "r.json"], tmp_path)
    head, h = read_asc(tmp_path / "flat.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert h.shape == h0.shape
    assert rep["steady"] is True, rep
    s = face_slopes(h, 0.1)
    assert s <= TAN35 + 1e-6, f"steepest face {s:.9f} above tan 35 = {TAN35:.9f}"
    assert math.tan(math.radians(rep["max_slope_after_deg"])) <= TAN35 + 1e-6, rep
    assert rep["max_slope_before_deg"] > 80, rep
    v0, v1 = h0.sum(), h.sum()
    assert abs(v1 - v0) <= 1e-12 * v0, f"volume {v0!r} -> {v1!r} with wall sides"
    assert rep["cells_moved"] > 100 and rep["volume_moved"] > 0, rep
    assert rep["steps"] > 0 and rep["wall_seconds"] > 0, rep


@pytest.mark.parametrize("integrator", ["euler", "rkl2"])
def test_same_bits_for_any_tile_size_and_thread_count(tmp_path, integrator):
    write_asc(tmp_path / "cliff.asc", cliff(30, 20))
    outputs = []
    for k, extra in enumerate([["--threads", "1"], ["--threads", "2", "--tile", "8x4"],
                               ["--threads", "2", "--tile", "7x3"]]):
        # 20 s of a collapse that takes about 450 s: a few thousand steps
        relax(["cliff.asc", "-o", f"{k}.asc", "--integrator", integrator, "--max-time", "20"]
              + extra, tmp_path)
        outputs.append((tmp_path / f"{k}.asc").read_bytes())
    assert outputs[0] == outputs[1] == outputs[2], \
        f"{integrator}: the relaxed surface depends on --tile or --threads"


def test_subcritical_dem_is_returned_bit_for_bit_without_steps(tmp_path):
    ny, nx = 30, 25
    y, x = np.mgrid[0:ny, 0:nx] * 0.1
    h0 = 0.3 * x + 0.2 * y + 0.01 * np.sin(x * 3.7) * np.cos(y * 2.3)
    write_asc(tmp_path / "gentle.asc", h0, x0=1000.5, y0=-20.25)
    relax(["gentle.asc", "-o", "out.asc", "--report", "r.json"], tmp_path)
    head, h = read_asc(tmp_path / "out.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["steps"] == 0 and rep["cells_moved"] == 0, rep
    assert np.array_equal(h.view(np.uint64), h0.view(np.uint64)), "heights changed"
    assert float(head["xllcorner"]) == 1000.5 and float(head["yllcorner"]) == -20.25
    assert float(head["cellsize"]) == 0.1


def test_open_nodata_cells_are_kept_and_take_the_sand(tmp_path):
    h0 = cliff(30, 20)
    h0[5:8, 20:24] = -9999.0
    write_asc(tmp_path / "hole.asc", h0, nodata=-9999.0)
    relax(["hole.asc", "--nodata", "open", "-o", "out.asc", "--report", "r.json"], tmp_path)
    head, h = read_asc(tmp_path / "out.asc")
    assert float(head["nodata_value"]) == -9999.0
    assert np.all(h[5:8, 20:24] == -9999.0), "nodata cells lost their marker"
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["outflow"] > 0.0, rep
    valid = h0 != -9999.0
    # what left through the open nodata cells is what the surface lost
    dv = (h0[valid].sum() - h[valid].sum()) * 0.01
    assert dv == pytest.approx(rep["outflow"], rel=1e-9, abs=1e-12)


def test_bedrock_inclined_sand_slides_off_and_leaves_it_bare(tmp_path):
    ny, nx, dx = 10, 40, 0.05
    x = (np.arange(nx) + 0.5) * dx
    rock = np.tile(-1.0 * x, (ny, 1))            # 45 degrees, down to the east
    sand = rock + 0.01
    write_asc(tmp_path / "rock.asc", rock, cellsize=dx)
    write_asc(tmp_path / "sand.asc", sand, cellsize=dx)
    relax(["sand.asc", "--bedrock", "rock.asc", "--sides", "open", "--open-level",
           "-2.1", "-o", "out.asc", "--report", "r.json"], tmp_path)
    _, h = read_asc(tmp_path / "out.asc")
    thick = h - rock
    assert thick.min() >= -1e-12, f"sand thickness {thick.min()!r} below the bedrock"
    assert thick.max() < 1e-6, f"{thick.max()!r} m of sand left on a 45 degree bedrock"
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["outflow"] == pytest.approx(0.01 * nx * ny * dx * dx, rel=1e-9)


def test_bedrock_flat_sand_forms_a_pile_at_repose(tmp_path):
    n, dx = 36, 0.05
    c = (np.arange(n) + 0.5) * dx - 0.5 * n * dx
    r = np.hypot(*np.meshgrid(c, c))
    sand = np.maximum(0.0, math.tan(math.radians(60)) * (0.35 - r))
    rock = np.zeros_like(sand)
    write_asc(tmp_path / "rock.asc", rock, cellsize=dx)
    write_asc(tmp_path / "pile.asc", sand, cellsize=dx)
    relax(["pile.asc", "--bedrock", "rock.asc", "-o", "out.asc", "--report", "r.json"],
          tmp_path)
    _, h = read_asc(tmp_path / "out.asc")
    assert h.min() >= -1e-12, "sand below the flat bedrock"
    s = face_slopes(h, dx)
    assert TAN35 - 0.03 <= s <= TAN35 + 1e-6, f"pile slope {s:.6f}, tan 35 {TAN35:.6f}"
    assert h.sum() == pytest.approx(sand.sum(), rel=1e-12)


def test_add_sand_pours_a_pile(tmp_path):
    write_asc(tmp_path / "floor.asc", np.zeros((30, 30)))
    relax(["floor.asc", "--add-sand", "disk=1.5,1.5,0.15", "--sand-rate", "0.5",
           "--sand-duration", "2", "-o", "out.asc", "--report", "r.json"], tmp_path)
    _, h = read_asc(tmp_path / "out.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["inflow"] > 0 and rep["steady"] is True, rep
    assert h.sum() * 0.01 == pytest.approx(rep["inflow"], rel=1e-9)
    assert face_slopes(h, 0.1) <= TAN35 + 1e-6
    assert h.max() > 0.2, "no pile formed"


def test_series_output_is_a_sandslide_file(tmp_path):
    write_asc(tmp_path / "cliff.asc", cliff(24, 16))
    relax(["cliff.asc", "-o", "series.h5", "--max-time", "2", "--output-every", "0.5"],
          tmp_path)
    with h5open(tmp_path / "series.h5") as f:
        assert f["height"].shape == (5, 16, 24)
        # stamped with the time of the step that reached each target
        # (the steps do not shorten to land on them); the end is exact
        t = list(f["time"][:])
        assert t[0] == 0.0 and t[-1] == 2.0, t
        assert all(target <= t[k] < t[k + 1] for k, target in enumerate([0.5, 1.0, 1.5], 1)), \
            f"snapshot times {t} are not the first step ends at or after 0.5, 1, 1.5"
        assert f["volume"][-1] == pytest.approx(f["volume"][0], rel=1e-12)


@pytest.mark.parametrize("integrator", ["auto", "rkl2"])
def test_the_relaxed_surface_does_not_depend_on_the_snapshots(tmp_path, integrator):
    """Snapshots watch a relaxation; they do not change it: the same steps,
    evaluations, end time and bits with and without --output-every."""
    write_asc(tmp_path / "cliff.asc", cliff(30, 20))
    reports = {}
    for name, extra in (("plain.asc", []), ("often.h5", ["--output-every", "7"]),
                        ("seldom.h5", ["--output-every", "150"])):
        relax(["cliff.asc", "-o", name, "--integrator", integrator, "--report",
               name + ".json"] + extra, tmp_path)
        reports[name] = json.loads((tmp_path / (name + ".json")).read_text())
    _, plain = read_asc(tmp_path / "plain.asc")
    for name in ("often.h5", "seldom.h5"):
        r, p = reports[name], reports["plain.asc"]
        assert r["steady"] and p["steady"], (r, p)
        for key in ("steps", "stencil_evaluations", "time", "rest_steps"):
            assert r[key] == p[key], \
                f"{integrator}, {name}: {key} {r[key]!r}, without snapshots {p[key]!r}"
        with h5open(tmp_path / name) as f:
            assert f["height"].shape[0] > 2, f"{name}: test set-up: too few snapshots"
            assert np.array_equal(f["height"][-1], plain), \
                f"{integrator}, {name}: the relaxed surface differs from the one " \
                f"without snapshots by up to {np.abs(f['height'][-1] - plain).max()!r} m"


def png16(path, grey, text=None):
    """Write a 16-bit greyscale PNG; grey (ny, nx) north row first."""
    ny, nx = grey.shape

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    raw = b"".join(b"\x00" + grey[j].astype(">u2").tobytes() for j in range(ny))
    body = chunk(b"IHDR", struct.pack(">IIBBBBB", nx, ny, 16, 0, 0, 0, 0))
    for k, v in (text or {}).items():
        body += chunk(b"tEXt", k.encode() + b"\x00" + v.encode())
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + body + chunk(b"IDAT", zlib.compress(raw)) +
                chunk(b"IEND", b""))


def read_png16(path):
    """(grey (ny, nx) north row first, text dict) of a 16-bit greyscale PNG."""
    data = open(path, "rb").read()
    pos, idat, text = 8, b"", {}
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            nx, ny, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 16 and colour == 0, "not a 16-bit greyscale PNG"
        elif kind == b"IDAT":
            idat += body
        elif kind == b"tEXt":
            k, v = body.split(b"\x00", 1)
            text[k.decode()] = v.decode()
        elif kind == b"zTXt":
            k, rest = body.split(b"\x00", 1)
            text[k.decode()] = zlib.decompress(rest[1:]).decode()
        elif kind == b"iTXt":
            k, rest = body.split(b"\x00", 1)
            comp = rest[0]
            rest = rest[2:].split(b"\x00", 2)[2]
            text[k.decode()] = (zlib.decompress(rest) if comp else rest).decode()
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride, bpp = 2 * nx, 2
    out = np.zeros((ny, stride), dtype=np.int64)
    prev = np.zeros(stride, dtype=np.int64)
    for j in range(ny):
        f = raw[j * (stride + 1)]
        line = np.frombuffer(raw[j * (stride + 1) + 1:(j + 1) * (stride + 1)],
                             dtype=np.uint8).astype(np.int64)
        cur = np.zeros(stride, dtype=np.int64)
        for i in range(stride):
            a = cur[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[i] = (line[i] + p) & 0xFF
        out[j] = cur
        prev = cur
    grey = (out[:, 0::2] << 8) | out[:, 1::2]
    return grey, text


def test_png16_round_trip_keeps_size_and_range(tmp_path):
    ny, nx = 20, 28
    grey = np.zeros((ny, nx), dtype=np.uint16)
    grey[:, :9] = 60000                               # a cliff at the west
    grey += np.arange(nx, dtype=np.uint16)[None, :]
    png16(tmp_path / "in.png", grey)
    relax(["in.png", "--zscale", "2e-5", "--dx", "0.1", "-o", "out.png", "--report",
           "r.json"], tmp_path)
    g2, text = read_png16(tmp_path / "out.png")
    assert g2.shape == (ny, nx)
    # the renderer's gray16 convention: grey 0 no data, v >= 1 the heights
    zmin, zmax = float(text["zmin_m"]), float(text["zmax_m"])
    assert g2.min() >= 1, "a cell with data written as nodata"
    h = zmin + (g2 - 1) * (zmax - zmin) / 65534.0
    h0 = grey.astype(float) * 2e-5
    step = (zmax - zmin) / 65534.0
    assert abs(h.sum() - h0.sum()) <= nx * ny * step, "volume lost beyond quantisation"
    assert h.max() < h0.max(), "the cliff did not come down"


def test_hdf5_input_relaxes_the_last_snapshot(tmp_path):
    write_asc(tmp_path / "cliff.asc", cliff(20, 12))
    relax(["cliff.asc", "-o", "a.h5", "--max-time", "0.05"], tmp_path)
    relax(["a.h5", "-o", "b.asc"], tmp_path)
    _, h = read_asc(tmp_path / "b.asc")
    assert h.shape == (12, 20) and face_slopes(h, 0.1) <= TAN35 + 1e-6
    # a dataset of it: /height (time, y, x) gives its last snapshot, which
    # is settled; /cell_type (y, x) is flat
    relax(["a.h5:/height", "-o", "c.asc", "--dx", "0.1"], tmp_path)
    relax(["a.h5:/cell_type", "-o", "d.asc", "--dx", "0.1"], tmp_path)
    assert np.array_equal(read_asc(tmp_path / "c.asc")[1], h)
    assert read_asc(tmp_path / "d.asc")[1].shape == (12, 20)


@pytest.mark.parametrize("setup, args, message", [
    ("nan", ["dem.asc"], "nan"),
    ("bedrock_size", ["dem.asc", "--bedrock", "small.asc"], "expected the DEM's"),
    ("bedrock_above", ["dem.asc", "--bedrock", "high.asc"], "above the surface"),
    ("png8", ["grey8.png"], "16-bit"),
    ("plain", ["dem.xyz"], ".asc"),
    ("plain", ["dem.asc", "-o", "missing/out.asc"], "does not exist"),
    ("plain", ["dem.asc", "--add-sand", "disk=1,1,0.1"], "--sand-rate"),
    ("plain", ["dem.asc", "--angle", "95"], "--angle"),
    ("plain", ["dem.asc", "--tile", "0x8"], "--tile"),
])
def test_bad_input_exits_2_and_leaves_the_input_alone(tmp_path, setup, args, message):
    h = cliff(12, 10)
    write_asc(tmp_path / "dem.asc", h)
    (tmp_path / "dem.xyz").write_text("1 2 3\n")
    if setup == "nan":
        text = (tmp_path / "dem.asc").read_text().replace(repr(float(h[3, 3])), "nan", 1)
        (tmp_path / "dem.asc").write_text(text)
    elif setup == "bedrock_size":
        write_asc(tmp_path / "small.asc", np.zeros((4, 4)))
    elif setup == "bedrock_above":
        write_asc(tmp_path / "high.asc", h + 1.0)
    elif setup == "png8":
        from conftest import write_png
        write_png(tmp_path / "grey8.png", [[0, 10, 20], [30, 40, 50]])
    before = (tmp_path / "dem.asc").read_bytes()
    r = relax(args, tmp_path, expect=2)
    assert message.lower() in r.stderr.lower(), r.stderr
    assert (tmp_path / "dem.asc").read_bytes() == before, "the input was modified"
    assert not list(tmp_path.glob("out/*")), "an output was written for bad input"


def test_case_file_bedrock_is_used_and_stored(tmp_path):
    """[initial] bedrock = FILE in a case: the run keeps every cell on or
    above it and the output carries /bedrock (doc/output.md#variables)."""
    ny, nx, dx = 8, 30, 0.05
    x = (np.arange(nx) + 0.5) * dx
    rock = np.tile(-1.0 * x, (ny, 1))
    write_asc(tmp_path / "rock.asc", rock, cellsize=dx)
    write_asc(tmp_path / "sand.asc", rock + 0.01, cellsize=dx)
    (tmp_path / "slope.ini").write_text(f"""\
[grid]
nx = {nx}
ny = {ny}
dx = {dx}
origin = 0 0
[model]
closure = coulomb
repose_angle = 35
nu = 0.05
[time]
end = 0.4
output_every = 0.1
[boundary]
west = wall
east = open
south = wall
north = wall
open_level = -2
[initial]
type = file
file = sand.asc
bedrock = rock.asc
""")
    r = run(["run", "slope.ini", "-o", "slope.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "slope.h5") as f:
        stored = f["bedrock"][:]
        h = f["height"][:]
    assert np.array_equal(stored, rock), "/bedrock is not the bedrock file"
    assert (h - rock[None]).min() >= -1e-12, "sand went below the bedrock"
    assert (h[-1] - rock).max() < (h[0] - rock).max(), "nothing slid off"


def test_run_max_slope_counts_the_faces_in_sand_as_relax_does(tmp_path):
    """/max_slope_deg of `run` is the steepest face in sand, as relax's
    report (issue 16, item 6): a bare 50 deg rock ramp in the west does not
    count, so a 60 deg pile on the flat rock east of it ends at the repose
    angle; relax of the run's last snapshot on the same bedrock reports the
    same angle before it moves anything."""
    ny, nx, dx = 24, 40, 0.05
    y, x = (np.mgrid[0:ny, 0:nx] + 0.5) * dx
    rock = math.tan(math.radians(50)) * np.maximum(0.0, 0.6 - x)
    sand = rock + math.tan(math.radians(60)) * np.maximum(0.0, 0.35 - np.hypot(x - 1.3, y - 0.6))
    write_asc(tmp_path / "rock.asc", rock, cellsize=dx)
    write_asc(tmp_path / "sand.asc", sand, cellsize=dx)
    (tmp_path / "ramp.ini").write_text(f"""\
[grid]
nx = {nx}
ny = {ny}
dx = {dx}
[model]
closure = coulomb
repose_angle = 35
nu = 1
[time]
end = steady
output_every = 1
[boundary]
west = wall
east = wall
south = wall
north = wall
[initial]
type = file
file = sand.asc
bedrock = rock.asc
""")
    r = run(["run", "ramp.ini", "-o", "ramp.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "ramp.h5") as f:
        slope = f["max_slope_deg"][:]
        long_name = text_attr(f["max_slope_deg"], "long_name")
        h = f["height"][-1]
    assert (h - rock)[:, :10].max() == 0.0, "the ramp is not bare (test bug)"
    assert slope[0] > 55, f"the pile starts at 60 deg: {slope!r}"
    assert math.tan(math.radians(slope[-1])) <= TAN35 + 1e-6, (
        f"final /max_slope_deg {slope[-1]!r}: the bare 50 deg ramp counted")
    assert slope[-1] > 34, f"final /max_slope_deg {slope[-1]!r}: the pile is not at repose"
    assert "sand" in long_name, f"/max_slope_deg long_name {long_name!r} does not say sand"
    relax(["ramp.h5", "--bedrock", "rock.asc", "-o", "again.asc", "--report", "r.json"],
          tmp_path)
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["max_slope_before_deg"] == slope[-1], (rep, slope[-1])


def gdal_built():
    r = run(["--version"])
    return "GDAL: on" in r.stdout


@pytest.mark.skipif(not gdal_built(), reason="this build has no GDAL (made with GDAL=0 or "
                    "MPI=1, or without Debian package libgdal-dev)")
def test_geotiff_round_trip_keeps_georeferencing_and_nodata(tmp_path):
    h0 = cliff(30, 20)
    h0[2:4, 25:28] = -9999.0
    write_asc(tmp_path / "dem.asc", h0, x0=512000.5, y0=4100000.25, nodata=-9999.0)
    # .asc -> .tif (one tiny step: a format conversion), .tif -> relaxed
    # .tif, then -> .asc to read it back here
    relax(["dem.asc", "-o", "in.tif", "--max-time", "1e-9"], tmp_path)
    relax(["in.tif", "-o", "out.tif", "--report", "r.json"], tmp_path)
    relax(["out.tif", "-o", "out.asc", "--max-time", "1e-9"], tmp_path)
    head, h = read_asc(tmp_path / "out.asc")
    assert h.shape == h0.shape
    assert float(head["xllcorner"]) == 512000.5 and float(head["yllcorner"]) == 4100000.25
    assert float(head["cellsize"]) == 0.1
    assert np.all(h[2:4, 25:28] == float(head["nodata_value"])), "nodata lost"
    assert json.loads((tmp_path / "r.json").read_text())["steady"] is True
    valid = h0 != -9999.0
    assert face_slopes(np.where(valid, h, h[valid].min()), 0.1) < 2.0   # the cliff came down
    assert h[valid].max() < h0[valid].max()


def test_numbers_print_exactly_and_shortest(tmp_path):
    """The report's tolerances are 1e-09 and 1e-06, not 17 digits that
    merely read back (1.0000000000000001e-09), and every number in it reads
    back as the double relax had; `info` gives a UTM corner exactly, not
    rounded by 2 m (5.47933e+06), and the cell size as written."""
    y, x = (np.mgrid[0:12, 0:14] + 0.5) * 0.3
    write_asc(tmp_path / "dem.asc", 1.0 + 0.2 * x + 0.1 * y, cellsize=0.3, x0=263811.5,
              y0=5479330.25)
    r = run(["relax", "dem.asc", "-o", "out.h5", "-q", "--report", "r.json",
             "--tol", "1e-9", "--slope-tol", "1e-6"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    text = (tmp_path / "r.json").read_text()
    assert '"tol": 1e-09,' in text and '"slope_tol": 1e-06,' in text, text
    def significant(token):
        mantissa = token.lower().split("e")[0].lstrip("-").replace(".", "")
        return len(mantissa.strip("0"))
    for token in re.findall(r"(?<![\w.])-?\d[\d.]*(?:e[-+]?\d+)?", text):
        # Python's repr is the shortest text that reads back
        assert significant(token) <= significant(repr(float(token))), \
            f"{token} has more digits than it takes ({repr(float(token))}):\n{text}"
    rep = json.loads(text)
    assert rep["tol"] == 1e-9 and rep["slope_tol"] == 1e-6 and rep["dx"] == 0.3, rep
    r = run(["info", "out.h5"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    grid = [line for line in r.stdout.splitlines() if line.startswith("grid")][0]
    assert grid.endswith("dx = 0.3 m, dy = 0.3 m, lower-left corner (263811.5, 5479330.25) m"), \
        grid


def test_output_over_the_input_is_refused_before_the_work(tmp_path):
    """-o naming the DEM itself, even with --force: refused (exit 2) before
    the relaxation, not after it.  The hooked binary would stop after its
    first substep and leave a marker file had the relaxation begun."""
    import subprocess
    from conftest import SANDSLIDE_PAUSE, hook_binary, pause_env
    h0 = cliff(24, 16)
    write_asc(tmp_path / "dem.asc", h0)
    before = (tmp_path / "dem.asc").read_bytes()
    marker = tmp_path / "paused"
    env = dict(pause_env(1, marker), SANDSLIDE_TEST_PAUSE_SECONDS="1")
    r = subprocess.run([hook_binary(SANDSLIDE_PAUSE), "relax", "dem.asc", "-o", "dem.asc",
                        "--force"], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "the file the raster was read from" in r.stderr, \
        (r.returncode, r.stderr)
    assert not marker.exists(), "the relaxation ran before the output was refused"
    assert (tmp_path / "dem.asc").read_bytes() == before, "the input changed"
