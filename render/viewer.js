// SPDX-License-Identifier: BSD-3-Clause
// viewer.js - what the page of `sandslide render --html` does (html.c):
// the slider, play/pause and speed, the frame's time, the colour bar,
// and the height and position under the mouse and at a pinned point.
//
// html.c writes this file into the page as it is, in a <script> after
// the one that holds the data: SS (the series: sizes, geometry, the
// colour map, the quantisation of the heights, the cell types, the times
// and snapshots), FRAMES (each frame's PNG as a data: URI) and HEIGHTS
// (each frame's quantised heights, deflated, base64).  The Makefile
// embeds it at build time ($(BUILD)/gen/render/viewer_js.h), leaving out
// this header: the comment lines up to the first empty line and that
// line.  Plain JavaScript, no framework, nothing fetched: the page opens
// from a file:// URL.

'use strict';
(function () {
const S = SS, n = FRAMES.length;
const $ = id => document.getElementById(id);
const pic = $('pic'), slider = $('slider'), playButton = $('play'), fpsInput = $('fps');
const timeText = $('time'), frameText = $('frame'), hoverText = $('hover');
const pinnedText = $('pinned'), pinMark = $('pin');
const step = (S.qhi - S.qlo) / 65533;   // m per quantisation level (see html.c)
const readable = S.gw > 0 && typeof DecompressionStream === 'function';
const xyDigits =
  Math.max(0, Math.min(8, Math.ceil(-Math.log10(Math.min(S.gdx, S.gdy))) + 2));
const hDigits = Math.max(0, Math.min(6, Math.ceil(-Math.log10(step))));
let current = 0, timer = null, hover = null, pinned = null;

// ---- the embedded heights: base64 of zlib-deflated uint16, inflated on demand
function bytes(base64) {
  const s = atob(base64), b = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) b[i] = s.charCodeAt(i);
  return b;
}
async function inflate(base64) {
  const stream = new Blob([bytes(base64)]).stream()
    .pipeThrough(new DecompressionStream('deflate'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}
const types = readable ? inflate(S.types) : null;   // 0 flow, 1 wall, 2 open, 3 no data
const cache = new Map();
function heights(k) {
  let p = cache.get(k);
  if (!p) {
    p = inflate(HEIGHTS[k]).then(b => {
      const v = new DataView(b.buffer, b.byteOffset, b.byteLength);
      const a = new Uint16Array(b.length >> 1);
      for (let i = 0; i < a.length; i++) a[i] = v.getUint16(2 * i, true);
      return a;
    });
    cache.set(k, p);
    if (cache.size > 16) cache.delete(cache.keys().next().value);
  }
  return p;
}

// ---- the frame shown
function timeLabel(t) { return String(Number(t.toPrecision(6))); }
function show(k) {
  current = Math.max(0, Math.min(n - 1, k));
  pic.src = FRAMES[current];
  slider.value = current;
  timeText.textContent = 't = ' + timeLabel(S.times[current]) + ' s';
  frameText.textContent = 'frame ' + (current + 1) + ' / ' + n +
    ' \u00b7 snapshot ' + S.snapshots[current];
  if (hover) readout(hoverText, hover);
  if (pinned) readout(pinnedText, pinned);
}
function fps() {
  const f = Number(fpsInput.value);
  return f >= 1 && f <= 240 ? f : S.fps;
}
function tick() {
  timer = null;
  if (current + 1 >= n) { stop(); return; }
  show(current + 1);
  timer = setTimeout(tick, 1000 / fps());
}
function play() {
  if (timer || n < 2) return;
  if (current + 1 >= n) show(0);
  playButton.textContent = 'Pause';
  timer = setTimeout(tick, 1000 / fps());
}
function stop() {
  clearTimeout(timer);
  timer = null;
  playButton.textContent = 'Play';
}
function toggle() { if (timer) stop(); else play(); }

// ---- height and position under the mouse or at the pinned point
function locate(e) {
  const r = pic.getBoundingClientRect();
  const fx = ((e.clientX - r.left) / r.width * S.imageW - S.mapX) / S.mapW;
  const fy = ((e.clientY - r.top) / r.height * S.imageH - S.mapY) / S.mapH;
  if (!(fx >= 0 && fx < 1 && fy >= 0 && fy < 1) || !(S.gw > 0)) return null;
  const col = Math.min(S.gw - 1, Math.floor(fx * S.gw));
  const row = Math.min(S.gh - 1, Math.floor(fy * S.gh));
  return {col: col, row: row};
}
function readout(el, at) {
  const k = current, i = at.col, j = S.gh - 1 - at.row;
  const x = S.x0 + (i + 0.5) * S.gdx, y = S.y0 + (j + 0.5) * S.gdy;
  const what = el === hoverText ? 'mouse' : 'pinned';
  const where = what + ': x = ' + x.toFixed(xyDigits) + ' m, y = ' + y.toFixed(xyDigits) +
    ' m (' + (S.cells ? 'cell ' + i + ', ' + j : 'pixel ' + i + ', ' + j +
    ', a mean of its cells') + ')';
  if (!readable) {
    el.textContent = where + ' \u00b7 height: this browser cannot inflate the ' +
      'embedded heights (it lacks DecompressionStream)';
    return;
  }
  Promise.all([heights(k), types]).then(([a, type_of]) => {
    if (k !== current || (el === hoverText ? hover : pinned) !== at) return;
    const v = a[at.row * S.gw + at.col], type = type_of[at.row * S.gw + at.col];
    let text, kind, h = '';
    if (v === 0) { text = 'wall'; kind = 'wall'; }
    else if (v === 1) { text = 'no data'; kind = 'nodata'; }
    else {
      h = S.qlo + (v - 2) * step;
      kind = type === 2 ? 'open' : 'flow';
      text = 'h = ' + h.toFixed(hDigits) + ' m' + (type === 2 ? ' (open)' : '');
    }
    el.textContent = where + ' \u00b7 ' + text;
    Object.assign(el.dataset, {frame: k, i: i, j: j, x: x, y: y, h: h, kind: kind});
  }).catch(err => { el.textContent = where + ' \u00b7 height unreadable: ' + err; });
}
function pinAt(at) {
  pinned = at;
  if (!at) {
    pinMark.style.display = 'none';
    pinnedText.textContent = '';
    pinnedText.removeAttribute('data-frame');
    return;
  }
  pinMark.style.left = (S.mapX + (at.col + 0.5) / S.gw * S.mapW) / S.imageW * 100 + '%';
  pinMark.style.top = (S.mapY + (at.row + 0.5) / S.gh * S.mapH) / S.imageH * 100 + '%';
  pinMark.style.display = 'block';
  readout(pinnedText, at);
}

// ---- the colour bar, from the colour map's own table
function drawBar() {
  const c = $('bar'), dpr = window.devicePixelRatio || 1;
  const w = 80, h = Math.max(140, Math.round(pic.getBoundingClientRect().height) - 44);
  c.style.width = w + 'px';
  c.style.height = h + 'px';
  c.width = Math.round(w * dpr);
  c.height = Math.round(h * dpr);
  const g = c.getContext('2d');
  g.scale(dpr, dpr);
  const top = 7, bottom = h - 7, x = 1, bw = 18, span = bottom - top;
  // colour k is that of heights within half a step of zmin + k / 255 (zmax - zmin)
  for (let k = 0; k < 256; k++) {
    g.fillStyle = '#' + S.cmap.substr(6 * k, 6);
    const lo = Math.max(0, (k - 0.5) / 255), hi = Math.min(1, (k + 0.5) / 255);
    const y0 = Math.floor(bottom - span * hi), y1 = Math.ceil(bottom - span * lo);
    g.fillRect(x, y0, bw, y1 - y0);
  }
  g.strokeStyle = '#666';
  g.lineWidth = 1;
  g.strokeRect(x + 0.5, top + 0.5, bw - 1, span - 1);
  const range = S.zmax - S.zmin, raw = range / 5;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const tick = [1, 2, 2.5, 5, 10].map(m => m * mag).find(s => s >= raw);
  const digits = Math.max(0, -Math.floor(Math.log10(tick) + 1e-9) + (tick / mag === 2.5));
  g.fillStyle = '#222';
  g.font = '12px system-ui, -apple-system, sans-serif';
  g.textBaseline = 'middle';
  const mark = (v, text) => {
    const y = Math.round(bottom - (v - S.zmin) / range * span) + 0.5;
    g.beginPath();
    g.moveTo(x + bw, y);
    g.lineTo(x + bw + 4, y);
    g.stroke();
    g.fillText(text, x + bw + 8, Math.min(bottom - 5, Math.max(top + 5, y)));
  };
  // both ends, one digit finer than the ticks unless on one; the ticks
  // between that leave room for their labels
  const onTick = v => Math.abs(v / tick - Math.round(v / tick)) < 1e-9;
  for (const v of [S.zmin, S.zmax])
    mark(v, (Math.abs(v) < tick / 20 ? 0 : v).toFixed(digits + (onTick(v) ? 0 : 1)));
  for (let v = Math.ceil(S.zmin / tick - 1e-9) * tick; v <= S.zmax + 1e-9 * range;
       v += tick) {
    const gap = Math.min(v - S.zmin, S.zmax - v) / range * span;
    if (gap >= 14)
      mark(v, (Math.abs(v) < tick / 2 ? 0 : v).toFixed(digits));
  }
}

// ---- set-up
document.title = S.name + ' \u2014 sandslide viewer';
$('title').textContent = S.name;
$('sub').textContent = S.nx + ' \u00d7 ' + S.ny + ' cells of ' + S.dx +
  (S.dy === S.dx ? '' : ' \u00d7 ' + S.dy) + ' m \u00b7 ' +
  n + ' frame' + (n === 1 ? '' : 's') + ', t = ' + timeLabel(S.times[0]) + ' \u2026 ' +
  timeLabel(S.times[n - 1]) + ' s \u00b7 heights ' + Number(S.zmin.toPrecision(4)) +
  ' \u2026 ' + Number(S.zmax.toPrecision(4)) + ' m \u00b7 ' + S.style +
  (S.style === 'gray16' ? '' : ', ' + S.cmapName);
$('wallkey').style.background = S.wall;
if (S.open) $('openkey').style.background = S.open;
else $('openkey').parentNode.style.display = 'none';
if (S.absent) $('nodatakey').style.background = S.absent;
else $('nodatakey').parentNode.style.display = 'none';
const zoom = Math.max(S.imageW, S.imageH) < 400 ?
  Math.ceil(400 / Math.max(S.imageW, S.imageH)) : 1;
pic.width = S.imageW * zoom;
pic.height = S.imageH * zoom;
$('main').style.width = Math.max(pic.width, 420) + 'px';
if (zoom > 1) pic.classList.add('pixelated');
slider.max = n - 1;
fpsInput.value = S.fps;
hoverText.textContent = S.gw > 0 ?
  'Move the mouse over the picture for the height and position; click to pin a point.' :
  'No height readout for the ' + S.style + ' view: render with --style shaded for one.';
slider.addEventListener('input', () => { stop(); show(Number(slider.value)); });
playButton.addEventListener('click', toggle);
fpsInput.addEventListener('change', () => { if (timer) { stop(); play(); } });
pic.addEventListener('mousemove', e => {
  const at = locate(e);
  if (at && hover && at.col === hover.col && at.row === hover.row) return;
  hover = at;
  if (at) readout(hoverText, at);
});
pic.addEventListener('mouseleave', () => { hover = null; });
pic.addEventListener('click', e => pinAt(locate(e)));
document.addEventListener('keydown', e => {
  if (e.target === fpsInput || e.altKey || e.ctrlKey || e.metaKey) return;
  if (e.key === 'ArrowLeft' || e.key === 'ArrowRight') {
    e.preventDefault();
    stop();
    show(current + (e.key === 'ArrowRight' ? 1 : -1));
  } else if (e.key === 'Home' || e.key === 'End') {
    e.preventDefault();
    stop();
    show(e.key === 'Home' ? 0 : n - 1);
  } else if (e.key === ' ') {
    e.preventDefault();
    toggle();
  } else if (e.key === 'Escape') {
    pinAt(null);
  }
});
window.addEventListener('resize', drawBar);
pic.addEventListener('load', drawBar, {once: true});
show(n - 1);   // the end: what the run made (a pouring case starts empty)
drawBar();
})();
