#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Write the hand-made seed inputs of the fuzz harnesses (tests/fuzz/) into
tests/fuzz/corpus/<harness>/seed-*: small case files with overrides, ESRI
ASCII grids, 16-bit PNG heightmaps and PNG masks of many kinds (bit depths,
colour types, interlaced, tRNS, text chunks before and after the image).
Standard library only; each seed is under 4 KB (cases/reference.ini
under 8 KB).  The HDF5 seeds (corpus/h5/seed-*, under 64 KB: the writer's
B-trees and series chunks take most of it) are small outputs of
build/sandslide (or $SANDSLIDE) and files made with h5py; they are
written only when both are at hand.

    /usr/bin/python3 tests/fuzz/make_seeds.py      (from the repository root)

The case seeds also include cases/*.ini as they are; the fuzzers add their
own inputs beside these (libFuzzer -merge=1 keeps the corpus minimal).
"""
import os
import shutil
import struct
import subprocess
import tempfile
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")


def put(harness, name, data):
    folder = os.path.join(CORPUS, harness)
    os.makedirs(folder, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    limit = {"case": 8192, "h5": 65536}.get(harness, 4096)
    assert len(data) < limit, (harness, name, len(data))
    with open(os.path.join(folder, "seed-" + name), "wb") as f:
        f.write(data)


# ---- case files ----------------------------------------------------------

BASE = """[grid]
nx = 12
ny = 8
dx = 0.25
origin = 0 0

[model]
repose_angle = 35
nu = 0.1

[time]
end = 10
output_every = 1
"""

CASES = {
    "herschel.ini": """[grid]
nx = 16
ny = 16
dx = 0.1
dy = 0.2
origin = -1 -2

[model]
closure = herschel-bulkley
repose_angle = 33.5
gamma = 0.5
delta = 0.01
density = 1600
gravity = 9.81
consistency = 2.5

[time]
end = steady
max_time = 100
output_every = 5
cfl = 0.5
steady_tol = 1e-8

[boundary]
west = periodic
east = periodic
south = open
north = wall
open_level = -0.5
""",
    "cone.ini": """[grid]
nx = 20
ny = 20
dx = 0.05

[model]
closure = bingham
repose_angle = 30
delta = 0.02
density = 1500
viscosity = 0.3

[time]
end = 2.5
output_every = 0.5

[initial]
type = cone
height = 0.1
center = 0.5 0.5
radius = 0.4
angle = 50
""",
    "file.ini": """[grid]
nx = 8
ny = 8
dx = 1

[model]
closure = casson
repose_angle = 35
nu = 2

[time]
end = steady
output_every = 10

[initial]
type = file
file = dem/terrain.asc
bedrock = /abs/rock.png
""",
    "regions.ini": BASE + """
[boundary]
west = open
east = open

[wall block]
rect = 0.5 0.5 1.0 1.5

[wall mask_1]
mask = walls.png

[open hole]
disk = 2 1 0.3

[source pour]
polygon = 0.1 0.1  1.0 0.1 ; first two points
    1.0 1.0  0.1 1.2   ; continued
	0.5 1.9
rate = 0.002
start = 1
stop = 5
""",
}

OVERRIDES = [
    ("override.ini", BASE + "\n[source s]\nrect = 0 0 1 1\nrate = 1e-3\n",
     ["model.closure=casson", "source s.rate=0.002", " grid . nx = 7 ",
      "source s.polygon=0 0 1 0 1 1"]),
    ("override-bad.ini", BASE, ["model.closure", "time.end=steady", "nosuch.key=1",
                                "wall x.rect=0 0 1 1"]),
    ("override-mask.ini", BASE + "\n[wall w]\ndisk = 1 1 0.5\n",
     ["wall w.mask=m.png", "initial.type=file", "initial.file=h.h5:/height",
      "initial.bedrock=b.asc"]),
]


def cases():
    for name in sorted(os.listdir(os.path.join(ROOT, "cases"))):
        if name.endswith(".ini"):
            with open(os.path.join(ROOT, "cases", name), "rb") as f:
                put("case", name, f.read())
    for name, text in CASES.items():
        put("case", "v-" + name, text)
    for name, text, sets in OVERRIDES:
        put("case", name, "\0".join([text] + sets))


# ---- ESRI ASCII grids ----------------------------------------------------

def asc():
    with open(os.path.join(ROOT, "cases", "dem", "terrain.asc")) as f:
        lines = f.read().splitlines()
    head = [ln for ln in lines[:6] if ln.split()[0].isalpha()]
    body = lines[len(head):len(head) + 8]
    rows = [" ".join(ln.split()[:8]) for ln in body]
    head = [("ncols 8" if h.lower().startswith("ncols") else
             "nrows 8" if h.lower().startswith("nrows") else h) for h in head]
    put("asc", "terrain8.asc", "\n".join(head + rows) + "\n")
    put("asc", "centre.asc", "NCOLS 3\nNROWS 2\nXLLCENTER 0.5\nYLLCENTER -0.5\n"
        "CELLSIZE 1\nNODATA_VALUE -9999\n1.5 -9999 2\n-9999 0.25 3e2\n")
    put("asc", "dxdy.asc", "ncols 4\r\nnrows 1\r\nxllcorner -1e3\r\nyllcorner 2.5E-3\r\n"
        "dx 0.5\r\ndy 2\r\n-1 +2 .5 6.02e23\r\n")
    put("asc", "nan.asc", "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0.1\n"
        "NODATA_value nan\nnan 1\n2 NaN\n")
    put("asc", "one.asc", "ncols 1 nrows 1 xllcorner 0 yllcorner 0 cellsize 3 7")
    put("asc", "denormal.asc", "ncols 2\nnrows 1\nyllcorner 0\nxllcorner 0\n"
        "cellsize 1e-300\n4.9e-324 -0\n")


# ---- PNG -----------------------------------------------------------------

def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def pack_row(samples, depth):
    """Samples (ints) of one row at bit depth depth, filter byte first."""
    if depth == 16:
        return b"\0" + b"".join(struct.pack(">H", s) for s in samples)
    if depth == 8:
        return b"\0" + bytes(samples)
    out, acc, bits = bytearray(), 0, 0
    for s in samples:
        acc = acc << depth | s
        bits += depth
        if bits == 8:
            out.append(acc)
            acc, bits = 0, 0
    if bits:
        out.append(acc << (8 - bits))
    return b"\0" + bytes(out)


ADAM7 = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4),
         (1, 0, 2, 2), (0, 1, 1, 2)]


def png(width, height, pixels, depth=8, colour=0, interlace=0, before=(), after=(), level=9):
    """pixels[y][x] is a tuple of samples (one per channel); before and after
    are (kind, data) chunks around the image data; level 0 stores the rows
    uncompressed, so that a mutation changes pixels, not the deflate stream."""
    def raw_rows(xs, ys):
        return b"".join(pack_row([s for x in xs for s in pixels[y][x]], depth) for y in ys)

    if interlace:
        raw = b""
        for x0, y0, dx, dy in ADAM7:
            xs, ys = range(x0, width, dx), range(y0, height, dy)
            if len(xs) and len(ys):
                raw += raw_rows(xs, ys)
    else:
        raw = raw_rows(range(width), range(height))
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0,
                                       interlace)) +
            b"".join(chunk(k, d) for k, d in before) +
            chunk(b"IDAT", zlib.compress(raw, level)) +
            b"".join(chunk(k, d) for k, d in after) + chunk(b"IEND", b""))


def text(key, value):
    return (b"tEXt", key.encode() + b"\0" + value.encode())


def ztext(key, value):
    return (b"zTXt", key.encode() + b"\0\0" + zlib.compress(value.encode()))


def itext(key, value):
    return (b"iTXt", key.encode() + b"\0\0\0\0\0" + value.encode())


def grey16(w, h, f):
    return [[(f(x, y),) for x in range(w)] for y in range(h)]


def dem_png():
    ramp = grey16(8, 6, lambda x, y: 0 if (x, y) == (3, 2) else 1 + (x * 9000 + y * 2000) % 65535)
    gray16 = [text("Software", "sandslide 0.1.0"), text("style", "gray16"),
              text("zmin_m", "-2.5"), text("zmax_m", "40.25"), text("dx_m", "0.5"),
              text("x0_m", "100"), text("y0_m", "-7.125")]
    trns0 = (b"tRNS", struct.pack(">H", 0))
    put("png", "gray16.png", png(8, 6, ramp, 16, before=gray16 + [trns0]))
    put("png", "interlaced.png", png(8, 6, ramp, 16, interlace=1, before=gray16[:4]))
    put("png", "after.png", png(5, 3, grey16(5, 3, lambda x, y: 65535 * (x == y)), 16,
                                before=[trns0],
                                after=[text("zmin_m", "0"), text("zmax_m", "1e3"),
                                       text("dy_m", "0.25"), text("dx_m", "2")]))
    put("png", "ztxt.png", png(3, 4, grey16(3, 4, lambda x, y: 7 + x + y), 16,
                               before=[ztext("zmin_m", "1"), itext("zmax_m", "2"),
                                       (b"tRNS", struct.pack(">H", 7))]))
    put("png", "plain.png", png(4, 4, grey16(4, 4, lambda x, y: x * 4096 + y), 16))
    put("png", "flat.png", png(2, 1, grey16(2, 1, lambda x, y: 1), 16,
                               before=[text("zmin_m", "5"), text("zmax_m", "5")]))
    put("png", "gray8.png", png(4, 2, [[(x * 60,) for x in range(4)]] * 2, 8))
    put("png", "stored.png", png(6, 5, ramp[:5], 16, before=gray16 + [trns0], level=0))
    put("png", "stored-interlaced.png", png(5, 4, [r[:5] for r in ramp[:4]], 16, interlace=1,
                                            before=gray16[2:4], level=0))


def masks():
    W, H = 8, 6
    g8 = [[(255 if (x + y) % 3 else 0,) for x in range(W)] for y in range(H)]
    put("mask", "gray8.png", png(W, H, g8))
    put("mask", "gray1.png", png(W, H, [[(v[0] & 1,) for v in row] for row in g8], 1))
    put("mask", "gray4-interlaced.png",
        png(W, H, [[((x ^ y) & 15,) for x in range(W)] for y in range(H)], 4, interlace=1))
    put("mask", "gray16.png", png(W, H, grey16(W, H, lambda x, y: 257 * x * y), 16,
                                  before=[(b"gAMA", struct.pack(">I", 45455))]))
    put("mask", "rgb.png", png(W, H, [[(x * 30, y * 40, 0) for x in range(W)]
                                      for y in range(H)], 8, 2,
                               before=[(b"tRNS", struct.pack(">HHH", 0, 0, 0))]))
    put("mask", "rgba16.png", png(4, 3, [[(x, y, 9, 65535 * (x > 1)) for x in range(4)]
                                         for y in range(3)], 16, 6))
    put("mask", "grayalpha.png", png(W, H, [[(200, 255 * (y > 2)) for x in range(W)]
                                            for y in range(H)], 8, 4))
    plte = (b"PLTE", bytes([0, 0, 0, 255, 255, 255, 10, 200, 30]))
    put("mask", "palette2.png", png(W, H, [[((x + y) % 3,) for x in range(W)]
                                           for y in range(H)], 2, 3,
                                    before=[plte, (b"tRNS", b"\xff\x80")]))
    put("mask", "srgb-interlaced.png", png(3, 2, [[(1, 2, 3)] * 3] * 2, 8, 2, interlace=1,
                                           before=[(b"sRGB", b"\0")]))
    put("mask", "one.png", png(1, 1, [[(255,)]]))
    put("mask", "stored.png", png(W, H, g8, level=0))
    put("mask", "stored-rgba.png", png(5, 4, [[(x * 50, y * 60, 7, 255 * (x != y)) for x in range(5)]
                                              for y in range(4)], 8, 6, level=0))
    put("mask", "9x6.png", png(9, 6, [[(255,)] * 9] * 6))


# ---- HDF5 files -----------------------------------------------------------

H5_CASE = """[grid]
nx = 5
ny = 4
dx = 0.1
dy = 0.2
origin = -0.1 2

[model]
closure = herschel-bulkley
repose_angle = 33
nu = 0.05
gamma = 0.5

[time]
cfl = 0.5
output_every = 0.2
end = 0.4

[boundary]
south = periodic
north = periodic
east = open
open_level = 0.05

[initial]
type = flat
height = 0.3

[wall post]
rect = 0 2.2 0.1 2.4

[source pour]
rect = 0.1 2.0 0.2 2.2
rate = 1e-3
"""


DIAGNOSTICS = ["volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
               "active_fraction", "wall_seconds"]


def sandslide_outputs(binary, d):
    """A run (walls, an open side, a source; deflated heights) and a relax
    of a 3 x 2 grid: the writer's own files."""
    with open(os.path.join(d, "c.ini"), "w") as f:
        f.write(H5_CASE)
    with open(os.path.join(d, "d.asc"), "w") as f:
        f.write("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n0 0 0\n0 0 9\n")
    for args in (["run", "c.ini", "-o", "run.h5", "--deflate", "6", "-q"],
                 ["relax", "d.asc", "-o", "relax.h5", "-q"]):
        # argv[0] "sandslide": the history attribute holds no local path
        subprocess.run(["sandslide"] + args, executable=binary, cwd=d, check=True,
                       capture_output=True)
    for name in ("run", "relax"):
        with open(os.path.join(d, name + ".h5"), "rb") as f:
            put("h5", "sandslide-" + name, f.read())


def h5py_files(h5py, np, d):
    """Files of other writers: the newest format, variable-length strings,
    other number types, no snapshot, a plain (y, x) dataset."""
    path = os.path.join(d, "x.h5")
    with h5py.File(path, "w", libver="latest") as f:
        f.attrs["source"] = "sandslide by hand"            # variable length
        f.attrs["dx"] = np.float32(0.5)
        f.attrs["dy"] = 2
        f.attrs["case"] = "[grid]\nnx = 3\nny = 2\ndx = 0.5\n"
        f.attrs["title"] = "x.ini"
        f.attrs["case_overrides"] = ""
        f.attrs["restart_state"] = np.array([4.0, 0, 0, 0, 0])
        f["height"] = np.arange(12, dtype="<f4").reshape(2, 2, 3)
        f["time"] = np.array([0, 1], dtype=">f8")
        f["cell_type"] = np.array([[0, 1, 2], [0, 0, 1]], dtype="<i2")
        f["x"] = np.array([0.25, 0.75, 1.25])
        for name in DIAGNOSTICS:
            f[name] = np.array([1, 2], dtype="<i4")
    with open(path, "rb") as f:
        put("h5", "latest-format", f.read())
    with h5py.File(path, "w") as f:   # all there, but no snapshot yet
        for name in ("source", "closure", "title"):
            f.attrs[name] = np.bytes_("sandslide 0.1.0" if name == "source" else name)
        f.attrs.create("dx", 0.1, dtype=">f8")
        f.attrs.create("dy", 0.25, dtype="<f4")
        f.create_dataset("cell_type", data=np.eye(4, 5, dtype="u1") * 2)
        f["x"], f["y"] = np.arange(5) * 0.1 + 3, np.arange(4) * 0.25 - 1
        f.create_dataset("height", (0, 4, 5), "f8", maxshape=(None, 4, 5), chunks=(1, 2, 5))
        for name in ["time"] + DIAGNOSTICS:
            f.create_dataset(name, (0,), "f8", maxshape=(None,), chunks=(16,))
    with open(path, "rb") as f:
        put("h5", "no-snapshot", f.read())
    with h5py.File(path, "w") as f:
        f.create_dataset("height", data=np.linspace(0, 1, 12).reshape(3, 4),
                         compression="gzip", shuffle=True, chunks=(2, 2))
        f["cell_type"] = np.ones((3, 4), dtype="u1")
    with open(path, "rb") as f:
        put("h5", "plain-field", f.read())


def h5_seeds():
    binary = os.environ.get("SANDSLIDE", os.path.join(ROOT, "build", "sandslide"))
    try:
        import h5py
        import numpy as np
    except ImportError:
        print("make_seeds: no h5py: HDF5 seeds not written")
        return
    if not os.access(binary, os.X_OK):
        print(f"make_seeds: no {binary} (run make): HDF5 seeds not written")
        return
    d = tempfile.mkdtemp(prefix="sandslide-seeds-")
    try:
        sandslide_outputs(binary, d)
        h5py_files(h5py, np, d)
    finally:
        shutil.rmtree(d)


if __name__ == "__main__":
    cases()
    asc()
    dem_png()
    masks()
    h5_seeds()
