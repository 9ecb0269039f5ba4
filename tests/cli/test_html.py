# SPDX-License-Identifier: BSD-3-Clause
"""`sandslide render --html`: the self-contained viewer of a run.

The file: nothing in it reaches outside it (no http:, no external script,
style sheet or font; every picture a data: URI), it embeds one PNG per
chosen snapshot (the very bytes `render -o` writes), an existing file is
refused without --force and replaced with it, a bad path exits 2 naming it,
and --html alone writes no frame folder.

The page, in headless Chromium through selenium (chromium-driver): the
screenshot is not blank, the slider and the arrow keys change the frame and
the time shown (the snapshot's time read with h5py), the height under the
mouse and at a clicked point is the file's /height at that cell within the
quantisation step (walls say wall, open cells say so), the x, y shown are
the cell's /x, /y, play advances the frames and space pauses, and the
browser logs no error.  `make deps-test` installs Chromium, its driver and
selenium; without them those tests are skipped, saying which is missing.
"""
import base64
import io
import os
import re
import shutil
import struct
import time
import zlib

import numpy as np
import pytest

from conftest import BASE, edit, h5open, run, run_ok

# BASE (20 x 16 cells of 0.1 m) with five snapshots, a source so that the
# surface changes in time, a wall block and an open drain.
CASE = edit(BASE, "output_every = 0.5", "output_every = 0.25") + """
[source pour]
rect = 0.2 0.4 0.6 1.2
rate = 0.05

[wall block]
rect = 1.0 0.5 1.3 0.8

[open drain]
rect = 1.6 0.2 1.8 0.4
"""

CHROMEDRIVER = "/usr/bin/chromedriver"


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    """The run, and what the file holds."""
    d = tmp_path_factory.mktemp("html")
    (d / "case.ini").write_text(CASE)
    run_ok(["run", "case.ini", "-o", "out.h5", "-q"], cwd=d)
    with h5open(d / "out.h5") as f:
        data = {k: f[k][:] for k in ("time", "height", "cell_type", "x", "y")}
    assert len(data["time"]) == 5
    types = data["cell_type"]
    assert (types == 1).any() and (types == 2).any(), \
        "test bug: the case needs walls and open cells"
    return d, data


@pytest.fixture(scope="module")
def viewer(series):
    """The viewer of every snapshot, written from a folder of its own."""
    d, _ = series
    work = d / "viewer"
    work.mkdir()
    r = run_ok(["render", d / "out.h5", "--html", "view.html"], cwd=work)
    return work / "view.html", r.stdout, work


def embedded_frames(text):
    """The PNGs of the page, decoded, in the order of its frames."""
    return [base64.b64decode(b) for b in
            re.findall(r"'data:image/png;base64,([A-Za-z0-9+/=]*)'", text)]


def png_texts(data):
    """The tEXt chunks of a PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, texts = 8, {}
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if kind == b"tEXt":
            key, _, value = data[pos + 8:pos + 8 + n].partition(b"\0")
            texts[key.decode("latin-1")] = value.decode("latin-1")
        pos += 12 + n
    return texts


# ---- the file ----------------------------------------------------------------

def test_summary_and_no_frame_folder(viewer):
    path, stdout, work = viewer
    # 20 x 16 cells at 26 px, a wall a cell thick west, south and north
    m = re.fullmatch(r"wrote view\.html: 5 frames of 546 x 468 px, (\d+) kB\n", stdout)
    assert m, stdout
    assert abs(int(m.group(1)) * 1000 - path.stat().st_size) <= 500, "the size printed"
    assert sorted(os.listdir(work)) == ["view.html"], \
        "--html alone writes the viewer and nothing else (no frames/, no .partial)"


def test_self_contained(viewer):
    path, _, _ = viewer
    text = path.read_text(encoding="utf-8")
    for outside in ("http:", "https:", "//cdn", "<script src", "<link", "@import", "url("):
        assert outside.lower() not in text.lower(), f"the page reaches outside: {outside!r}"
    for tag in re.findall(r"<(?:img|script|iframe|source|video|audio|embed|object)\b[^>]*>",
                          text, flags=re.I):
        src = re.search(r"\bsrc\s*=\s*['\"]?([^'\" >]*)", tag)
        assert src is None or src.group(1).startswith("data:"), f"external source: {tag}"
    assert text.count("data:image/png;base64,") == 5, "one picture per snapshot"
    assert len(re.findall(r"data:(?!image/png;base64,)", text)) == 0, "only PNG data: URIs"


def test_frames_are_render_frames(series, viewer, tmp_path):
    """The embedded frames are the bytes `render -o` writes, in time order."""
    d, data = series
    path, _, _ = viewer
    frames = embedded_frames(path.read_text(encoding="utf-8"))
    run_ok(["render", d / "out.h5", "-o", tmp_path, "-q"])
    assert len(frames) == 5
    for k, png in enumerate(frames):
        assert png == (tmp_path / f"frame_{k:05d}.png").read_bytes(), f"frame {k}"
        texts = png_texts(png)
        assert float(texts["time_s"]) == data["time"][k] and texts["snapshot"] == str(k)


def test_selection_and_look(series, tmp_path):
    d, data = series
    r = run_ok(["render", d / "out.h5", "--html", tmp_path / "v.html", "--frames", "1:4:2",
                "--cmap", "terrain", "--max-size", "100"])
    # 100 x 80 px of map (5 px a cell), the wall sides a cell thick
    assert "wrote " + str(tmp_path / "v.html") + ": 2 frames of 105 x 90 px" in r.stdout, \
        r.stdout
    frames = embedded_frames((tmp_path / "v.html").read_text(encoding="utf-8"))
    assert [png_texts(f)["snapshot"] for f in frames] == ["1", "3"]
    assert os.listdir(tmp_path) == ["v.html"]


def test_with_frames_and_viewer(series, tmp_path):
    """-o DIR with --html: both, from the same frames."""
    d, _ = series
    r = run_ok(["render", d / "out.h5", "-o", tmp_path / "frames", "--html",
                tmp_path / "v.html", "--frames", "2:"])
    assert "wrote 3 frames of 546 x 468 px to" in r.stdout and "v.html: 3 frames" in r.stdout
    names = sorted(os.listdir(tmp_path / "frames"))
    assert names == [f"frame_{k:05d}.png" for k in range(3)]
    frames = embedded_frames((tmp_path / "v.html").read_text(encoding="utf-8"))
    assert frames == [(tmp_path / "frames" / n).read_bytes() for n in names]


def test_existing_file_needs_force(series, tmp_path):
    d, _ = series
    out = tmp_path / "v.html"
    out.write_text("an earlier viewer")
    r = run(["render", d / "out.h5", "--html", out, "--frames", "0"])
    assert r.returncode == 2, r.stderr
    assert str(out) in r.stderr and "exists" in r.stderr and "--force" in r.stderr, r.stderr
    assert out.read_text() == "an earlier viewer", "refused: left as it was"
    run_ok(["render", d / "out.h5", "--html", out, "--frames", "0", "--force", "-q"])
    assert out.read_text(encoding="utf-8").count("data:image/png;base64,") == 1, "replaced"
    assert sorted(os.listdir(tmp_path)) == ["v.html"], "no .partial left"


def test_bad_paths(series, tmp_path):
    d, _ = series
    missing = tmp_path / "no" / "such" / "v.html"
    r = run(["render", d / "out.h5", "--html", missing])
    assert r.returncode == 2, r.stderr
    assert str(missing) in r.stderr and "does not exist" in r.stderr and \
        str(tmp_path / "no" / "such") in r.stderr, r.stderr
    (tmp_path / "dir.html").mkdir()
    r = run(["render", d / "out.h5", "--html", tmp_path / "dir.html", "--force"])
    assert r.returncode == 2 and "is a folder" in r.stderr, r.stderr
    r = run(["render", d / "out.h5", "--html", tmp_path / "v.html", "--fps", "0"])
    assert r.returncode == 2 and "--fps" in r.stderr, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["dir.html"], "nothing written"


def page_heights(text):
    """The page's data grid and its heights per frame (rows north first;
    NaN for walls and no data), decoded as the page decodes them."""
    meta = {k: v for k, v in re.findall(r"\b(cells|gw|gh|qlo|qhi): ([^,\s]+)", text)}
    gw, gh = int(meta["gw"]), int(meta["gh"])
    qlo, qhi = float(meta["qlo"]), float(meta["qhi"])
    block = text[text.index("const HEIGHTS = ["):]
    block = block[:block.index("];")]
    out = []
    for b in re.findall(r"'([A-Za-z0-9+/=]*)'", block):
        codes = np.frombuffer(zlib.decompress(base64.b64decode(b)), dtype="<u2")
        assert codes.size == gw * gh
        h = qlo + (codes.astype(float) - 2) * (qhi - qlo) / 65533
        h[codes < 2] = np.nan
        out.append(h.reshape(gh, gw))
    return meta["cells"] == "true", (qhi - qlo) / 65533, out


def test_embedded_heights_are_the_cells(series, viewer):
    _, data = series
    path, _, _ = viewer
    cells, step, frames = page_heights(path.read_text(encoding="utf-8"))
    h, walls = data["height"], data["cell_type"] == 1
    assert cells and len(frames) == 5
    assert step < 1e-5, "16-bit steps over the file's range of heights"
    for k, f in enumerate(frames):
        f = f[::-1]                          # south row first, as in the file
        assert np.array_equal(np.isnan(f), walls), "walls, and only walls, have no height"
        assert np.max(np.abs(f[~walls] - h[k][~walls])) <= 0.5 * step + 1e-12, f"frame {k}"


def test_embedded_heights_beyond_the_scale_and_pixel_means(series, tmp_path):
    """--zmax below the sand still reads back the true heights; a picture
    smaller than the grid embeds its pixels' heights, the means of the
    cells each covers (walls left out)."""
    d, data = series
    h, walls = data["height"], data["cell_type"] == 1
    run_ok(["render", d / "out.h5", "--html", tmp_path / "z.html", "--zmax", "0.1", "-q"])
    cells, step, frames = page_heights((tmp_path / "z.html").read_text(encoding="utf-8"))
    assert cells
    for k, f in enumerate(frames):
        assert np.max(np.abs(f[::-1][~walls] - h[k][~walls])) <= 0.5 * step + 1e-12
    run_ok(["render", d / "out.h5", "--html", tmp_path / "p.html", "--max-size", "10", "-q"])
    cells, step, frames = page_heights((tmp_path / "p.html").read_text(encoding="utf-8"))
    assert not cells and frames[0].shape == (8, 10), "2 x 2 cells a pixel"
    for k, f in enumerate(frames):
        sand = (~walls).reshape(8, 2, 10, 2)
        sums = np.where(walls, 0.0, h[k]).reshape(8, 2, 10, 2).sum(axis=(1, 3))
        means = (sums / np.maximum(sand.sum(axis=(1, 3)), 1))[::-1]
        sand = ~np.isnan(f)
        assert sand.sum() > 60
        assert np.max(np.abs(f[sand] - means[sand])) <= 0.5 * step + 1e-12, f"frame {k}"


# ---- the page in a browser -----------------------------------------------------

def browser_missing():
    """Why the page cannot be opened here, or None."""
    missing = [n for n in ("chromium",) if shutil.which(n) is None]
    if not os.access(CHROMEDRIVER, os.X_OK):
        missing.append(f"chromedriver ({CHROMEDRIVER})")
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("selenium (python3-selenium)")
    if missing:
        return ("cannot open the viewer in a browser: " + ", ".join(missing) + " missing "
                "(Debian packages chromium chromium-driver python3-selenium; make deps-test)")
    return None


@pytest.fixture(scope="module")
def browser():
    reason = browser_missing()
    if reason:
        pytest.skip(reason)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1000,860",
              "--force-device-scale-factor=1", "--allow-file-access-from-files"):
        options.add_argument(a)
    options.binary_location = shutil.which("chromium")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    yield driver
    driver.quit()


@pytest.fixture
def page(browser, viewer):
    """The viewer freshly loaded, its last frame shown."""
    path, _, _ = viewer
    browser.get_log("browser")    # what an earlier test left
    browser.get(path.as_uri())
    wait(browser, lambda: browser.execute_script(
        "const p = document.getElementById('pic'); return p.complete && p.naturalWidth > 0;"),
        "the first frame to load")
    time.sleep(0.1)
    assert_no_js_errors(browser)
    return browser


def wait(driver, predicate, what, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        v = predicate()
        if v:
            return v
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def assert_no_js_errors(driver):
    errors = [e for e in driver.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert not errors, f"the browser logged errors: {errors}"


def shown(driver):
    """The frame shown: the slider's value, the time and frame texts, the img's src."""
    return driver.execute_script(
        "const $ = id => document.getElementById(id);"
        "return [Number($('slider').value), $('time').textContent, $('frame').textContent,"
        "        $('pic').src.length, $('pic').src.slice(-64)];")


def time_of(text):
    m = re.fullmatch(r"t = (\S+) s", text)
    assert m, f"time text {text!r}"
    return float(m.group(1))


def test_screenshot_is_not_blank(page):
    from PIL import Image
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.HOME, Keys.ARROW_RIGHT)   # frame 1
    time.sleep(0.2)
    shot = Image.open(io.BytesIO(page.get_screenshot_as_png())).convert("RGB")
    colours = shot.getcolors(maxcolors=1 << 20)
    white = max((c for c in colours if c[1] == (255, 255, 255)), default=(0, None))[0]
    assert white < 0.5 * shot.width * shot.height, "mostly white"
    # the frame itself: shaded sand, walls, the drain
    r = page.execute_script("const r = document.getElementById('pic').getBoundingClientRect();"
                            "return [r.left, r.top, r.right, r.bottom];")
    assert r[2] - r[0] >= 500 and r[3] - r[1] >= 400, f"the picture is shown at {r}"
    frame = shot.crop(tuple(int(round(v)) for v in r)).getcolors(maxcolors=1 << 20)
    assert frame is not None and len(frame) > 100, \
        f"{len(frame or [])} distinct colours in the picture: it looks blank"
    assert_no_js_errors(page)


def test_slider_and_keys_change_the_frame(page, series):
    _, data = series
    times = data["time"]
    # the page opens on the last frame: what the run made (a pouring case
    # starts empty)
    k4 = shown(page)
    assert k4[0] == 4 and time_of(k4[1]) == pytest.approx(times[4], rel=1e-5), \
        f"the page opened on {k4[:3]}, not the last frame"
    assert k4[2].startswith("frame 5 / 5") and "snapshot 4" in k4[2], k4[2]
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.HOME)
    k0 = shown(page)
    assert k0[0] == 0 and time_of(k0[1]) == pytest.approx(times[0], rel=1e-5, abs=1e-9)
    assert k0[2].startswith("frame 1 / 5")
    assert k0[3:] != k4[3:], "Home shows another picture"
    page.execute_script("const s = document.getElementById('slider');"
                        "s.value = 3; s.dispatchEvent(new Event('input', {bubbles: true}));")
    k3 = shown(page)
    assert k3[0] == 3 and k3[2].startswith("frame 4 / 5") and "snapshot 3" in k3[2]
    assert time_of(k3[1]) == pytest.approx(times[3], rel=1e-5)
    assert k3[3:] != k0[3:], "the picture changed"
    body = page.find_element(By.TAG_NAME, "body")
    body.send_keys(Keys.ARROW_RIGHT)
    assert shown(page)[0] == 4 and time_of(shown(page)[1]) == pytest.approx(times[4], rel=1e-5)
    body.send_keys(Keys.ARROW_RIGHT)
    assert shown(page)[0] == 4, "stays at the last frame"
    body.send_keys(Keys.ARROW_LEFT, Keys.ARROW_LEFT)
    assert shown(page)[0] == 2 and time_of(shown(page)[1]) == pytest.approx(times[2], rel=1e-5)
    # the slider focused: one step per key, not two
    page.find_element(By.ID, "slider").send_keys(Keys.ARROW_RIGHT)
    assert shown(page)[0] == 3
    assert_no_js_errors(page)


def move_to_cell(driver, i, j, nx, ny, click=False):
    """Put the mouse on the centre of cell (i, j) (j = 0 the south row): the
    map lies mapW x mapH px from (mapX, mapY) in a frame of imageW x imageH
    (a label strip above, wall sides round it, a colour bar right)."""
    from selenium.webdriver.common.actions.action_builder import ActionBuilder
    r = driver.execute_script(
        "const r = document.getElementById('pic').getBoundingClientRect();"
        "return [r.left, r.top, r.width, r.height, SS.imageW, SS.imageH, SS.mapX, SS.mapY,"
        " SS.mapW, SS.mapH];")
    sx, sy = r[2] / r[4], r[3] / r[5]        # screen px per frame px
    x = r[0] + (r[6] + (i + 0.5) * r[8] / nx) * sx
    y = r[1] + (r[7] + (ny - 1 - j + 0.5) * r[9] / ny) * sy
    ab = ActionBuilder(driver)
    ab.pointer_action.move_to_location(int(round(x)), int(round(y)))
    if click:
        ab.pointer_action.click()
    ab.perform()


def readout(driver, which, frame, i, j):
    """The readout's text and data once it is that of cell (i, j) in frame."""
    def ready():
        d = driver.execute_script(
            f"const e = document.getElementById('{which}');"
            "return [e.textContent, Object.assign({}, e.dataset)];")
        ok = (d[1].get("frame") == str(frame) and d[1].get("i") == str(i) and
              d[1].get("j") == str(j))
        return d if ok else None
    return wait(driver, ready, f"the {which} readout of cell ({i}, {j}) in frame {frame}")


def test_height_under_the_mouse_and_pinned(page, series):
    _, data = series
    h, types, xs, ys = data["height"], data["cell_type"], data["x"], data["y"]
    ny, nx = types.shape
    lo, hi = np.nanmin(h[:, types != 1]), np.nanmax(h[:, types != 1])
    step = (hi - lo) / 65533     # the page's quantisation step (render/html.c)
    page.execute_script("const s = document.getElementById('slider');"
                        "s.value = 3; s.dispatchEvent(new Event('input', {bubbles: true}));")
    # the highest sand (under the source), the lowest (by the drain), a wall, an open cell
    j, i = np.unravel_index(np.argmax(np.where(types == 0, h[3], -np.inf)), types.shape)
    top = (int(i), int(j))
    j, i = np.unravel_index(np.argmin(np.where(types == 0, h[3], np.inf)), types.shape)
    slope = (int(i), int(j))
    wall = tuple(int(v) for v in np.argwhere(types == 1)[0][::-1])
    drain = tuple(int(v) for v in np.argwhere(types == 2)[0][::-1])
    cells = [top, slope, wall, drain]
    assert h[3, slope[1], slope[0]] < h[3, top[1], top[0]]
    for i, j in cells:
        move_to_cell(page, i, j, nx, ny)
        text, d = readout(page, "hover", 3, i, j)
        assert float(d["x"]) == pytest.approx(xs[i], abs=1e-9), text
        assert float(d["y"]) == pytest.approx(ys[j], abs=1e-9), text
        assert f"cell {i}, {j}" in text, text
        if types[j, i] == 1:
            assert d["kind"] == "wall" and text.endswith("wall"), text
            continue
        assert abs(float(d["h"]) - h[3, j, i]) <= 0.5 * step + 1e-12, (text, h[3, j, i])
        shown_h = float(re.search(r"h = (\S+) m", text).group(1))
        assert abs(shown_h - h[3, j, i]) <= step, (text, h[3, j, i])
        assert (d["kind"] == "open") == (types[j, i] == 2) and \
            ("(open)" in text) == (types[j, i] == 2), text
    # a click pins the top cell; the pinned height follows the frames
    i, j = top
    move_to_cell(page, i, j, nx, ny, click=True)
    text, d = readout(page, "pinned", 3, i, j)
    assert text.startswith("pinned:") and abs(float(d["h"]) - h[3, j, i]) <= 0.5 * step + 1e-12
    move_to_cell(page, 0, 0, nx, ny)      # the mouse elsewhere
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.ARROW_LEFT)
    text, d = readout(page, "pinned", 2, i, j)
    assert abs(float(d["h"]) - h[2, j, i]) <= 0.5 * step + 1e-12, (text, h[2, j, i])
    assert h[2, j, i] != h[3, j, i], "test bug: the pinned cell should change"
    assert_no_js_errors(page)


def test_play_and_pause(page):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    page.execute_script("document.getElementById('fps').value = 20;")
    button = page.find_element(By.ID, "play")
    assert button.text == "Play"
    button.click()
    assert button.text == "Pause"
    wait(page, lambda: shown(page)[0] >= 2, "play to advance two frames", timeout=4)
    wait(page, lambda: shown(page)[0] == 4 and button.text == "Play",
         "play to stop at the last frame", timeout=4)
    # space plays (from the start again) and pauses
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.ARROW_LEFT, Keys.ARROW_LEFT,
                                                     Keys.ARROW_LEFT, Keys.ARROW_LEFT)
    assert shown(page)[0] == 0
    page.execute_script("document.getElementById('fps').value = 2;")
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.SPACE)
    assert button.text == "Pause"
    wait(page, lambda: shown(page)[0] >= 1, "space to play", timeout=4)
    page.find_element(By.TAG_NAME, "body").send_keys(Keys.SPACE)
    assert button.text == "Play"
    k = shown(page)[0]
    time.sleep(0.8)
    assert shown(page)[0] == k, "paused"
    # space with the focus on the button: one toggle, not two
    button.send_keys(Keys.SPACE)
    assert button.text == "Pause"
    button.send_keys(Keys.SPACE)
    assert button.text == "Play"
    assert_no_js_errors(page)


# ---- a DEM with cells without data ---------------------------------------------

def test_cells_without_data_read_no_data(browser, tmp_path):
    """A relaxed DEM with nodata round it: the readout over a nodata cell
    says "no data" (not "wall"), a cell with data its height, and the key
    names "no data"."""
    nx, ny = 14, 10
    y, x = np.mgrid[0:ny, 0:nx] + 0.5
    h = 2.0 + 0.05 * x + 0.02 * y
    nodata = np.hypot(x - 7, y - 5) > 4.5
    rows = [" ".join("-9999" if nodata[j, i] else repr(float(h[j, i])) for i in range(nx))
            for j in range(ny - 1, -1, -1)]
    (tmp_path / "dem.asc").write_text(
        f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\ncellsize 1\n"
        "NODATA_value -9999\n" + "\n".join(rows) + "\n")
    run_ok(["relax", "dem.asc", "-o", "dem.h5", "-q"], cwd=tmp_path)
    run_ok(["render", "dem.h5", "--html", "view.html", "-q"], cwd=tmp_path)
    browser.get_log("browser")
    browser.get((tmp_path / "view.html").as_uri())
    wait(browser, lambda: browser.execute_script(
        "const p = document.getElementById('pic'); return p.complete && p.naturalWidth > 0;"),
        "the frame to load")
    key = browser.execute_script(
        "const k = document.getElementById('nodatakey');"
        "return [k.parentNode.style.display, getComputedStyle(k).backgroundColor];")
    assert key[0] != "none" and key[1] == "rgb(255, 255, 255)", \
        f"the 'no data' key: {key} (shown, white like the cells without data)"
    with h5open(tmp_path / "dem.h5") as f:
        last = f["height"][-1]
    frame = len(browser.execute_script("return SS.times;")) - 1
    for i, j in [(0, 0), (7, 5)]:
        move_to_cell(browser, i, j, nx, ny)
        text, d = readout(browser, "hover", frame, i, j)
        if nodata[j, i]:
            assert d["kind"] == "nodata" and text.endswith("no data"), \
                f"cell ({i}, {j}) has no data: {text}"
        else:
            assert d["kind"] == "flow" and abs(float(d["h"]) - last[j, i]) < 1e-3, \
                (text, last[j, i])
    assert_no_js_errors(browser)
