/*
 * html.c - `sandslide render --html FILE.html`: the frames of a series in
 * one self-contained page that opens from a file:// URL (no server, no
 * network, no external script, font or style sheet), with a slider,
 * play/pause, a speed control, the time and frame number, the colour bar,
 * and the height and position under the mouse and at a pinned point.
 *
 * What the page holds, all inside the one file:
 *
 *   frames   each frame's PNG, the very bytes `render` writes to
 *            frame_NNNNN.png (same look options), base64 in a data: URI;
 *   heights  per frame, the data behind the picture: the cells when the
 *            picture has at least one pixel per cell (its pixels are then
 *            interpolated, the cells are the data), else the pixel heights
 *            the picture was coloured from (area means of cells, under
 *            --max-size).  Quantised to uint16:
 *                0       wall
 *                1       no data (a cell without data, or a height that
 *                        is not a number)
 *                v >= 2  height qlo + (v - 2) * step,
 *                        step = (qhi - qlo) / 65533,
 *            [qlo, qhi] the height scale widened to the heights of the
 *            chosen snapshots, so that heights outside --zmin/--zmax read
 *            back too.  A height read back is within step / 2 of the
 *            file's (the door case: 0.8 m / 65533 = 12 um steps).  Each
 *            frame's array (little-endian, rows north first) is deflated
 *            with zlib and base64; the page inflates a frame's when it
 *            first needs it, with the browser's DecompressionStream
 *            (checked from file:// in Chromium 156 and Firefox 153 ESR;
 *            it needs no network);
 *   types    the cell (or pixel) types once, the same way: 0 flow, 1 wall,
 *            2 open, 3 no data (a DEM's nodata, drawn as background);
 *   scale    the colour map's 256 colours (ss_render_cmap_table), zmin and
 *            zmax, so the page's colour bar is the frames' exactly.
 *
 * The page opens on the last frame: what a run made, where the first is
 * often an empty room (a pouring case) or the very start of a slide; Home
 * and the slider go back, and play starts again from the first frame.
 *
 * The oblique style has no map from the picture to the cells: its page has
 * the frames and the controls but no height readout.
 *
 * The page is built in memory and written as FILE.html.partial, renamed
 * when complete (ss_render_write_file); an existing FILE.html is refused
 * unless --force says to replace it.  The template is plain C strings
 * below, one line each: CSS, markup and script, with no framework.
 */
#include "internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zlib.h>

#include "base/strings.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"

/* Codes of the quantised heights below the first height. */
enum { CODE_WALL = 0, CODE_NODATA = 1, CODE_FIRST = 2, CODE_STEPS = 65535 - CODE_FIRST };

struct html_frame {
	unsigned char *png;         /* the frame's PNG bytes */
	size_t png_size;
	unsigned char *heights;     /* deflated uint16 codes, NULL for oblique */
	size_t heights_size;
	double time;                /* s */
	long long snapshot;
};

struct ss_render_html {
	const struct ss_render_plan *plan;
	struct ss_render_source *source;
	int cells;                  /* the data are the cells (else the pixels) */
	int any_nodata;             /* some data cell has no data: a key for it */
	int gw, gh;                 /* the data grid (0 x 0: no readout) */
	double gdx, gdy;            /* m per data cell */
	double qlo, qhi;            /* m, the quantisation's range */
	unsigned char *types;       /* deflated data-cell types */
	size_t types_size;
	long long n;
	struct html_frame *frame;   /* n */
};

/* ---- the page, written into memory ------------------------------------ */

struct page {
	char *data;
	size_t len, cap;
	int failed;                 /* out of memory: the rest is dropped */
};

static void put_bytes(struct page *p, const char *s, size_t n)
{
	if (p->failed)
		return;
	if (n > p->cap - p->len) {
		size_t cap = p->cap ? p->cap : 1 << 20;
		while (cap - p->len < n) {
			if (cap > SIZE_MAX / 2) {
				p->failed = 1;
				return;
			}
			cap *= 2;
		}
		char *more = realloc(p->data, cap);
		if (!more) {
			p->failed = 1;
			return;
		}
		p->data = more;
		p->cap = cap;
	}
	memcpy(p->data + p->len, s, n);
	p->len += n;
}

static void put(struct page *p, const char *s)
{
	put_bytes(p, s, strlen(s));
}

static void putf(struct page *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void putf(struct page *p, const char *fmt, ...)
{
	char buf[512];
	va_list ap;
	va_start(ap, fmt);
	const int n = vsnprintf(buf, sizeof buf, fmt, ap);
	va_end(ap);
	if (n < 0 || (size_t)n >= sizeof buf)
		SS_BUG("putf: '%s' needs %d bytes", fmt, n);
	put_bytes(p, buf, (size_t)n);
}

/* Lines of the template, each followed by a newline. */
static void put_lines(struct page *p, const char *const *lines)
{
	for (; *lines; lines++) {
		put(p, *lines);
		put_bytes(p, "\n", 1);
	}
}

static void put_base64(struct page *p, const unsigned char *b, size_t n)
{
	static const char digits[] =
		"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
	char quad[4 * 1024];
	size_t q = 0;
	for (size_t k = 0; k < n; k += 3) {
		const unsigned v = (unsigned)b[k] << 16 | (k + 1 < n ? (unsigned)b[k + 1] << 8 : 0) |
		                   (k + 2 < n ? b[k + 2] : 0);
		quad[q++] = digits[v >> 18 & 63];
		quad[q++] = digits[v >> 12 & 63];
		quad[q++] = k + 1 < n ? digits[v >> 6 & 63] : '=';
		quad[q++] = k + 2 < n ? digits[v & 63] : '=';
		if (q == sizeof quad) {
			put_bytes(p, quad, q);
			q = 0;
		}
	}
	put_bytes(p, quad, q);
}

/* s as a JavaScript string literal that is also safe inside <script>:
 * quotes, backslashes, control characters and <, >, & escaped. */
static void put_js_string(struct page *p, const char *s)
{
	put_bytes(p, "\"", 1);
	for (; *s; s++) {
		const unsigned char c = (unsigned char)*s;
		if (c < 0x20 || c == '"' || c == '\\' || c == '<' || c == '>' || c == '&')
			putf(p, "\\u%04x", c);
		else
			put_bytes(p, s, 1);
	}
	put_bytes(p, "\"", 1);
}

/* A number that reads back exactly (the shortest such text); null when it
 * is not finite. */
static void put_number(struct page *p, double x)
{
	if (isfinite(x))
		putf(p, "%s", SS_REAL(x));
	else
		put(p, "null");
}

/* ---- the template ------------------------------------------------------ */

static const char *const page_head[] = {
	"<!DOCTYPE html>",
	"<html lang='en'>",
	"<head>",
	"<meta charset='utf-8'>",
	"<meta name='viewport' content='width=device-width, initial-scale=1'>",
	"<title>sandslide viewer</title>",
	"<style>",
	"body { margin: 16px 20px; background: #f4f4f1; color: #222;",
	"       font: 14px/1.4 system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif; }",
	"h1 { font-size: 17px; font-weight: 600; margin: 0; }",
	"#sub { color: #666; font-size: 12.5px; margin: 2px 0 12px; }",
	"#stage { display: flex; align-items: flex-start; gap: 14px; }",
	"#main { flex: none; max-width: calc(100vw - 150px); }",
	"#view { position: relative; width: fit-content; line-height: 0; cursor: crosshair;",
	"        background: #fff;",
	"        box-shadow: 0 0 0 1px #c8c8c0, 0 1px 4px rgba(0, 0, 0, 0.12); }",
	"#pic { display: block; max-width: 100%; height: auto; user-select: none; }",
	"#pic.pixelated { image-rendering: pixelated; }",
	"#pin { position: absolute; display: none; width: 9px; height: 9px; margin: -7px 0 0 -7px;",
	"       border: 2px solid #fff; border-radius: 50%; pointer-events: none;",
	"       box-shadow: 0 0 0 1.5px #d00, inset 0 0 0 1.5px #d00; }",
	"#transport { display: flex; align-items: center; gap: 10px; margin-top: 10px; }",
	"#slider { flex: auto; min-width: 0; margin: 0; }",
	"#controls { display: flex; align-items: baseline; gap: 4px 14px; flex-wrap: wrap;",
	"            margin-top: 6px; }",
	"#play { flex: none; min-width: 5.2em; font: inherit; padding: 2px 10px; }",
	"#time { font-weight: 600; min-width: 6.5em; }",
	"#time, #frame, #readout { font-variant-numeric: tabular-nums; }",
	"#frame { color: #555; }",
	"#speed { margin-left: auto; color: #555; }",
	"#fps { width: 4.2em; font: inherit; }",
	"#side { flex: none; font-size: 12.5px; color: #333; }",
	"#side .unit { font-weight: 600; margin-bottom: 2px; }",
	"#bar { display: block; }",
	".key { display: flex; align-items: center; gap: 6px; margin-top: 4px; }",
	".swatch { width: 14px; height: 10px; box-shadow: 0 0 0 1px #888; }",
	"#readout { margin-top: 10px; padding: 6px 9px; background: #fff; border-radius: 3px;",
	"           box-shadow: 0 0 0 1px #ddd; min-height: 2.8em; }",
	"#pinned { color: #b00; }",
	"#help { color: #777; font-size: 12px; margin-top: 8px; }",
	"kbd { font: 11px/1 ui-monospace, monospace; padding: 1px 4px; border: 1px solid #bbb;",
	"      border-radius: 3px; background: #fff; }",
	"</style>",
	"</head>",
	"<body>",
	"<h1 id='title'>sandslide</h1>",
	"<div id='sub'></div>",
	"<div id='stage'>",
	"<div id='main'>",
	"<div id='view'><img id='pic' alt='frame' draggable='false'><div id='pin'></div></div>",
	"<div id='transport'>",
	"<button id='play' type='button'>Play</button>",
	"<input id='slider' type='range' min='0' max='0' step='1' value='0' aria-label='frame'>",
	"</div>",
	"<div id='controls'>",
	"<span id='time'></span>",
	"<span id='frame'></span>",
	"<label id='speed'>speed <input id='fps' type='number' min='1' max='240' step='1'>"
	" frames/s</label>",
	"</div>",
	"<div id='readout'><div id='hover'></div><div id='pinned'></div></div>",
	"<div id='help'><kbd>&larr;</kbd> <kbd>&rarr;</kbd> step &middot; <kbd>space</kbd>"
	" play/pause &middot; click pins a point, <kbd>Esc</kbd> unpins</div>",
	"</div>",
	"<div id='side'>",
	"<div class='unit'>height, m</div>",
	"<canvas id='bar' width='80' height='300' aria-label='height scale'></canvas>",
	"<div class='key'><span class='swatch' id='wallkey'></span>wall</div>",
	"<div class='key'><span class='swatch' id='openkey'></span>open</div>",
	"<div class='key'><span class='swatch' id='nodatakey'></span>no data</div>",
	"</div>",
	"</div>",
	NULL,
};

/* After the data (SS, FRAMES, HEIGHTS): what the page does. */
static const char *const page_script[] = {
	"<script>",
	"'use strict';",
	"(function () {",
	"const S = SS, n = FRAMES.length;",
	"const $ = id => document.getElementById(id);",
	"const pic = $('pic'), slider = $('slider'), playButton = $('play'), fpsInput = $('fps');",
	"const timeText = $('time'), frameText = $('frame'), hoverText = $('hover');",
	"const pinnedText = $('pinned'), pinMark = $('pin');",
	"const step = (S.qhi - S.qlo) / 65533;   // m per quantisation level (see html.c)",
	"const readable = S.gw > 0 && typeof DecompressionStream === 'function';",
	"const xyDigits =",
	"  Math.max(0, Math.min(8, Math.ceil(-Math.log10(Math.min(S.gdx, S.gdy))) + 2));",
	"const hDigits = Math.max(0, Math.min(6, Math.ceil(-Math.log10(step))));",
	"let current = 0, timer = null, hover = null, pinned = null;",
	"",
	"// ---- the embedded heights: base64 of zlib-deflated uint16, inflated on demand",
	"function bytes(base64) {",
	"  const s = atob(base64), b = new Uint8Array(s.length);",
	"  for (let i = 0; i < s.length; i++) b[i] = s.charCodeAt(i);",
	"  return b;",
	"}",
	"async function inflate(base64) {",
	"  const stream = new Blob([bytes(base64)]).stream()",
	"    .pipeThrough(new DecompressionStream('deflate'));",
	"  return new Uint8Array(await new Response(stream).arrayBuffer());",
	"}",
	"const types = readable ? inflate(S.types) : null;   // 0 flow, 1 wall, 2 open, 3 no data",
	"const cache = new Map();",
	"function heights(k) {",
	"  let p = cache.get(k);",
	"  if (!p) {",
	"    p = inflate(HEIGHTS[k]).then(b => {",
	"      const v = new DataView(b.buffer, b.byteOffset, b.byteLength);",
	"      const a = new Uint16Array(b.length >> 1);",
	"      for (let i = 0; i < a.length; i++) a[i] = v.getUint16(2 * i, true);",
	"      return a;",
	"    });",
	"    cache.set(k, p);",
	"    if (cache.size > 16) cache.delete(cache.keys().next().value);",
	"  }",
	"  return p;",
	"}",
	"",
	"// ---- the frame shown",
	"function timeLabel(t) { return String(Number(t.toPrecision(6))); }",
	"function show(k) {",
	"  current = Math.max(0, Math.min(n - 1, k));",
	"  pic.src = FRAMES[current];",
	"  slider.value = current;",
	"  timeText.textContent = 't = ' + timeLabel(S.times[current]) + ' s';",
	"  frameText.textContent = 'frame ' + (current + 1) + ' / ' + n +",
	"    ' \\u00b7 snapshot ' + S.snapshots[current];",
	"  if (hover) readout(hoverText, hover);",
	"  if (pinned) readout(pinnedText, pinned);",
	"}",
	"function fps() {",
	"  const f = Number(fpsInput.value);",
	"  return f >= 1 && f <= 240 ? f : S.fps;",
	"}",
	"function tick() {",
	"  timer = null;",
	"  if (current + 1 >= n) { stop(); return; }",
	"  show(current + 1);",
	"  timer = setTimeout(tick, 1000 / fps());",
	"}",
	"function play() {",
	"  if (timer || n < 2) return;",
	"  if (current + 1 >= n) show(0);",
	"  playButton.textContent = 'Pause';",
	"  timer = setTimeout(tick, 1000 / fps());",
	"}",
	"function stop() {",
	"  clearTimeout(timer);",
	"  timer = null;",
	"  playButton.textContent = 'Play';",
	"}",
	"function toggle() { if (timer) stop(); else play(); }",
	"",
	"// ---- height and position under the mouse or at the pinned point",
	"function locate(e) {",
	"  const r = pic.getBoundingClientRect();",
	"  const fx = ((e.clientX - r.left) / r.width * S.imageW - S.mapX) / S.mapW;",
	"  const fy = ((e.clientY - r.top) / r.height * S.imageH - S.mapY) / S.mapH;",
	"  if (!(fx >= 0 && fx < 1 && fy >= 0 && fy < 1) || !(S.gw > 0)) return null;",
	"  const col = Math.min(S.gw - 1, Math.floor(fx * S.gw));",
	"  const row = Math.min(S.gh - 1, Math.floor(fy * S.gh));",
	"  return {col: col, row: row};",
	"}",
	"function readout(el, at) {",
	"  const k = current, i = at.col, j = S.gh - 1 - at.row;",
	"  const x = S.x0 + (i + 0.5) * S.gdx, y = S.y0 + (j + 0.5) * S.gdy;",
	"  const what = el === hoverText ? 'mouse' : 'pinned';",
	"  const where = what + ': x = ' + x.toFixed(xyDigits) + ' m, y = ' + y.toFixed(xyDigits) +",
	"    ' m (' + (S.cells ? 'cell ' + i + ', ' + j : 'pixel ' + i + ', ' + j +",
	"    ', a mean of its cells') + ')';",
	"  if (!readable) {",
	"    el.textContent = where + ' \\u00b7 height: this browser cannot inflate the ' +",
	"      'embedded heights (it lacks DecompressionStream)';",
	"    return;",
	"  }",
	"  Promise.all([heights(k), types]).then(([a, type_of]) => {",
	"    if (k !== current || (el === hoverText ? hover : pinned) !== at) return;",
	"    const v = a[at.row * S.gw + at.col], type = type_of[at.row * S.gw + at.col];",
	"    let text, kind, h = '';",
	"    if (v === 0) { text = 'wall'; kind = 'wall'; }",
	"    else if (v === 1) { text = 'no data'; kind = 'nodata'; }",
	"    else {",
	"      h = S.qlo + (v - 2) * step;",
	"      kind = type === 2 ? 'open' : 'flow';",
	"      text = 'h = ' + h.toFixed(hDigits) + ' m' + (type === 2 ? ' (open)' : '');",
	"    }",
	"    el.textContent = where + ' \\u00b7 ' + text;",
	"    Object.assign(el.dataset, {frame: k, i: i, j: j, x: x, y: y, h: h, kind: kind});",
	"  }).catch(err => { el.textContent = where + ' \\u00b7 height unreadable: ' + err; });",
	"}",
	"function pinAt(at) {",
	"  pinned = at;",
	"  if (!at) {",
	"    pinMark.style.display = 'none';",
	"    pinnedText.textContent = '';",
	"    pinnedText.removeAttribute('data-frame');",
	"    return;",
	"  }",
	"  pinMark.style.left = (S.mapX + (at.col + 0.5) / S.gw * S.mapW) / S.imageW * 100 + '%';",
	"  pinMark.style.top = (S.mapY + (at.row + 0.5) / S.gh * S.mapH) / S.imageH * 100 + '%';",
	"  pinMark.style.display = 'block';",
	"  readout(pinnedText, at);",
	"}",
	"",
	"// ---- the colour bar, from the colour map's own table",
	"function drawBar() {",
	"  const c = $('bar'), dpr = window.devicePixelRatio || 1;",
	"  const w = 80, h = Math.max(140, Math.round(pic.getBoundingClientRect().height) - 44);",
	"  c.style.width = w + 'px';",
	"  c.style.height = h + 'px';",
	"  c.width = Math.round(w * dpr);",
	"  c.height = Math.round(h * dpr);",
	"  const g = c.getContext('2d');",
	"  g.scale(dpr, dpr);",
	"  const top = 7, bottom = h - 7, x = 1, bw = 18, span = bottom - top;",
	"  // colour k is that of heights within half a step of zmin + k / 255 (zmax - zmin)",
	"  for (let k = 0; k < 256; k++) {",
	"    g.fillStyle = '#' + S.cmap.substr(6 * k, 6);",
	"    const lo = Math.max(0, (k - 0.5) / 255), hi = Math.min(1, (k + 0.5) / 255);",
	"    const y0 = Math.floor(bottom - span * hi), y1 = Math.ceil(bottom - span * lo);",
	"    g.fillRect(x, y0, bw, y1 - y0);",
	"  }",
	"  g.strokeStyle = '#666';",
	"  g.lineWidth = 1;",
	"  g.strokeRect(x + 0.5, top + 0.5, bw - 1, span - 1);",
	"  const range = S.zmax - S.zmin, raw = range / 5;",
	"  const mag = Math.pow(10, Math.floor(Math.log10(raw)));",
	"  const tick = [1, 2, 2.5, 5, 10].map(m => m * mag).find(s => s >= raw);",
	"  const digits = Math.max(0, -Math.floor(Math.log10(tick) + 1e-9) + (tick / mag === 2.5));",
	"  g.fillStyle = '#222';",
	"  g.font = '12px system-ui, -apple-system, sans-serif';",
	"  g.textBaseline = 'middle';",
	"  const mark = (v, text) => {",
	"    const y = Math.round(bottom - (v - S.zmin) / range * span) + 0.5;",
	"    g.beginPath();",
	"    g.moveTo(x + bw, y);",
	"    g.lineTo(x + bw + 4, y);",
	"    g.stroke();",
	"    g.fillText(text, x + bw + 8, Math.min(bottom - 5, Math.max(top + 5, y)));",
	"  };",
	"  // both ends, one digit finer than the ticks unless on one; the ticks",
	"  // between that leave room for their labels",
	"  const onTick = v => Math.abs(v / tick - Math.round(v / tick)) < 1e-9;",
	"  for (const v of [S.zmin, S.zmax])",
	"    mark(v, (Math.abs(v) < tick / 20 ? 0 : v).toFixed(digits + (onTick(v) ? 0 : 1)));",
	"  for (let v = Math.ceil(S.zmin / tick - 1e-9) * tick; v <= S.zmax + 1e-9 * range;",
	"       v += tick) {",
	"    const gap = Math.min(v - S.zmin, S.zmax - v) / range * span;",
	"    if (gap >= 14)",
	"      mark(v, (Math.abs(v) < tick / 2 ? 0 : v).toFixed(digits));",
	"  }",
	"}",
	"",
	"// ---- set-up",
	"document.title = S.name + ' \\u2014 sandslide viewer';",
	"$('title').textContent = S.name;",
	"$('sub').textContent = S.nx + ' \\u00d7 ' + S.ny + ' cells of ' + S.dx +",
	"  (S.dy === S.dx ? '' : ' \\u00d7 ' + S.dy) + ' m \\u00b7 ' +",
	"  n + ' frame' + (n === 1 ? '' : 's') + ', t = ' + timeLabel(S.times[0]) + ' \\u2026 ' +",
	"  timeLabel(S.times[n - 1]) + ' s \\u00b7 heights ' + Number(S.zmin.toPrecision(4)) +",
	"  ' \\u2026 ' + Number(S.zmax.toPrecision(4)) + ' m \\u00b7 ' + S.style +",
	"  (S.style === 'gray16' ? '' : ', ' + S.cmapName);",
	"$('wallkey').style.background = S.wall;",
	"if (S.open) $('openkey').style.background = S.open;",
	"else $('openkey').parentNode.style.display = 'none';",
	"if (S.absent) $('nodatakey').style.background = S.absent;",
	"else $('nodatakey').parentNode.style.display = 'none';",
	"const zoom = Math.max(S.imageW, S.imageH) < 400 ?",
	"  Math.ceil(400 / Math.max(S.imageW, S.imageH)) : 1;",
	"pic.width = S.imageW * zoom;",
	"pic.height = S.imageH * zoom;",
	"$('main').style.width = Math.max(pic.width, 420) + 'px';",
	"if (zoom > 1) pic.classList.add('pixelated');",
	"slider.max = n - 1;",
	"fpsInput.value = S.fps;",
	"hoverText.textContent = S.gw > 0 ?",
	"  'Move the mouse over the picture for the height and position; click to pin a point.' :",
	"  'No height readout for the ' + S.style + ' view: render with --style shaded for one.';",
	"slider.addEventListener('input', () => { stop(); show(Number(slider.value)); });",
	"playButton.addEventListener('click', toggle);",
	"fpsInput.addEventListener('change', () => { if (timer) { stop(); play(); } });",
	"pic.addEventListener('mousemove', e => {",
	"  const at = locate(e);",
	"  if (at && hover && at.col === hover.col && at.row === hover.row) return;",
	"  hover = at;",
	"  if (at) readout(hoverText, at);",
	"});",
	"pic.addEventListener('mouseleave', () => { hover = null; });",
	"pic.addEventListener('click', e => pinAt(locate(e)));",
	"document.addEventListener('keydown', e => {",
	"  if (e.target === fpsInput || e.altKey || e.ctrlKey || e.metaKey) return;",
	"  if (e.key === 'ArrowLeft' || e.key === 'ArrowRight') {",
	"    e.preventDefault();",
	"    stop();",
	"    show(current + (e.key === 'ArrowRight' ? 1 : -1));",
	"  } else if (e.key === 'Home' || e.key === 'End') {",
	"    e.preventDefault();",
	"    stop();",
	"    show(e.key === 'Home' ? 0 : n - 1);",
	"  } else if (e.key === ' ') {",
	"    e.preventDefault();",
	"    toggle();",
	"  } else if (e.key === 'Escape') {",
	"    pinAt(null);",
	"  }",
	"});",
	"window.addEventListener('resize', drawBar);",
	"pic.addEventListener('load', drawBar, {once: true});",
	"show(n - 1);   // the end: what the run made (a pouring case starts empty)",
	"drawBar();",
	"})();",
	"</script>",
	"</body>",
	"</html>",
	NULL,
};

/* ---- building it --------------------------------------------------------- */

int ss_render_html_check_path(const char *path, int force)
{
	struct stat sb;
	char parent[4096];
	const char *slash = strrchr(path, '/');
	if (!*path)
		return ss_error_input("--html needs a file name, e.g. view.html");
	if (!slash)
		snprintf(parent, sizeof parent, ".");
	else
		snprintf(parent, sizeof parent, "%.*s", (int)(slash - path) + (slash == path), path);
	if (slash && !slash[1])
		return ss_error_input("cannot write the viewer '%s': expected a file name, e.g. "
		                      "%sview.html", path, path);
	if (stat(parent, &sb) != 0 || !S_ISDIR(sb.st_mode))
		return ss_error_input("cannot write the viewer '%s': folder '%s' does not exist", path,
		                      parent);
	if (access(parent, W_OK | X_OK) != 0)
		return ss_error_input("cannot write the viewer '%s': folder '%s' is not writable",
		                      path, parent);
	if (stat(path, &sb) == 0) {
		if (S_ISDIR(sb.st_mode))
			return ss_error_input("cannot write the viewer '%s': it is a folder", path);
		if (!force)
			return ss_error_input("the viewer '%s' exists: give --force to replace it", path);
	}
	return SS_OK;
}

/* Deflate n bytes with zlib (its own format, as the page's
 * DecompressionStream('deflate') reads it). */
static int deflate_bytes(const unsigned char *b, size_t n, unsigned char **out, size_t *size)
{
	uLongf cap = compressBound((uLong)n);
	if ((size_t)(uLong)n != n)
		return ss_error_fail("cannot compress %zu bytes of heights at once", n);
	*out = malloc(cap);
	if (!*out)
		return ss_error_fail("out of memory compressing the viewer's heights");
	const int z = compress2(*out, &cap, b, (uLong)n, Z_BEST_COMPRESSION);
	if (z != Z_OK) {
		free(*out);
		*out = NULL;
		return ss_error_fail("cannot compress the viewer's heights: zlib error %d", z);
	}
	*size = cap;
	return SS_OK;
}

/* The data grid's cell types, north row first, deflated. */
static int make_types(struct ss_render_html *h)
{
	const struct ss_render_plan *p = h->plan;
	const size_t count = (size_t)h->gw * (size_t)h->gh;
	unsigned char *t = malloc(count ? count : 1);
	if (!t)
		return ss_error_fail("out of memory");
	for (int row = 0; row < h->gh; row++)
		for (int col = 0; col < h->gw; col++) {
			const size_t k = (size_t)row * h->gw + col;
			t[k] = h->cells ? h->source->cell_type[(size_t)(h->gh - 1 - row) * h->gw + col]
			                : p->pixel_type[k];
			h->any_nodata |= t[k] == SS_RENDER_CELL_NODATA;
		}
	const int err = deflate_bytes(t, count, &h->types, &h->types_size);
	free(t);
	return err;
}

int ss_render_html_create(struct ss_render_html **out, const struct ss_render_plan *p,
                          struct ss_render_source *s, const long long *sel, long long n,
                          int scale_given)
{
	*out = NULL;
	struct ss_render_html *h = calloc(1, sizeof *h);
	if (!h)
		return ss_error_fail("out of memory");
	h->plan = p;
	h->source = s;
	h->n = n;
	h->qlo = p->zmin;
	h->qhi = p->zmax;
	if (p->look.style != SS_RENDER_OBLIQUE) {
		h->cells = p->rs.width >= s->file.nx && p->rs.height >= s->file.ny;
		h->gw = h->cells ? s->file.nx : p->rs.width;
		h->gh = h->cells ? s->file.ny : p->rs.height;
		h->gdx = h->cells ? s->file.dx : p->rs.px_dx;
		h->gdy = h->cells ? s->file.dy : p->rs.px_dy;
	}
	int err = SS_OK;
	h->frame = calloc((size_t)n, sizeof *h->frame);
	if (!h->frame)
		err = ss_error_fail("out of memory");
	if (!err && h->gw > 0 && scale_given) {
		/* heights beyond --zmin/--zmax must read back too */
		long long first = sel[0], last = sel[0];
		for (long long k = 1; k < n; k++) {
			first = sel[k] < first ? sel[k] : first;
			last = sel[k] > last ? sel[k] : last;
		}
		double lo, hi;
		if (!(err = ss_render_source_range(s, first, last, &lo, &hi))) {
			h->qlo = fmin(h->qlo, lo);
			h->qhi = fmax(h->qhi, hi);
		}
	}
	if (!err && h->gw > 0)
		err = make_types(h);
	if (err) {
		ss_render_html_destroy(h);
		return err;
	}
	*out = h;
	return SS_OK;
}

int ss_render_html_wants_pixels(const struct ss_render_html *h)
{
	return h->gw > 0 && !h->cells;
}

/* The quantised codes (little-endian uint16) of the data grid of snapshot
 * t: the cells read from the file, or pixel_h. */
static int quantise(struct ss_render_html *h, long long t, const double *pixel_h,
                    unsigned char *codes)
{
	const size_t count = (size_t)h->gw * (size_t)h->gh;
	const double step = (h->qhi - h->qlo) / CODE_STEPS;
	double *cells = NULL;
	const double *v = pixel_h;
	if (h->cells) {
		struct ss_snapshot_file *f = &h->source->file;
		cells = ss_alloc(count, sizeof *cells, "the viewer's heights");
		if (!cells)
			return SS_ERR_FAIL;
		const int block = ss_snapshot_file_block_rows(f);
		for (int j0 = 0; j0 < f->ny; j0 += block) {
			const int rows = f->ny - j0 < block ? f->ny - j0 : block;
			const int err = ss_snapshot_file_read_rows(f, t, j0, rows,
			                                           cells + (size_t)j0 * f->nx);
			if (err) {
				ss_free(cells);
				return err;
			}
		}
		v = cells;
	}
	for (int row = 0; row < h->gh; row++)
		for (int col = 0; col < h->gw; col++) {
			const size_t k = (size_t)row * h->gw + col;
			/* cells are stored south row first, the page's rows north first */
			const size_t src = h->cells ? (size_t)(h->gh - 1 - row) * h->gw + col : k;
			const uint8_t type = h->cells ? h->source->cell_type[src]
			                               : h->plan->pixel_type[k];
			const double z = v[src];
			unsigned code;
			if (type == SS_CELL_WALL)
				code = CODE_WALL;
			else if (type == SS_RENDER_CELL_NODATA || !isfinite(z))
				code = CODE_NODATA;
			else {
				const double q = round((z - h->qlo) / step);
				code = CODE_FIRST + (unsigned)(q < 0 ? 0 : q > CODE_STEPS ? CODE_STEPS : q);
			}
			codes[2 * k] = (unsigned char)(code & 0xff);
			codes[2 * k + 1] = (unsigned char)(code >> 8);
		}
	ss_free(cells);
	return SS_OK;
}

int ss_render_html_add(struct ss_render_html *h, long long k, long long t, unsigned char *png,
                       size_t png_size, const double *pixel_h)
{
	struct html_frame *f = &h->frame[k];
	f->png = png;
	f->png_size = png_size;
	f->time = h->source->file.time[t];
	f->snapshot = t;
	if (h->gw == 0)
		return SS_OK;
	const size_t count = (size_t)h->gw * (size_t)h->gh;
	unsigned char *codes = malloc(2 * count);
	if (!codes)
		return ss_error_fail("out of memory");
	int err = quantise(h, t, pixel_h, codes);
	if (!err)
		err = deflate_bytes(codes, 2 * count, &f->heights, &f->heights_size);
	free(codes);
	return err;
}

static void put_color(struct page *pg, const char *key, int r, int g, int b)
{
	putf(pg, "  %s: '#%02x%02x%02x',\n", key, r, g, b);
}

/* The data: SS (what the page shows besides the frames), FRAMES, HEIGHTS. */
static void put_data(struct page *pg, const struct ss_render_html *h, const char *name, int fps)
{
	const struct ss_render_plan *p = h->plan;
	const struct ss_snapshot_file *f = &h->source->file;
	const enum ss_render_cmap cmap =
		p->look.style == SS_RENDER_GRAY16 ? SS_RENDER_CMAP_GRAY : p->look.cmap;
	uint8_t table[256][3];
	ss_render_cmap_table(cmap, table);

	put(pg, "<script>\n'use strict';\nconst SS = {\n  name: ");
	put_js_string(pg, name);
	putf(pg, ",\n  style: '%s', cmapName: '%s', fps: %d,\n",
	     ss_render_style_name(p->look.style), ss_render_cmap_name(cmap), fps);
	putf(pg, "  nx: %d, ny: %d, dx: ", f->nx, f->ny);
	put_number(pg, f->dx);
	put(pg, ", dy: ");
	put_number(pg, f->dy);
	/* the frame: the label strip, the wall sides, the map, the colour bar */
	putf(pg, ",\n  imageW: %d, imageH: %d, mapX: %d, mapY: %d, mapW: %d, mapH: %d,\n",
	     p->image_w, p->image_h, p->border[SS_WEST], p->label_h + p->border[SS_NORTH],
	     p->rs.width, p->rs.height);
	putf(pg, "  // the data grid: %s, rows north first\n",
	     h->gw == 0 ? "none (oblique)" : h->cells ? "the cells" : "the picture's pixels");
	putf(pg, "  cells: %s, gw: %d, gh: %d, gdx: ", h->cells ? "true" : "false", h->gw, h->gh);
	put_number(pg, h->gdx);
	put(pg, ", gdy: ");
	put_number(pg, h->gdy);
	put(pg, ",\n  x0: ");   /* the lower-left corner */
	put_number(pg, isfinite(f->origin_x) ? f->origin_x : 0.0);
	put(pg, ", y0: ");
	put_number(pg, isfinite(f->origin_y) ? f->origin_y : 0.0);
	put(pg, ",\n  zmin: ");
	put_number(pg, p->zmin);
	put(pg, ", zmax: ");
	put_number(pg, p->zmax);
	put(pg, ",\n  // heights: code 0 wall, 1 no data, v >= 2: qlo + (v - 2) * (qhi - qlo) / 65533\n"
	        "  qlo: ");
	put_number(pg, h->qlo);
	put(pg, ", qhi: ");
	put_number(pg, h->qhi);
	put(pg, ",\n");
	if (p->look.style == SS_RENDER_GRAY16) {   /* walls transparent, open cells grey */
		put(pg, "  wall: 'transparent', open: null,\n");
		put(pg, h->any_nodata ? "  absent: 'transparent',\n" : "  absent: null,\n");
	} else {
		put_color(pg, "wall", SS_RENDER_WALL_RGB);
		put_color(pg, "open", SS_RENDER_OPEN_RGB);
		if (h->any_nodata)
			put_color(pg, "absent", SS_RENDER_BACKGROUND, SS_RENDER_BACKGROUND,
			          SS_RENDER_BACKGROUND);   /* the key of cells without data */
		else
			put(pg, "  absent: null,\n");
	}
	put(pg, "  cmap: '");
	for (int k = 0; k < 256; k++)
		putf(pg, "%02x%02x%02x", table[k][0], table[k][1], table[k][2]);
	put(pg, "',\n  types: '");
	put_base64(pg, h->types, h->types_size);
	put(pg, "',\n  times: [");
	for (long long k = 0; k < h->n; k++) {
		put(pg, k ? ", " : "");
		put_number(pg, h->frame[k].time);
	}
	put(pg, "],\n  snapshots: [");
	for (long long k = 0; k < h->n; k++)
		putf(pg, "%s%lld", k ? ", " : "", h->frame[k].snapshot);
	put(pg, "],\n};\nconst FRAMES = [\n");
	for (long long k = 0; k < h->n; k++) {
		put(pg, "'data:image/png;base64,");
		put_base64(pg, h->frame[k].png, h->frame[k].png_size);
		put(pg, "',\n");
	}
	put(pg, "];\nconst HEIGHTS = [\n");
	for (long long k = 0; k < h->n; k++) {
		put(pg, "'");
		put_base64(pg, h->frame[k].heights, h->frame[k].heights_size);
		put(pg, "',\n");
	}
	put(pg, "];\n</script>\n");
}

int ss_render_html_write(struct ss_render_html *h, const char *path, int fps, size_t *bytes)
{
	const char *input = h->source->file.name, *slash = strrchr(input, '/');
	struct page pg = {0};
	put_lines(&pg, page_head);
	put_data(&pg, h, slash ? slash + 1 : input, fps);
	put_lines(&pg, page_script);
	int err;
	if (pg.failed)
		err = ss_error_fail("out of memory building the viewer '%s' (%zu bytes so far)", path,
		                    pg.len);
	else
		err = ss_render_write_file(path, pg.data, pg.len);
	*bytes = err ? 0 : pg.len;
	free(pg.data);
	return err;
}

void ss_render_html_destroy(struct ss_render_html *h)
{
	if (!h)
		return;
	for (long long k = 0; h->frame && k < h->n; k++) {
		free(h->frame[k].png);
		free(h->frame[k].heights);
	}
	free(h->frame);
	free(h->types);
	free(h);
}
