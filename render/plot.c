/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * plot.c - line plots as PNG figures (plot.h, beside it): the figures of
 * `sandslide fit --plot`.
 *
 * A figure keeps copies of what it was given and draws only when written:
 * each panel into a picture of its own (so nothing of it spills into its
 * neighbour), which is then copied into the figure's picture and encoded
 * by png.c.  A panel, top to bottom:
 *
 *     title (centred)
 *     +-------------------------------------+
 *   y |  grid, vertical lines, series,      |  the legend in the first
 *   t |  legend                             |  corner where it covers no
 *   i |                                     |  data
 *   t +-------------------------------------+
 *   l   ticks, tick labels
 *   e   x title (centred)
 *       [legend, its entries in rows, when no corner is free]
 *
 * The axes span the data with 5 % to spare.  Tick steps are 1, 2 or 5
 * times a power of ten (whole decades on a log axis, or every 2nd, 3rd, 5th
 * ... decade when they crowd), the finest whose labels keep an em between
 * them (two lines of text on the y axis) and that gives at most about 8
 * ticks.  Text is sized from the panel (ss_render_font_px) and everything
 * round it from the font's em; lines and markers thicken from 360 px on
 * the shorter side.
 */
#include "render/plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "sandslide/error.h"
#include "sandslide/render.h"

/* ---- the figure: what the caller gave, copied ------------------------- */

struct series {
	double *x, *y;              /* n each, owned (NULL when n is 0) */
	long long n;
	enum ss_plot_style style;
	int colour;                 /* palette index, any int */
	char *legend;               /* owned; NULL: no entry */
};

struct vline {
	double x;                   /* data units */
	int colour;
};

struct panel {
	char *title, *x_label, *y_label;   /* owned; NULL: none */
	int log_x;
	struct series *series;
	int n_series, cap_series;
	struct vline *vlines;
	int n_vlines, cap_vlines;
};

struct ss_plot {
	int columns, rows;
	int panel_w, panel_h;       /* px */
	struct panel *panels;       /* columns * rows, row by row */
};

/* Okabe and Ito's colour-blind-safe palette, without its yellow (too pale
 * on white) and black (the axes' colour). */
static const uint8_t palette[SS_PLOT_COLOURS][3] = {
	{0x00, 0x72, 0xb2},   /* blue */
	{0xd5, 0x5e, 0x00},   /* vermillion */
	{0x00, 0x9e, 0x73},   /* bluish green */
	{0xcc, 0x79, 0xa7},   /* reddish purple */
	{0xe6, 0x9f, 0x00},   /* orange */
	{0x56, 0xb4, 0xe9},   /* sky blue */
};

static const uint8_t ink[3] = {0x00, 0x00, 0x00};          /* text, frame, ticks */
static const uint8_t grid_rgb[3] = {0xe4, 0xe4, 0xe4};     /* grid lines */
static const uint8_t legend_edge[3] = {0xa0, 0xa0, 0xa0};  /* the legend's frame */
static const uint8_t white[3] = {0xff, 0xff, 0xff};

void ss_plot_palette(int colour, uint8_t rgb[3])
{
	const int k = (colour % SS_PLOT_COLOURS + SS_PLOT_COLOURS) % SS_PLOT_COLOURS;
	memcpy(rgb, palette[k], 3);
}

/* A copy of text into *out, NULL for NULL or "". */
static int copy_text(const char *text, char **out, const char *what)
{
	*out = NULL;
	if (!text || !*text)
		return SS_OK;
	const size_t n = strlen(text) + 1;
	*out = ss_alloc(n, 1, what);
	if (!*out)
		return SS_ERR_FAIL;
	memcpy(*out, text, n);
	return SS_OK;
}

int ss_plot_create(struct ss_plot **out, int columns, int rows, int panel_width_px,
                   int panel_height_px)
{
	*out = NULL;
	if (columns < 1 || rows < 1)
		return ss_error_input("plot: %d x %d panels: at least 1 column and 1 row are "
		                      "accepted", columns, rows);
	if (panel_width_px < SS_PLOT_PANEL_MIN_WIDTH || panel_height_px < SS_PLOT_PANEL_MIN_HEIGHT)
		return ss_error_input("plot: panels of %d x %d px: at least %d x %d px are accepted",
		                      panel_width_px, panel_height_px, SS_PLOT_PANEL_MIN_WIDTH,
		                      SS_PLOT_PANEL_MIN_HEIGHT);
	if (panel_width_px > SS_PLOT_SIDE_MAX / columns || panel_height_px > SS_PLOT_SIDE_MAX / rows)
		return ss_error_input("plot: %d x %d panels of %d x %d px: a figure of at most "
		                      "%d px on each side is accepted", columns, rows,
		                      panel_width_px, panel_height_px, SS_PLOT_SIDE_MAX);
	struct ss_plot *p = ss_alloc(1, sizeof *p, "a plot");
	if (!p)
		return SS_ERR_FAIL;
	p->panels = ss_alloc((size_t)columns * (size_t)rows, sizeof *p->panels, "a plot's panels");
	if (!p->panels) {
		ss_free(p);
		return SS_ERR_FAIL;
	}
	p->columns = columns;
	p->rows = rows;
	p->panel_w = panel_width_px;
	p->panel_h = panel_height_px;
	*out = p;
	return SS_OK;
}

static void series_release(struct series *s)
{
	ss_free(s->x);
	ss_free(s->y);
	ss_free(s->legend);
}

void ss_plot_destroy(struct ss_plot *p)
{
	if (!p)
		return;
	for (int k = 0; k < p->columns * p->rows; k++) {
		struct panel *pn = &p->panels[k];
		ss_free(pn->title);
		ss_free(pn->x_label);
		ss_free(pn->y_label);
		for (int s = 0; s < pn->n_series; s++)
			series_release(&pn->series[s]);
		ss_free(pn->series);
		ss_free(pn->vlines);
	}
	ss_free(p->panels);
	ss_free(p);
}

static int check_panel(const struct ss_plot *p, int panel, const char *function)
{
	const int n = p->columns * p->rows;
	if (panel < 0 || panel >= n)
		return ss_error_input("%s: panel %d: panels 0 to %d are accepted (%d x %d)",
		                      function, panel, n - 1, p->columns, p->rows);
	return SS_OK;
}

int ss_plot_panel(struct ss_plot *p, int panel, const char *title, const char *x_label,
                  const char *y_label, int log_x)
{
	int err = check_panel(p, panel, "plot panel");
	if (err)
		return err;
	char *t = NULL, *xl = NULL, *yl = NULL;
	if ((err = copy_text(title, &t, "a plot title")) ||
	    (err = copy_text(x_label, &xl, "a plot axis label")) ||
	    (err = copy_text(y_label, &yl, "a plot axis label"))) {
		ss_free(t);
		ss_free(xl);
		return err;
	}
	struct panel *pn = &p->panels[panel];
	ss_free(pn->title);
	ss_free(pn->x_label);
	ss_free(pn->y_label);
	pn->title = t;
	pn->x_label = xl;
	pn->y_label = yl;
	pn->log_x = log_x != 0;
	return SS_OK;
}

/* Room for one more element in *array (*n used of *cap, each size bytes),
 * doubling it; the array is unchanged on failure. */
static int grow(void **array, int n, int *cap, size_t size, const char *what)
{
	if (n < *cap)
		return SS_OK;
	if (*cap > (1 << 28))
		return ss_error_fail("cannot add to %s: %d of them already", what, n);
	const int more = *cap ? 2 * *cap : 4;
	void *a = ss_alloc((size_t)more, size, what);
	if (!a)
		return SS_ERR_FAIL;
	if (n)
		memcpy(a, *array, (size_t)n * size);
	ss_free(*array);
	*array = a;
	*cap = more;
	return SS_OK;
}

/* A value a plot accepts: a gap (NaN, infinite) or finite within range. */
static int value_ok(double v)
{
	return !isfinite(v) || fabs(v) <= SS_PLOT_VALUE_MAX;
}

int ss_plot_add(struct ss_plot *p, int panel, const double *x, const double *y, long long n,
                enum ss_plot_style style, int colour, const char *legend)
{
	int err = check_panel(p, panel, "plot add");
	if (err)
		return err;
	if (n < 0)
		return ss_error_input("plot add: %lld points: 0 or more are accepted", n);
	if (n > 0 && (!x || !y))
		return ss_error_input("plot add: %lld points without %s: arrays of n values are "
		                      "accepted (NULL only when n is 0)", n, !x ? "x" : "y");
	if (style != SS_PLOT_LINE && style != SS_PLOT_MARKERS && style != SS_PLOT_LINE_MARKERS)
		return ss_error_input("plot add: style %d: SS_PLOT_LINE, SS_PLOT_MARKERS or "
		                      "SS_PLOT_LINE_MARKERS is accepted", (int)style);
	for (long long i = 0; i < n; i++)
		if (!value_ok(x[i]) || !value_ok(y[i]))
			return ss_error_input("plot add: point %lld is (%g, %g): values up to %g in "
			                      "magnitude, or NaN for a gap, are accepted", i, x[i], y[i],
			                      SS_PLOT_VALUE_MAX);

	struct panel *pn = &p->panels[panel];
	struct series s = {.n = n, .style = style, .colour = colour};
	if (n > 0) {
		s.x = ss_alloc((size_t)n, sizeof *s.x, "a plot series");
		s.y = s.x ? ss_alloc((size_t)n, sizeof *s.y, "a plot series") : NULL;
		if (!s.y) {
			series_release(&s);
			return SS_ERR_FAIL;
		}
		memcpy(s.x, x, (size_t)n * sizeof *s.x);
		memcpy(s.y, y, (size_t)n * sizeof *s.y);
	}
	void *array = pn->series;
	if ((err = copy_text(legend, &s.legend, "a plot legend")) ||
	    (err = grow(&array, pn->n_series, &pn->cap_series, sizeof *pn->series,
	                "a plot panel's series"))) {
		series_release(&s);
		return err;
	}
	pn->series = array;
	pn->series[pn->n_series++] = s;
	return SS_OK;
}

int ss_plot_vline(struct ss_plot *p, int panel, double x, int colour)
{
	int err = check_panel(p, panel, "plot vline");
	if (err)
		return err;
	if (!isfinite(x) || fabs(x) > SS_PLOT_VALUE_MAX)
		return ss_error_input("plot vline: x = %g: a finite value up to %g in magnitude "
		                      "is accepted", x, SS_PLOT_VALUE_MAX);
	struct panel *pn = &p->panels[panel];
	void *array = pn->vlines;
	if ((err = grow(&array, pn->n_vlines, &pn->cap_vlines, sizeof *pn->vlines,
	                "a plot panel's vertical lines")))
		return err;
	pn->vlines = array;
	pn->vlines[pn->n_vlines++] = (struct vline){x, colour};
	return SS_OK;
}

/* ---- axes: range, ticks and their labels ----------------------------- */

enum { MAX_TICKS = 64, LABEL_SIZE = 32 };

/* One axis of a panel.  Positions along it are linear in t(v): v, or
 * log10(v) on a log axis. */
struct axis {
	int log;
	double lo, hi;              /* the range in t */
	int pix0, len;              /* its first pixel and its length, px */
	int flip;                   /* 1: t grows towards pixel 0 (the y axis) */
	int n_ticks, n_minor;
	double tick[MAX_TICKS];     /* values (not t) */
	char label[MAX_TICKS][LABEL_SIZE];
	double minor[MAX_TICKS];    /* unlabelled ticks (log axis), values */
};

static double axis_t(const struct axis *a, double v)
{
	return a->log ? log10(v) : v;
}

/* Pixel of value v (unrounded); v in the range or near it. */
static double axis_pixel(const struct axis *a, double v)
{
	double f = (axis_t(a, v) - a->lo) / (a->hi - a->lo);
	f = f < -1.0 ? -1.0 : f > 2.0 ? 2.0 : f;   /* keeps the rounding in int */
	return a->pix0 + (a->flip ? 1.0 - f : f) * (a->len - 1);
}

static int round_px(double x)
{
	return (int)floor(x + 0.5);
}

/* Whether a point can be drawn: both coordinates finite, x > 0 on log. */
static int drawable(int log_x, double x, double y)
{
	return isfinite(x) && isfinite(y) && (!log_x || x > 0.0);
}

/* [lo, hi] of what is drawn along an axis (in t), widened by 5 % each
 * side, or by a tenth of its magnitude (half a decade on a log axis) when
 * it is a single value; [0, 1] with nothing to draw. */
static void finish_range(struct axis *a, int any, double lo, double hi)
{
	if (!any) {
		lo = 0.0, hi = 1.0;
	} else if (lo == hi) {
		const double d = a->log ? 0.5 : lo != 0.0 ? 0.1 * fabs(lo) : 1.0;
		lo -= d, hi += d;
	} else {
		const double d = 0.05 * (hi - lo);
		lo -= d, hi += d;
	}
	a->lo = lo;
	a->hi = hi;
}

static void data_ranges(const struct panel *pn, struct axis *ax, struct axis *ay)
{
	double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
	int any_x = 0, any_y = 0;
	for (int s = 0; s < pn->n_series; s++) {
		const struct series *sr = &pn->series[s];
		for (long long i = 0; i < sr->n; i++) {
			if (!drawable(pn->log_x, sr->x[i], sr->y[i]))
				continue;
			const double t = axis_t(ax, sr->x[i]);
			xlo = fmin(xlo, t), xhi = fmax(xhi, t);
			ylo = fmin(ylo, sr->y[i]), yhi = fmax(yhi, sr->y[i]);
			any_x = any_y = 1;
		}
	}
	for (int k = 0; k < pn->n_vlines; k++) {
		if (pn->log_x && !(pn->vlines[k].x > 0.0))
			continue;
		const double t = axis_t(ax, pn->vlines[k].x);
		xlo = fmin(xlo, t), xhi = fmax(xhi, t);
		any_x = 1;
	}
	finish_range(ax, any_x, xlo, xhi);
	finish_range(ay, any_y, ylo, yhi);
}

/* "1.5e-4" from printf's "1.50e-04"; returns the length snprintf gives
 * (a label is at most "-1.23456789e-308", digits <= 8, well within its
 * room: a cut would be a bug, and returning the count tells the compiler
 * that one was thought of). */
static int short_exponent(double v, int digits, char *out, size_t size)
{
	char buf[LABEL_SIZE * 2];
	snprintf(buf, sizeof buf, "%.*e", digits, v);
	char *e = strchr(buf, 'e');
	if (!e)
		return snprintf(out, size, "%s", buf);
	*e = '\0';
	const int exponent = atoi(e + 1);
	if (strchr(buf, '.')) {
		char *end = buf + strlen(buf) - 1;
		while (*end == '0')
			*end-- = '\0';
		if (*end == '.')
			*end = '\0';
	}
	return snprintf(out, size, "%se%d", buf, exponent);
}

/* A tick of a linear axis: v, a multiple of step, as short as tells it
 * from its neighbours: fixed decimals ("0.02", "150") while they are few,
 * else a power of ten ("2e-4", "1.5e5"). */
static void linear_label(double v, double step, double magnitude, char *out, size_t size)
{
	const int e_step = (int)floor(log10(step) + 1e-9);
	if (fabs(v) < 1e-9 * step) {
		snprintf(out, size, "0");
	} else if (e_step >= -3 && magnitude < 1e5) {
		snprintf(out, size, "%.*f", e_step < 0 ? -e_step : 0, v);
	} else {
		int digits = (int)floor(log10(fabs(v)) + 1e-9) - e_step;
		digits = digits < 0 ? 0 : digits > 8 ? 8 : digits;
		short_exponent(v, digits, out, size);
	}
}

/* A tick of a log axis, m * 10^d with m a whole 1..9: plain from 0.01 to
 * 9000, else "1e-3", "5e4". */
static void log_label(int m, int d, char *out, size_t size)
{
	if (d >= -2 && d <= 3)
		snprintf(out, size, "%.*f", d < 0 ? -d : 0, m * pow(10.0, d));
	else if (m == 1)
		snprintf(out, size, "1e%d", d);
	else
		snprintf(out, size, "%de%d", m, d);
}

/* Space a tick label needs along the axis, px: its width on the x axis
 * plus an em between neighbours; two lines of text on the y axis. */
static int label_room(const struct axis *a, const struct ss_render_font *f)
{
	int w = 0;
	if (a->flip)
		return 2 * ss_render_font_line(f);
	for (int i = 0; i < a->n_ticks; i++) {
		const int tw = ss_render_text_width(f, a->label[i]);
		w = tw > w ? tw : w;
	}
	return w + ss_render_font_em(f);
}

static double tick_spacing_px(const struct axis *a, double step_t)
{
	return step_t / (a->hi - a->lo) * (a->len - 1);
}

/* Ticks at multiples of a 1-2-5 step in value space, the finest that
 * leaves room between labels and gives no more than about 8 ticks; for a
 * log axis less than a decade or so wide too (values, then, placed by
 * their logarithm). */
static void linear_ticks(struct axis *a, const struct ss_render_font *f)
{
	const double vlo = a->log ? pow(10.0, a->lo) : a->lo;
	const double vhi = a->log ? pow(10.0, a->hi) : a->hi;
	const double span = vhi - vlo, magnitude = fmax(fabs(vlo), fabs(vhi));
	a->n_ticks = 0;
	if (!(span > 0.0) || !isfinite(span))
		return;
	const double base = pow(10.0, floor(log10(span / 50.0)));
	static const double mult[3] = {1.0, 2.0, 5.0};
	for (int j = 0; j < 3 * 6; j++) {
		const double step = mult[j % 3] * base * pow(10.0, j / 3);
		if (!(step > 0.0) || !isfinite(step))
			return;
		const double first = ceil(vlo / step - 1e-9), last = floor(vhi / step + 1e-9);
		if (last - first + 1 > MAX_TICKS)
			continue;
		struct axis b = *a;
		b.n_ticks = 0;
		for (double i = first; i <= last; i++) {
			const double v = i * step;
			if (a->log && !(v > 0.0))
				continue;
			b.tick[b.n_ticks] = v;
			linear_label(v, step, magnitude, b.label[b.n_ticks], LABEL_SIZE);
			b.n_ticks++;
		}
		/* the narrowest gap between ticks: on a log axis, the last two */
		double gap = tick_spacing_px(&b, step);
		if (a->log && b.n_ticks >= 2)
			gap = tick_spacing_px(&b, log10(b.tick[b.n_ticks - 1]) -
			                              log10(b.tick[b.n_ticks - 2]));
		const int fits = gap >= label_room(&b, f) && gap >= (a->len - 1) / 8.0;
		if (fits || j == 3 * 6 - 1) {
			a->n_ticks = b.n_ticks;
			memcpy(a->tick, b.tick, sizeof a->tick);
			memcpy(a->label, b.label, sizeof a->label);
			return;
		}
	}
}

/* Ticks of a log axis: every `stride`-th decade, the smallest stride whose
 * labels have room; with a single decade each, also 2 and 5 times them;
 * failing two ticks, linear_ticks.  Unlabelled minor ticks at 2 .. 9 times
 * each decade when decades are far enough apart. */
static void log_ticks(struct axis *a, const struct ss_render_font *f)
{
	const int dlo = (int)ceil(a->lo - 1e-9), dhi = (int)floor(a->hi + 1e-9);
	static const int strides[] = {1, 2, 3, 5, 10, 20, 50, 100, 200};
	a->n_ticks = a->n_minor = 0;
	int stride = 0;
	for (size_t j = 0; j < sizeof strides / sizeof strides[0]; j++) {
		struct axis b = *a;
		b.n_ticks = 0;
		for (int d = dlo; d <= dhi && b.n_ticks < MAX_TICKS; d++) {
			if (((d % strides[j]) + strides[j]) % strides[j])
				continue;
			b.tick[b.n_ticks] = pow(10.0, d);
			log_label(1, d, b.label[b.n_ticks], LABEL_SIZE);
			b.n_ticks++;
		}
		if (tick_spacing_px(&b, strides[j]) >= label_room(&b, f) &&
		    tick_spacing_px(&b, strides[j]) >= (a->len - 1) / 10.0) {
			*a = b;
			stride = strides[j];
			break;
		}
	}
	if (stride == 1 && a->n_ticks < 3) {
		/* a decade or two: 1, 2, 5 times each, if their labels fit */
		struct axis b = *a;
		b.n_ticks = 0;
		for (int d = dlo - 1; d <= dhi && b.n_ticks < MAX_TICKS - 3; d++)
			for (int m = 1; m <= 5; m += m == 1 ? 1 : 3) {
				const double t = d + log10(m);
				if (t < a->lo - 1e-9 || t > a->hi + 1e-9)
					continue;
				b.tick[b.n_ticks] = m * pow(10.0, d);
				log_label(m, d, b.label[b.n_ticks], LABEL_SIZE);
				b.n_ticks++;
			}
		/* the narrowest gap is between 1 and 2 times a decade */
		if (tick_spacing_px(&b, log10(2.0)) >= label_room(&b, f))
			*a = b;
	}
	if (a->n_ticks < 3) {
		/* within a decade or so (2 .. 5): 1-2-5 steps of the values, if
		 * they give more ticks */
		struct axis b = *a;
		linear_ticks(&b, f);
		if (b.n_ticks > a->n_ticks) {
			*a = b;
			return;
		}
	}
	if (a->n_ticks < 2)
		return;
	if (stride == 1 && tick_spacing_px(a, 1.0) >= 6 * ss_render_font_em(f))
		for (int d = dlo - 1; d <= dhi && a->n_minor < MAX_TICKS - 8; d++)
			for (int m = 2; m <= 9; m++) {
				const double t = d + log10(m);
				if (t >= a->lo && t <= a->hi)
					a->minor[a->n_minor++] = m * pow(10.0, d);
			}
}

static void make_ticks(struct axis *a, const struct ss_render_font *f)
{
	if (a->log)
		log_ticks(a, f);
	else
		linear_ticks(a, f);
}

/* ---- pixels ----------------------------------------------------------- */

/* A clip rectangle: pixels [x0, x1) x [y0, y1). */
struct clip {
	int x0, y0, x1, y1;
};

static void put(struct ss_render_image *img, const struct clip *c, int x, int y,
                const uint8_t rgb[3])
{
	if (x < c->x0 || y < c->y0 || x >= c->x1 || y >= c->y1)
		return;
	uint8_t *q = img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
	q[0] = rgb[0], q[1] = rgb[1], q[2] = rgb[2];
}

static void fill(struct ss_render_image *img, const struct clip *c, int x0, int y0, int x1,
                 int y1, const uint8_t rgb[3])
{
	for (int y = y0; y < y1; y++)
		for (int x = x0; x < x1; x++)
			put(img, c, x, y, rgb);
}

/* A line of `width` px from (x0, y0) to (x1, y1), both ends drawn
 * (Bresenham, a width x width brush at each step). */
static void line(struct ss_render_image *img, const struct clip *c, int x0, int y0, int x1,
                 int y1, int width, const uint8_t rgb[3])
{
	const int dx = abs(x1 - x0), dy = -abs(y1 - y0);
	const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
	const int o = (width - 1) / 2;
	int err = dx + dy;
	for (;;) {
		fill(img, c, x0 - o, y0 - o, x0 - o + width, y0 - o + width, rgb);
		if (x0 == x1 && y0 == y1)
			break;
		const int e2 = 2 * err;
		if (e2 >= dy)
			err += dy, x0 += sx;
		if (e2 <= dx)
			err += dx, y0 += sy;
	}
}

static void disc(struct ss_render_image *img, const struct clip *c, int x, int y, int r,
                 const uint8_t rgb[3])
{
	for (int v = -r; v <= r; v++)
		for (int u = -r; u <= r; u++)
			if (u * u + v * v <= r * r + r)   /* + r: rounder than a diamond */
				put(img, c, x + u, y + v, rgb);
}

/* ---- a panel ---------------------------------------------------------- */

/* The fonts of a figure: titles, and everything else. */
struct fonts {
	struct ss_render_font *text, *title;
};

/* A legend's box and where it went. */
struct legend {
	int entries;
	int flow_w;                 /* entries flow in rows this wide, px; 0: one
	                             * entry a row */
	int w, h;                   /* the box, px */
	int x, y;                   /* its top-left corner */
};

/* Sizes of a panel's parts, px: text from the fonts' em, lines and markers
 * thicker on larger panels. */
struct layout {
	const struct fonts *fonts;
	int em, line, pad, tick, gap, line_w, marker_r;
	int below;                  /* px kept at the bottom for a legend */
	struct clip whole, area;    /* the panel, and inside its frame */
};

static int max_int(int a, int b)
{
	return a > b ? a : b;
}

/*
 * The panel's layout for axes ax, ay (their ranges set; their ticks made
 * here), with `below` px kept free at the bottom (for a legend put under
 * the plot).  Top to bottom: pad, title, half an em, the plot area, ticks,
 * tick labels, the x axis's title, `below`, pad; left to right: pad, the
 * y axis's title (turned), the y tick labels, ticks, the area, room for
 * half the last x tick label, pad.
 */
static struct layout panel_layout(const struct panel *pn, const struct fonts *fonts, int w,
                                  int h, int below, struct axis *ax, struct axis *ay)
{
	struct layout l;
	const struct ss_render_font *f = fonts->text;
	const int k = max_int((w < h ? w : h) + 120, 240) / 240;   /* thickness unit */
	l.fonts = fonts;
	l.em = ss_render_font_em(f);
	l.line = ss_render_font_line(f);
	l.pad = l.em / 2;
	l.tick = max_int(l.em / 3, 3);
	l.gap = max_int(l.em / 4, 2);
	l.line_w = k < 2 ? 1 : 2;
	l.marker_r = 3 * k;
	l.below = below;
	l.whole = (struct clip){0, 0, w, h};
	l.area.y0 = l.pad + (pn->title ? ss_render_font_line(fonts->title) : 0) + l.em / 2;
	l.area.y1 = h - (l.pad + below + (pn->x_label ? l.line + l.gap : 0) + l.line + l.gap +
	                 l.tick + 1);
	ay->pix0 = l.area.y0;
	ay->len = l.area.y1 - l.area.y0;
	make_ticks(ay, f);
	int label_w = 0;
	for (int i = 0; i < ay->n_ticks; i++)
		label_w = max_int(label_w, ss_render_text_width(f, ay->label[i]));
	l.area.x0 = l.pad + (pn->y_label ? l.line + l.em / 2 : 0) + label_w + l.gap + l.tick + 1;
	l.area.x1 = w - (l.pad + l.em + 1);
	/* the last x tick label, centred on its tick, must end inside the
	 * panel: narrow the area until it does (its ticks change with it) */
	for (int tries = 0; tries < 4; tries++) {
		ax->pix0 = l.area.x0;
		ax->len = l.area.x1 - l.area.x0;
		make_ticks(ax, f);
		if (ax->n_ticks == 0)
			break;
		const int last = ax->n_ticks - 1;
		const int x = round_px(axis_pixel(ax, ax->tick[last]));
		const int over = x + (ss_render_text_width(f, ax->label[last]) + 1) / 2 - (w - l.pad);
		if (over <= 0 || l.area.x1 - over - l.area.x0 < l.em)
			break;
		l.area.x1 -= over;
	}
	return l;
}

/* Data in the box [x0, x1) x [y0, y1): pixels that are neither background
 * nor grid (only the series and vertical lines are drawn when it looks). */
static long ink_in(const struct ss_render_image *img, int x0, int y0, int x1, int y1)
{
	long n = 0;
	for (int y = y0 < 0 ? 0 : y0; y < y1 && y < img->height; y++)
		for (int x = x0 < 0 ? 0 : x0; x < x1 && x < img->width; x++) {
			const uint8_t *q = img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
			n += memcmp(q, white, 3) != 0 && memcmp(q, grid_rgb, 3) != 0;
		}
	return n;
}

/* A legend sample of series s, centred on row y from x0 to x1. */
static void draw_sample(struct ss_render_image *img, const struct layout *l,
                        const struct series *s, int x0, int x1, int y)
{
	uint8_t rgb[3];
	ss_plot_palette(s->colour, rgb);
	if (s->style != SS_PLOT_LINE)
		disc(img, &l->whole, (x0 + x1) / 2, y, l->marker_r, rgb);
	if (s->style != SS_PLOT_MARKERS)
		line(img, &l->whole, x0, y, x1, y, l->line_w, rgb);
}

/* The width of a legend entry: its sample, a third of an em, its text. */
static int entry_w(const struct ss_render_font *f, const char *text)
{
	const int em = ss_render_font_em(f);
	return 2 * em + em / 3 + ss_render_text_width(f, text);
}

/* Entries placed in rows at most `width` px wide (0: one a row), an em
 * between neighbours: the next entry's x in its row (row: fl->row). */
struct flow {
	int width, em, x, row;
};

static int flow_place(struct flow *fl, int w)
{
	if (fl->x > 0 && (fl->width == 0 || fl->x + fl->em + w > fl->width)) {
		fl->row++;
		fl->x = 0;
	}
	const int at = fl->x ? fl->x + fl->em : 0;
	fl->x = at + w;
	return at;
}

/* Inside the legend's frame: a third of an em and the frame's pixel. */
static int legend_inner(const struct ss_render_font *f)
{
	return ss_render_font_em(f) / 3 + 1;
}

/* The legend's size in the text font with its entries in rows at most
 * flow_w px wide (0: one entry a row). */
static struct legend legend_size(const struct panel *pn, const struct ss_render_font *f,
                                 int flow_w)
{
	struct legend g = {.flow_w = flow_w};
	struct flow fl = {flow_w, ss_render_font_em(f), 0, 0};
	int widest = 0;
	for (int s = 0; s < pn->n_series; s++)
		if (pn->series[s].legend) {
			flow_place(&fl, entry_w(f, pn->series[s].legend));
			widest = max_int(widest, fl.x);
			g.entries++;
		}
	g.w = 2 * legend_inner(f) + widest;
	g.h = 2 * legend_inner(f) + (fl.row + 1) * ss_render_font_line(f);
	return g;
}

/*
 * Where the legend goes inside the plot area: the first corner of upper
 * right, upper left, lower right, lower left whose box, with a quarter em
 * round it, holds no pixel of data already drawn; 0 if none does.  With
 * `any`, the corner with the fewest such pixels instead (the fallback of
 * a panel too small for a legend under its plot), and 1.
 */
static int legend_inside(const struct ss_render_image *img, const struct layout *l,
                         struct legend *g, int any)
{
	const int inset = max_int(l->em / 3, 3), margin = max_int(l->em / 4, 2);
	const int left = l->area.x0 + inset, right = l->area.x1 - inset - g->w;
	const int top = l->area.y0 + inset, bottom = l->area.y1 - inset - g->h;
	const int cx[4] = {right, left, right, left}, cy[4] = {top, top, bottom, bottom};
	int best = -1;
	long best_ink = 0;
	for (int c = 0; c < 4; c++) {
		const long n = ink_in(img, cx[c] - margin, cy[c] - margin, cx[c] + g->w + margin,
		                      cy[c] + g->h + margin);
		if (best < 0 || n < best_ink)
			best = c, best_ink = n;
		if (n == 0 && !any)
			break;
	}
	if (best_ink > 0 && !any)
		return 0;
	g->x = cx[best];
	g->y = cy[best];
	return 1;
}

static void draw_legend(struct ss_render_image *img, const struct layout *l,
                        const struct panel *pn, const struct legend *g)
{
	const struct ss_render_font *f = l->fonts->text;
	const int em = l->em, inner = legend_inner(f), sample_w = 2 * em;
	const int bx = g->x, by = g->y;
	fill(img, &l->whole, bx, by, bx + g->w, by + g->h, white);
	fill(img, &l->whole, bx, by, bx + g->w, by + 1, legend_edge);
	fill(img, &l->whole, bx, by + g->h - 1, bx + g->w, by + g->h, legend_edge);
	fill(img, &l->whole, bx, by, bx + 1, by + g->h, legend_edge);
	fill(img, &l->whole, bx + g->w - 1, by, bx + g->w, by + g->h, legend_edge);
	/* a sample on the height of the middle of its line's digits */
	const int middle = ss_render_font_ascent(f) - ss_render_font_digit_height(f) / 2;
	struct flow fl = {g->flow_w, em, 0, 0};
	for (int s = 0; s < pn->n_series; s++) {
		const struct series *sr = &pn->series[s];
		if (!sr->legend)
			continue;
		const int x = bx + inner + flow_place(&fl, entry_w(f, sr->legend));
		const int y = by + inner + fl.row * l->line;
		draw_sample(img, l, sr, x, x + sample_w, y + middle);
		ss_render_draw_text(img, f, x + sample_w + em / 3, y, sr->legend, ink);
	}
}

static void draw_series(struct ss_render_image *img, const struct layout *l,
                        const struct panel *pn, const struct axis *ax, const struct axis *ay,
                        const struct series *s)
{
	uint8_t rgb[3];
	ss_plot_palette(s->colour, rgb);
	const int dot = max_int(l->line_w, 1);
	if (s->style != SS_PLOT_MARKERS) {
		int have_prev = 0, px = 0, py = 0;
		for (long long i = 0; i < s->n; i++) {
			if (!drawable(pn->log_x, s->x[i], s->y[i])) {
				have_prev = 0;   /* a gap */
				continue;
			}
			const int x = round_px(axis_pixel(ax, s->x[i]));
			const int y = round_px(axis_pixel(ay, s->y[i]));
			if (have_prev)
				line(img, &l->area, px, py, x, y, l->line_w, rgb);
			px = x, py = y, have_prev = 1;
			/* a lone point between gaps: a small dot rather than nothing */
			const int alone = (i == 0 || !drawable(pn->log_x, s->x[i - 1], s->y[i - 1])) &&
			                  (i == s->n - 1 || !drawable(pn->log_x, s->x[i + 1], s->y[i + 1]));
			if (alone)
				disc(img, &l->area, x, y, dot, rgb);
		}
	}
	if (s->style != SS_PLOT_LINE)
		for (long long i = 0; i < s->n; i++)
			if (drawable(pn->log_x, s->x[i], s->y[i]))
				disc(img, &l->area, round_px(axis_pixel(ax, s->x[i])),
				     round_px(axis_pixel(ay, s->y[i])), l->marker_r, rgb);
}

/* Text centred on x, kept inside the panel. */
static void text_centred(struct ss_render_image *img, const struct ss_render_font *f, int x,
                         int y, const char *text)
{
	const int w = ss_render_text_width(f, text);
	int x0 = x - w / 2;
	x0 = x0 + w > img->width ? img->width - w : x0;
	x0 = x0 < 0 ? 0 : x0;
	ss_render_draw_text(img, f, x0, y, text, ink);
}

/* The data of the panel (grid, vertical lines, series) inside the area of
 * layout l, on white. */
static void draw_data(struct ss_render_image *img, const struct layout *l,
                      const struct panel *pn, const struct axis *ax, const struct axis *ay)
{
	for (int y = 0; y < img->height; y++)
		memset(img->pixels + (size_t)y * img->row_bytes, 0xff, 3 * (size_t)img->width);
	for (int i = 0; i < ax->n_ticks; i++) {
		const int x = round_px(axis_pixel(ax, ax->tick[i]));
		fill(img, &l->area, x, l->area.y0, x + 1, l->area.y1, grid_rgb);
	}
	for (int i = 0; i < ay->n_ticks; i++) {
		const int y = round_px(axis_pixel(ay, ay->tick[i]));
		fill(img, &l->area, l->area.x0, y, l->area.x1, y + 1, grid_rgb);
	}
	for (int v = 0; v < pn->n_vlines; v++) {
		if (pn->log_x && !(pn->vlines[v].x > 0.0))
			continue;
		uint8_t rgb[3];
		ss_plot_palette(pn->vlines[v].colour, rgb);
		const int x = round_px(axis_pixel(ax, pn->vlines[v].x));
		line(img, &l->area, x, l->area.y0, x, l->area.y1 - 1, l->line_w, rgb);
	}
	for (int s = 0; s < pn->n_series; s++)
		draw_series(img, l, pn, ax, ay, &pn->series[s]);
}

/* The frame one px outside the area, ticks and their labels outside it,
 * the axes' titles and the panel's. */
static void draw_axes(struct ss_render_image *img, const struct layout *l,
                      const struct panel *pn, const struct axis *ax, const struct axis *ay)
{
	const struct ss_render_font *f = l->fonts->text;
	const struct clip *all = &l->whole;
	const int fx0 = l->area.x0 - 1, fx1 = l->area.x1, fy0 = l->area.y0 - 1, fy1 = l->area.y1;
	fill(img, all, fx0, fy0, fx1 + 1, fy0 + 1, ink);
	fill(img, all, fx0, fy1, fx1 + 1, fy1 + 1, ink);
	fill(img, all, fx0, fy0, fx0 + 1, fy1 + 1, ink);
	fill(img, all, fx1, fy0, fx1 + 1, fy1 + 1, ink);
	for (int i = 0; i < ax->n_ticks; i++) {
		const int x = round_px(axis_pixel(ax, ax->tick[i]));
		fill(img, all, x, fy1 + 1, x + 1, fy1 + 1 + l->tick, ink);
		text_centred(img, f, x, fy1 + 1 + l->tick + l->gap, ax->label[i]);
	}
	for (int i = 0; i < ax->n_minor; i++) {
		const int x = round_px(axis_pixel(ax, ax->minor[i]));
		fill(img, all, x, fy1 + 1, x + 1, fy1 + 1 + (l->tick + 1) / 2, ink);
	}
	/* a y tick label's digits are centred on its tick */
	const int centre = ss_render_font_ascent(f) - ss_render_font_digit_height(f) / 2;
	for (int i = 0; i < ay->n_ticks; i++) {
		const int y = round_px(axis_pixel(ay, ay->tick[i]));
		fill(img, all, fx0 - l->tick, y, fx0, y + 1, ink);
		const int tw = ss_render_text_width(f, ay->label[i]);
		ss_render_draw_text(img, f, fx0 - l->tick - l->gap - tw, y - centre, ay->label[i], ink);
	}
	if (pn->title)
		text_centred(img, l->fonts->title, img->width / 2, l->pad, pn->title);
	if (pn->x_label)
		text_centred(img, f, (fx0 + fx1) / 2, img->height - l->pad - l->below - l->line,
		             pn->x_label);
	if (pn->y_label) {
		const int tw = ss_render_text_width(f, pn->y_label);
		int y = (fy0 + fy1) / 2 - tw / 2;
		y = y + tw > img->height ? img->height - tw : y;
		ss_render_draw_text_up(img, f, l->pad, y < 0 ? 0 : y, pn->y_label, ink);
	}
}

/* Panel pn into img (its own picture, the panel's size).  The data are
 * drawn first; the legend goes into a corner of the area where it covers
 * none of them, else under the area (its entries in rows), which is
 * shortened for it and drawn again; in a panel too small for that, into
 * the corner where it covers least. */
static void draw_panel(struct ss_render_image *img, const struct panel *pn,
                       const struct fonts *fonts)
{
	struct axis ax = {.log = pn->log_x}, ay = {.flip = 1};
	data_ranges(pn, &ax, &ay);
	struct layout l = panel_layout(pn, fonts, img->width, img->height, 0, &ax, &ay);
	draw_data(img, &l, pn, &ax, &ay);
	struct legend g = legend_size(pn, fonts->text, 0);
	if (g.entries && !legend_inside(img, &l, &g, 0)) {
		const struct legend under = legend_size(pn, fonts->text,
		                                        img->width - 2 * l.pad -
		                                        2 * legend_inner(fonts->text));
		struct axis bx = {.log = pn->log_x}, by = {.flip = 1};
		data_ranges(pn, &bx, &by);
		struct layout m = panel_layout(pn, fonts, img->width, img->height, under.h + l.gap,
		                               &bx, &by);
		if (m.area.y1 - m.area.y0 >= img->height / 3) {
			l = m, ax = bx, ay = by, g = under;
			g.x = max_int((l.area.x0 + l.area.x1) / 2 - g.w / 2, l.pad);
			if (g.x + g.w > img->width - l.pad)
				g.x = max_int(img->width - l.pad - g.w, 0);
			g.y = img->height - l.pad - g.h;
			draw_data(img, &l, pn, &ax, &ay);
		} else {
			legend_inside(img, &l, &g, 1);
		}
	}
	if (g.entries)
		draw_legend(img, &l, pn, &g);
	draw_axes(img, &l, pn, &ax, &ay);
}

int ss_plot_check_font(void)
{
	return ss_render_font_check();
}

int ss_plot_write_png(const struct ss_plot *p, const char *path)
{
	if (!path || !*path)
		return ss_error_input("plot: no file name: a path for the PNG is accepted");
	struct ss_render_image fig, panel;
	struct fonts fonts = {NULL, NULL};
	/* text about 1/24 of the panel's shorter side, titles a fifth larger */
	const int px = ss_render_font_px(p->panel_w, p->panel_h);
	int err = ss_render_font_create(&fonts.text, px);
	if (err || (err = ss_render_font_create(&fonts.title, (6 * px + 2) / 5)))
		goto out_fonts;
	if ((err = ss_render_image_init(&fig, p->columns * p->panel_w, p->rows * p->panel_h, 3, 8)))
		goto out_release_fig;
	if ((err = ss_render_image_init(&panel, p->panel_w, p->panel_h, 3, 8)))
		goto out_release_panel;
	for (int r = 0; r < p->rows; r++)
		for (int c = 0; c < p->columns; c++) {
			draw_panel(&panel, &p->panels[r * p->columns + c], &fonts);
			for (int y = 0; y < p->panel_h; y++)
				memcpy(fig.pixels + (size_t)(r * p->panel_h + y) * fig.row_bytes +
				               3 * (size_t)c * (size_t)p->panel_w,
				       panel.pixels + (size_t)y * panel.row_bytes, panel.row_bytes);
		}
	err = ss_render_write_png(&fig, path, 6);
out_release_panel:
	ss_render_image_release(&panel);
out_release_fig:
	ss_render_image_release(&fig);
out_fonts:
	ss_render_font_destroy(fonts.title);
	ss_render_font_destroy(fonts.text);
	return err;
}
