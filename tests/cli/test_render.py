# SPDX-License-Identifier: BSD-3-Clause
"""`sandslide render` and `sandslide run --frames` through the command line
(doc/rendering.md): frames written in time order with their times, frame
selection, bad input (exit 2, nothing written), the video with and without
ffmpeg, and determinism.  Pixel-level properties are in tests/test_render.c.
"""
import os
import shutil
import struct
import subprocess
import zlib

import h5py
import numpy as np
import pytest

from conftest import BASE, SANDSLIDE, edit, h5open, run, run_ok, without_root_powers

# BASE with five snapshots and a source, so the surface changes in time.
CASE = edit(BASE, "output_every = 0.5", "output_every = 0.25") + (
    "\n[source pour]\nrect = 0.2 0.4 0.6 1.2\nrate = 0.05\n")


def read_png(path, pixels=False):
    """Size, bit depth, colour type and text chunks of a PNG; with pixels,
    also the samples as a numpy array (rows, columns[, channels]), decoded
    here with zlib (no image library needed)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    pos, idat, info = 8, [], {"text": {}}
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            info.update(width=w, height=h, depth=depth, ctype=ctype)
        elif kind == b"tEXt":
            key, _, value = body.partition(b"\0")
            info["text"][key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"IDAT":
            idat.append(body)
    if not pixels:
        return info
    channels = {0: 1, 2: 3}[info["ctype"]]
    bpp = channels * info["depth"] // 8
    stride = info["width"] * bpp
    raw = zlib.decompress(b"".join(idat))
    out, prev = bytearray(), bytearray(stride)
    for y in range(info["height"]):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    dtype = ">u2" if info["depth"] == 16 else "u1"
    arr = np.frombuffer(bytes(out), dtype=dtype).reshape(info["height"], info["width"], channels)
    info["pixels"] = arr[:, :, 0] if channels == 1 else arr
    return info


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    """A short run: 5 snapshots of a 20 x 16 grid with a source."""
    d = tmp_path_factory.mktemp("series")
    (d / "case.ini").write_text(CASE)
    run_ok(["run", "case.ini", "-o", "out.h5", "-q"], cwd=d)
    with h5open(d / "out.h5") as f:
        times = f["time"][:]
    assert len(times) == 5
    return d, times


def frames_in(folder):
    return sorted(n for n in os.listdir(folder))


# ---- frames --------------------------------------------------------------

def test_every_frame_in_time_order(series, tmp_path):
    d, times = series
    r = run_ok(["render", d / "out.h5", "-o", tmp_path / "frames"])
    assert "wrote 5 frames" in r.stdout
    names = frames_in(tmp_path / "frames")
    assert names == [f"frame_{k:05d}.png" for k in range(5)], names
    sizes = set()
    for k, name in enumerate(names):
        info = read_png(tmp_path / "frames" / name)
        assert float(info["text"]["time_s"]) == times[k], f"{name}: time"
        assert info["text"]["snapshot"] == str(k)
        assert info["depth"] == 8 and info["ctype"] == 2, "shaded is 8-bit RGB"
        sizes.add((info["width"], info["height"]))
        zs = (info["text"]["zmin_m"], info["text"]["zmax_m"])
        if k == 0:
            scale = zs
        assert zs == scale, "one height scale for the whole series"
    assert sizes == {(520 + 26, 416 + 2 * 26)}, \
        "20 x 16 cells at 26 px per cell, and a wall a cell thick west, south and north"
    with h5open(d / "out.h5") as f:
        h = f["height"][:]
        walls = f["cell_type"][:] == 1
    assert float(scale[0]) == h[:, ~walls].min() and float(scale[1]) == h[:, ~walls].max(), \
        "the default scale is the whole file's range"


def test_frames_slice_and_time(series, tmp_path):
    d, times = series
    run_ok(["render", d / "out.h5", "-o", tmp_path / "a", "--frames", "1:4:2", "-q"])
    names = frames_in(tmp_path / "a")
    assert names == ["frame_00000.png", "frame_00001.png"]
    assert [read_png(tmp_path / "a" / n)["text"]["snapshot"] for n in names] == ["1", "3"]
    run_ok(["render", d / "out.h5", "-o", tmp_path / "b", "--frames", "-2:", "-q"])
    assert [read_png(tmp_path / "b" / n)["text"]["snapshot"]
            for n in frames_in(tmp_path / "b")] == ["3", "4"]
    t = 0.5 * (times[2] + times[3]) - 0.01      # nearer snapshot 2
    run_ok(["render", d / "out.h5", "-o", tmp_path / "c", "--time", t, "-q"])
    assert frames_in(tmp_path / "c") == ["frame_00000.png"]
    assert read_png(tmp_path / "c" / "frame_00000.png")["text"]["snapshot"] == "2"


def python_slice(spec, count):
    """The indices Python's list(range(count))[A:B:STEP] (or [A]) gives."""
    parts = [int(p) if p else None for p in spec.split(":")]
    if len(parts) == 1:
        return [list(range(count))[parts[0]]]
    return list(range(count))[slice(*parts)]


@pytest.mark.parametrize("spec", ["0:100:9", "0:100:2", "::-1", "-1", "-5", "4", "-100:2",
                                  "3:-100:-1", "::-2", "10:-10:-3", "1:", ":-1", "-2::-1",
                                  "::999999999999999999", "::-9223372036854775808"])
def test_frames_as_a_python_slice(series, tmp_path, spec):
    """--frames is a Python slice of the snapshots: bounds clamped to the
    series, negative steps in reverse, frames numbered in the order drawn."""
    d, _ = series
    want = python_slice(spec, 5)
    assert want, "test bug: a spec that selects nothing"
    r = run(["render", d / "out.h5", "-o", tmp_path, "--frames", spec, "--max-size", "16"])
    assert r.returncode == 0, f"--frames {spec} on 5 snapshots: {r.stderr}"
    names = frames_in(tmp_path)
    assert names == [f"frame_{k:05d}.png" for k in range(len(want))], \
        f"--frames {spec}: {names}, expected {len(want)} frames"
    got = [int(read_png(tmp_path / n)["text"]["snapshot"]) for n in names]
    assert got == want, f"--frames {spec} drew snapshots {got}, Python's slice gives {want}"


@pytest.mark.parametrize("spec, expect", [
    ("5:9", "selects no snapshot"), ("3:1", "selects no snapshot"),
    ("-1:0", "selects no snapshot"), ("0:3:-1", "selects no snapshot"),
    ("::0", "STEP is 0"), ("1:4:0", "STEP is 0"),
    ("5", "outside the series"), ("-6", "outside the series"),
    ("1:2:3:4", "expected A:B:STEP"), ("1.5:", "expected A:B:STEP"), ("a", "expected A:B:STEP"),
])
def test_frames_that_select_nothing(series, tmp_path, spec, expect):
    """An empty slice, a step of 0 and an index outside the series exit 2,
    saying which, and write nothing."""
    d, _ = series
    r = run(["render", d / "out.h5", "-o", tmp_path / "f", f"--frames={spec}"])
    assert r.returncode == 2 and expect in r.stderr, \
        f"--frames {spec!r}: exit {r.returncode}, expected 2 and {expect!r}: {r.stderr}"
    assert r.stderr.count("\n") == 1, r.stderr
    assert not (tmp_path / "f").exists(), "nothing written"


def test_gray16_heights_and_range(series, tmp_path):
    d, times = series
    run_ok(["render", d / "out.h5", "-o", tmp_path, "--style", "gray16", "--frames", "4",
            "--zmin", "0", "--zmax", "0.5", "-q"])
    info = read_png(tmp_path / "frame_00000.png", pixels=True)
    assert info["depth"] == 16 and info["ctype"] == 0
    assert (info["width"], info["height"]) == (20, 16), "gray16: one pixel per cell"
    assert float(info["text"]["zmin_m"]) == 0.0 and float(info["text"]["zmax_m"]) == 0.5
    geometry = [float(info["text"][k]) for k in ("dx_m", "dy_m", "x0_m", "y0_m")]
    assert geometry == [0.1, 0.1, 0.0, 0.0], "pixel size and corner: the picture is a DEM"
    with h5open(d / "out.h5") as f:
        h = f["height"][4]
        walls = f["cell_type"][:] == 1
    v = info["pixels"][::-1].astype(float)       # north row first -> south first
    back = (v - 1) * 0.5 / 65534
    step = 0.5 / 65534
    assert np.all(v[walls] == 0)
    assert np.max(np.abs(back[~walls] - h[~walls])) <= 0.5 * step + 1e-12


def test_styles_label_colorbar_and_size(series, tmp_path):
    d, _ = series
    run_ok(["render", d / "out.h5", "-o", tmp_path / "o", "--style", "oblique",
            "--frames", "4", "--label", "-q"])
    info = read_png(tmp_path / "o" / "frame_00000.png")
    assert info["width"] == 520 and info["text"]["style"] == "oblique"
    run_ok(["render", d / "out.h5", "-o", tmp_path / "c", "--frames", "4", "--colorbar",
            "--contour", "0.05", "--cmap", "terrain", "-q"])
    info = read_png(tmp_path / "c" / "frame_00000.png")
    assert info["height"] == 468 and info["width"] > 546, "the colour bar widens the picture"
    run_ok(["render", d / "out.h5", "-o", tmp_path / "m", "--frames", "4", "--max-size", "10",
            "-q"])
    info = read_png(tmp_path / "m" / "frame_00000.png")
    assert (info["width"], info["height"]) == (10 + 3, 8 + 6), \
        "--max-size 10 on 20 x 16 cells, and walls 3 px thick west, south and north"


def test_wall_sides_drawn(series, tmp_path):
    """The file says which grid sides are walls (root attribute boundary),
    and the frames draw them as walls: the case's west, south and north."""
    d, _ = series
    with h5open(d / "out.h5") as f:
        sides = f.attrs["boundary"]
    assert sides == b"west=wall east=open south=wall north=wall", sides
    run_ok(["render", d / "out.h5", "-o", tmp_path, "--frames", "4", "-q"])
    px = read_png(tmp_path / "frame_00000.png", pixels=True)["pixels"]
    wall = np.array([0x2b, 0x2b, 0x30])
    assert np.all(px[:, :26] == wall), "west: a wall 26 px (a cell) wide"
    assert np.all(px[:26, :] == wall) and np.all(px[-26:, :] == wall), "north and south"
    assert not np.all(px[26:-26, -1] == wall), "east is open: sand to the edge"


def test_label_strip_covers_nothing(series, tmp_path):
    """--label puts the time in a white strip above the picture, which is
    otherwise the same pixels; the text is black, antialiased (a real font:
    grey at its edges, no other colour)."""
    d, times = series
    run_ok(["render", d / "out.h5", "-o", tmp_path / "a", "--frames", "2", "-q"])
    run_ok(["render", d / "out.h5", "-o", tmp_path / "b", "--frames", "2", "--label", "-q"])
    a = read_png(tmp_path / "a" / "frame_00000.png", pixels=True)["pixels"]
    b = read_png(tmp_path / "b" / "frame_00000.png", pixels=True)["pixels"]
    strip = b.shape[0] - a.shape[0]
    assert b.shape[1] == a.shape[1] and strip > 7, (a.shape, b.shape)
    assert np.array_equal(b[strip:], a), "the picture below the strip is untouched"
    label = b[:strip].astype(int)
    grey = (label[:, :, 0] == label[:, :, 1]) & (label[:, :, 1] == label[:, :, 2])
    black = np.all(label == 0, axis=2)
    white = np.all(label == 255, axis=2)
    assert np.all(grey) and black.sum() > 50, "black text on white"
    assert (~black & ~white).sum() > 20, "edges in grey: antialiased"


def test_force(series, tmp_path):
    """Frames and a video that exist are replaced only with --force (exit 2
    and nothing touched without it)."""
    d, _ = series
    run_ok(["render", d / "out.h5", "-o", tmp_path / "f", "--frames", "0:2", "-q"])
    before = (tmp_path / "f" / "frame_00001.png").read_bytes()
    r = run(["render", d / "out.h5", "-o", tmp_path / "f", "--frames", "3:5", "-q"])
    assert r.returncode == 2, r.stderr
    assert "frame_00000.png' exists, and 1 more of the 2 frames" in r.stderr, r.stderr
    assert "--force" in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
    assert (tmp_path / "f" / "frame_00001.png").read_bytes() == before, "untouched"
    run_ok(["render", d / "out.h5", "-o", tmp_path / "f", "--frames", "3:5", "-q", "--force"])
    assert read_png(tmp_path / "f" / "frame_00001.png")["text"]["snapshot"] == "4"
    (tmp_path / "v.mp4").write_bytes(b"an earlier video")
    r = run(["render", d / "out.h5", "-o", tmp_path / "g", "--video", tmp_path / "v.mp4"])
    assert r.returncode == 2 and "v.mp4' exists: give --force" in r.stderr, r.stderr
    assert not (tmp_path / "g").exists()
    assert (tmp_path / "v.mp4").read_bytes() == b"an earlier video"


def test_video_frames_have_time_and_scale(series, tmp_path):
    """--video draws the time label and the colour bar unless told not to
    (ffmpeg is kept off PATH: only the frames are looked at)."""
    d, _ = series
    empty = tmp_path / "bin"
    empty.mkdir()
    env = {**os.environ, "PATH": str(empty)}
    size = {}
    for name, extra in (("plain", []), ("video", ["--video", tmp_path / "v.mp4"]),
                        ("bare", ["--video", tmp_path / "w.mp4", "--no-label",
                                  "--no-colorbar"])):
        r = run(["render", d / "out.h5", "-o", tmp_path / name, "--frames", "4", "-q"] + extra,
                env=env)
        assert r.returncode == 0, r.stderr
        info = read_png(tmp_path / name / "frame_00000.png")
        size[name] = (info["width"], info["height"])
    assert size["video"][0] > size["plain"][0] + 30, f"a colour bar: {size}"
    assert size["video"][1] > size["plain"][1], f"a label strip: {size}"
    assert size["bare"] == size["plain"], f"--no-label --no-colorbar: {size}"


def test_same_bytes_on_one_and_two_threads(series, tmp_path):
    """Frames split between threads, or rows of one frame: the same files."""
    d, _ = series
    for threads in ("1", "2"):
        run_ok(["render", d / "out.h5", "-o", tmp_path / threads, "--threads", threads,
                "--style", "oblique", "-q"])
        run_ok(["render", d / "out.h5", "-o", tmp_path / ("one" + threads), "--frames", "3",
                "--threads", threads, "-q"])
    for name in frames_in(tmp_path / "1"):
        assert (tmp_path / "1" / name).read_bytes() == (tmp_path / "2" / name).read_bytes(), name
    assert ((tmp_path / "one1" / "frame_00000.png").read_bytes() ==
            (tmp_path / "one2" / "frame_00000.png").read_bytes())


# ---- bad input: exit 2, a clear message, nothing written ------------------

def make_empty_series(path):
    """A file laid out like sandslide output but with no snapshot."""
    with h5py.File(path, "w") as f:
        f.attrs["source"] = np.bytes_("sandslide 0.1.0")
        f.attrs["dx"] = 0.1
        f.attrs["dy"] = 0.1
        f.create_dataset("height", shape=(0, 4, 5), maxshape=(None, 4, 5), dtype="f8",
                         chunks=(1, 4, 5))
        f.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8", chunks=(16,))
        f.create_dataset("cell_type", data=np.zeros((4, 5), dtype="u1"))


@pytest.mark.parametrize("what", ["text", "hdf5", "empty", "missing"])
def test_bad_files(tmp_path, what):
    path = tmp_path / "in.h5"
    if what == "text":
        path.write_text("not hdf5\n")
        expect = "is not an HDF5 file"
    elif what == "hdf5":
        with h5py.File(path, "w") as f:
            f["height"] = np.zeros((2, 3, 3))
        expect = "is not a sandslide output file"
    elif what == "empty":
        make_empty_series(path)
        expect = "holds no snapshots"
    else:
        expect = "cannot open"
    r = run(["render", path, "-o", tmp_path / "frames"])
    assert r.returncode == 2, r.stderr
    assert expect in r.stderr and str(path) in r.stderr, r.stderr
    assert not (tmp_path / "frames").exists(), "nothing written"


@pytest.mark.parametrize("args, expect", [
    (["--frames", "5:9"], "selects no snapshot"),
    (["--frames", "7"], "outside the series"),
    (["--frames", "3:1"], "selects no snapshot"),
    (["--frames", "a:b"], "expected A:B:STEP"),
    (["--time", "99"], "outside the series"),
    (["--zmin", "0.5", "--zmax", "0.1"], "not below --zmax"),
    (["--zmin", "0.3", "--zmax", "0.3"], "not below --zmax"),
    (["--zmin", "5"], "give --zmax too"),
    (["--style", "gray16", "--label"], "do not apply to --style gray16"),
    (["--style", "ruled"], "expected shaded, gray16, oblique"),
    (["--altitude", "0"], "(0, 90]"),
    (["--fps", "0", "--video", "v.mp4"], "--fps"),
])
def test_bad_choices(series, tmp_path, args, expect):
    d, _ = series
    r = run(["render", d / "out.h5", "-o", tmp_path / "frames"] + args, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert expect in r.stderr, r.stderr
    assert not (tmp_path / "frames").exists(), "nothing written"


def test_bad_output_folders(series, tmp_path):
    d, _ = series
    r = run(["render", d / "out.h5", "-o", tmp_path / "no" / "such"])
    assert r.returncode == 2 and "does not exist" in r.stderr, r.stderr
    (tmp_path / "file").write_text("x")
    r = run(["render", d / "out.h5", "-o", tmp_path / "file"])
    assert r.returncode == 2 and "not a folder" in r.stderr, r.stderr
    r = run(["render", d / "out.h5", "-o", tmp_path / "f", "--video", tmp_path / "no" / "v.mp4"])
    assert r.returncode == 2 and "does not exist" in r.stderr, r.stderr
    assert not (tmp_path / "f").exists()
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    r = subprocess.run(without_root_powers() + [SANDSLIDE, "render", d / "out.h5", "-o", locked],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "not writable" in r.stderr, r.stderr
    assert os.listdir(locked) == []


def test_no_partial_frames_left(series, tmp_path):
    d, _ = series
    run_ok(["render", d / "out.h5", "-o", tmp_path, "-q"])
    assert not [n for n in os.listdir(tmp_path) if "partial" in n]


# ---- video ---------------------------------------------------------------

def test_video_without_ffmpeg_keeps_frames(series, tmp_path):
    d, _ = series
    empty = tmp_path / "bin"
    empty.mkdir()
    r = run(["render", d / "out.h5", "-o", tmp_path / "frames", "--video", tmp_path / "v.mp4"],
            env={**os.environ, "PATH": str(empty)})
    assert r.returncode == 0, r.stderr
    assert "ffmpeg is not on PATH" in r.stderr
    assert len(frames_in(tmp_path / "frames")) == 5, "the frames are kept"
    assert not (tmp_path / "v.mp4").exists()


@pytest.mark.skipif(not (shutil.which("ffmpeg") and shutil.which("ffprobe")),
                    reason="ffmpeg or ffprobe not on PATH (Debian package ffmpeg)")
def test_video_alone_keeps_no_frames(series, tmp_path):
    """--video without -o: the video, and no frames/ nor the temporary
    folder its frames went to, in the working folder or the video's."""
    d, _ = series
    (tmp_path / "work").mkdir()
    (tmp_path / "films").mkdir()
    r = run_ok(["render", d / "out.h5", "--video", tmp_path / "films" / "v.mp4",
                "--frames", "::-1", "--max-size", "64"], cwd=tmp_path / "work")
    assert os.listdir(tmp_path / "work") == [], \
        f"the working folder got {os.listdir(tmp_path / 'work')} (a frames/ folder?)"
    assert os.listdir(tmp_path / "films") == ["v.mp4"], \
        f"beside the video: {os.listdir(tmp_path / 'films')} (frames left behind?)"
    # five frames, none given a rate: one a second (a quarter of 5, at least 1)
    assert r.stdout == "wrote %s: 5 frames at 1 frames/s\n" % (tmp_path / "films" / "v.mp4"), \
        r.stdout
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                            "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0",
                            str(tmp_path / "films" / "v.mp4")],
                           capture_output=True, text=True, timeout=60)
    assert probe.stdout.strip() == "5", probe.stdout + probe.stderr


def test_video_alone_without_ffmpeg_is_refused(series, tmp_path):
    """--video without -o and without ffmpeg would make nothing: exit 2
    before anything is written, saying -o keeps the frames."""
    d, _ = series
    empty = tmp_path / "bin"
    empty.mkdir()
    r = run(["render", d / "out.h5", "--video", "v.mp4"], cwd=tmp_path,
            env={**os.environ, "PATH": str(empty)})
    assert r.returncode == 2, r.stderr
    assert "ffmpeg is not on PATH" in r.stderr and "-o DIR" in r.stderr, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["bin"], "something was written"


@pytest.mark.skipif(not (shutil.which("ffmpeg") and shutil.which("ffprobe")),
                    reason="ffmpeg or ffprobe not on PATH (Debian package ffmpeg)")
def test_video_frame_count(series, tmp_path):
    d, _ = series
    # a frame left over from a longer earlier series must not get in
    (tmp_path / "frames").mkdir()
    (tmp_path / "frames" / "frame_00005.png").write_bytes(b"not a picture")
    r = run_ok(["render", d / "out.h5", "-o", tmp_path / "frames", "--video",
                tmp_path / "v.mp4", "--fps", "10", "--max-size", "101"], timeout=300)
    assert "left from an earlier render" in r.stdout
    assert (tmp_path / "v.mp4").stat().st_size > 0
    assert not (tmp_path / "v.partial.mp4").exists()
    probe = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
         "-show_entries", "stream=nb_read_frames,codec_name,pix_fmt", "-of",
         "default=noprint_wrappers=1", str(tmp_path / "v.mp4")],
        capture_output=True, text=True, timeout=60)
    fields = dict(line.split("=", 1) for line in probe.stdout.split())
    assert fields == {"codec_name": "h264", "pix_fmt": "yuv420p", "nb_read_frames": "5"}, \
        probe.stdout + probe.stderr


def probe_video(path):
    """Frames, frame rate and duration (s) of a video, by ffprobe."""
    probe = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
         "-show_entries", "stream=nb_read_frames,r_frame_rate:format=duration", "-of",
         "default=noprint_wrappers=1", str(path)], capture_output=True, text=True, timeout=60)
    fields = dict(line.split("=", 1) for line in probe.stdout.split())
    num, den = fields["r_frame_rate"].split("/")
    return int(fields["nb_read_frames"]), int(num) / int(den), float(fields["duration"])


@pytest.mark.skipif(not (shutil.which("ffmpeg") and shutil.which("ffprobe")),
                    reason="ffmpeg or ffprobe not on PATH (Debian package ffmpeg)")
def test_video_of_few_frames_lasts_seconds(tmp_path):
    """Without --fps the frame rate comes from the number of frames: a
    quarter of them per second, 1 to 24, so that 21 frames play for 4.2 s
    at 5 frames/s, not 0.9 s at 24 (issue 36); the viewer starts at the
    same speed; --fps still wins."""
    (tmp_path / "case.ini").write_text(edit(BASE, "output_every = 0.5", "output_every = 0.05"))
    run_ok(["run", "case.ini", "-o", "out.h5", "-q"], cwd=tmp_path)
    r = run_ok(["render", "out.h5", "--video", "v.mp4", "--html", "v.html", "--max-size", "64"],
               cwd=tmp_path)
    assert "wrote v.mp4: 21 frames at 5 frames/s" in r.stdout, r.stdout
    frames, rate, seconds = probe_video(tmp_path / "v.mp4")
    assert (frames, rate) == (21, 5) and seconds >= 4.0, (frames, rate, seconds)
    assert "fps: 5," in (tmp_path / "v.html").read_text(), "the viewer's starting speed"
    run_ok(["render", "out.h5", "--video", "w.mp4", "--fps", "24", "--max-size", "64", "-q"],
           cwd=tmp_path)
    frames, rate, seconds = probe_video(tmp_path / "w.mp4")
    assert (frames, rate) == (21, 24) and seconds < 1.0, (frames, rate, seconds)


# ---- run --frames ---------------------------------------------------------

def test_run_frames_as_written(tmp_path):
    (tmp_path / "case.ini").write_text(CASE)
    r = run_ok(["run", "case.ini", "-o", "out.h5", "--frames", "frames", "--label"],
               cwd=tmp_path)
    assert "wrote 5 frames to frames/" in r.stdout
    with h5open(tmp_path / "out.h5") as f:
        times = f["time"][:]
        hmax = f["height"][:].max()
        hmin = f["height"][:].min()
    names = frames_in(tmp_path / "frames")
    assert names == [f"frame_{k:05d}.png" for k in range(5)]
    infos = [read_png(tmp_path / "frames" / n) for n in names]
    assert [float(i["text"]["time_s"]) for i in infos] == list(times)
    scales = {(i["text"]["zmin_m"], i["text"]["zmax_m"]) for i in infos}
    assert len(scales) == 1, "one scale for all the frames of the run"
    zmin, zmax = map(float, scales.pop())
    # flat 0.2 m with an open side at 0 m; the source adds at most 0.05 m/s x 1 s
    assert zmin == 0.0 and zmax == pytest.approx(0.25)
    # (up to the round-off of summing the source's increments)
    assert zmin <= hmin and hmax <= zmax * (1 + 1e-12), "the bound holds every height"


def test_run_frames_bad_folder_touches_nothing(tmp_path):
    (tmp_path / "case.ini").write_text(CASE)
    r = run(["run", "case.ini", "-o", "out.h5", "--frames", "no/such"], cwd=tmp_path)
    assert r.returncode == 2 and "does not exist" in r.stderr, r.stderr
    assert not (tmp_path / "out.h5").exists()
    r = run(["run", "case.ini", "-o", "out.h5", "--label"], cwd=tmp_path)
    assert r.returncode == 2 and "needs --frames" in r.stderr, r.stderr
    r = run(["run", "case.ini", "-o", "out.h5", "--frames", "f", "--zmin", "1", "--zmax", "0"],
            cwd=tmp_path)
    assert r.returncode == 2 and "not below --zmax" in r.stderr, r.stderr
    assert not (tmp_path / "out.h5").exists() and not (tmp_path / "f").exists()


def test_help_and_usage(tmp_path):
    r = run_ok(["render", "--help"])
    for option in ("--frames", "--time", "--style", "--video", "--max-size", "--contour",
                   "--colorbar", "--label", "--view-azimuth", "--zmin"):
        assert option in r.stdout, option
    assert "render" in run_ok(["--help"]).stdout
    assert "--frames DIR" in run_ok(["run", "--help"]).stdout
    r = run(["render"])
    assert r.returncode == 2 and "needs a sandslide output file" in r.stderr
    r = run(["render", "x.h5", "--bogus"])
    assert r.returncode == 2 and "unknown option" in r.stderr


@pytest.mark.parametrize("n", [64, 600])
def test_render_bench_small_and_large_grids(n):
    """--bench times one pixel per cell: a grid under 512 cells a side, which
    frames enlarge by default, used to crash it (found in issue 12)."""
    r = run_ok(["render", "--bench", str(n), "--threads", "1"])
    assert f"shaded {n} x {n}" in r.stdout and "png encoding, zlib level 6" in r.stdout, \
        r.stdout
