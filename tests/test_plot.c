/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_plot.c - pixel-level properties of the line plots (plot.h).
 *
 * Every figure is written as a PNG and decoded here with libpng's
 * simplified API, not with the renderer's code, so what is checked is
 * what a reader of the file sees.  Series are found by their palette
 * colour (ss_plot_palette): nothing else in a figure has it.
 *
 * SANDSLIDE_PLOT_DEMO=FILE.png also writes the demo figure (two panels: a
 * front radius over time, a cost along nu on a log axis) there, to look at.
 */
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>

#include "render/plot.h"
#include "sandslide/error.h"

/* ---- helpers ---------------------------------------------------------- */

/* A decoded figure, 8-bit RGB, rows from the top. */
struct pic {
	int w, h;
	uint8_t *px;
};

static int pic_read(const char *path, struct pic *p)
{
	png_image im;
	memset(&im, 0, sizeof im);
	im.version = PNG_IMAGE_VERSION;
	p->px = NULL;
	if (!png_image_begin_read_from_file(&im, path))
		return -1;
	im.format = PNG_FORMAT_RGB;
	p->w = (int)im.width;
	p->h = (int)im.height;
	p->px = malloc(PNG_IMAGE_SIZE(im));
	if (!p->px || !png_image_finish_read(&im, NULL, p->px, 0, NULL)) {
		png_image_free(&im);
		free(p->px);
		p->px = NULL;
		return -1;
	}
	return 0;
}

static const uint8_t *pic_at(const struct pic *p, int x, int y)
{
	return p->px + 3 * ((size_t)y * p->w + x);
}

static int is_colour(const struct pic *p, int x, int y, int colour)
{
	uint8_t rgb[3];
	ss_plot_palette(colour, rgb);
	return !memcmp(pic_at(p, x, y), rgb, 3);
}

/* Bounding box and count of the pixels of a palette colour in the
 * rectangle [x0, x1) x [y0, y1) of the picture (clipped to it). */
struct box {
	int x0, y0, x1, y1;   /* inclusive; x0 > x1 when empty */
	long n;
};

static struct box find_in(const struct pic *p, int colour, int x0, int x1, int y0, int y1)
{
	struct box b = {p->w, p->h, -1, -1, 0};
	for (int y = y0 < 0 ? 0 : y0; y < y1 && y < p->h; y++)
		for (int x = x0 < 0 ? 0 : x0; x < x1 && x < p->w; x++)
			if (is_colour(p, x, y, colour)) {
				b.x0 = x < b.x0 ? x : b.x0;
				b.x1 = x > b.x1 ? x : b.x1;
				b.y0 = y < b.y0 ? y : b.y0;
				b.y1 = y > b.y1 ? y : b.y1;
				b.n++;
			}
	return b;
}

/* The same in columns [x0, x1), all rows. */
static struct box find_colour(const struct pic *p, int colour, int x0, int x1)
{
	return find_in(p, colour, x0, x1, 0, p->h);
}

/* Markers of a colour, left to right: runs of columns holding it; their
 * centres (column and row of the middle of each run's box). */
static int find_blobs(const struct pic *p, int colour, double *cx, double *cy, int max)
{
	int n = 0, start = -1;
	for (int x = 0; x <= p->w; x++) {
		const int has = x < p->w && find_colour(p, colour, x, x + 1).n > 0;
		if (has && start < 0)
			start = x;
		if (!has && start >= 0) {
			const struct box b = find_colour(p, colour, start, x);
			if (n < max) {
				cx[n] = 0.5 * (b.x0 + b.x1);
				cy[n] = 0.5 * (b.y0 + b.y1);
			}
			n++;
			start = -1;
		}
	}
	return n;
}

/* The whole file's bytes (malloc'd) and size; NULL if unreadable. */
static unsigned char *slurp(const char *path, size_t *size)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	unsigned char *b = NULL;
	size_t n = 0, cap = 0, got;
	do {
		if (n == cap) {
			cap = cap ? 2 * cap : 1 << 16;
			unsigned char *more = realloc(b, cap);
			if (!more) {
				free(b);
				fclose(f);
				return NULL;
			}
			b = more;
		}
		got = fread(b + n, 1, cap - n, f);
		n += got;
	} while (got > 0);
	fclose(f);
	*size = n;
	return b;
}

static int same_bytes(const char *a, const char *b)
{
	size_t na = 0, nb = 0;
	unsigned char *x = slurp(a, &na), *y = slurp(b, &nb);
	const int same = x && y && na == nb && !memcmp(x, y, na);
	free(x);
	free(y);
	return same;
}

/* ---- tests ------------------------------------------------------------ */

/* The figure is columns * width x rows * height px of 8-bit RGB. */
static void test_size(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 3, 2, 300, 200) == SS_OK, "create 3 x 2 panels of 300 x 200");
	const double x[3] = {0, 1, 2}, y[3] = {1, 3, 2};
	CHECK(ss_plot_add(p, 4, x, y, 3, SS_PLOT_LINE_MARKERS, 0, "a") == SS_OK, "add to panel 4");
	const char *path = check_file("size.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write %s", path);
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "libpng reads %s", path);
	CHECK(pic.px && pic.w == 900 && pic.h == 400, "figure is %d x %d px, not 900 x 400", pic.w,
	      pic.h);
	/* panel 4 is row 1, column 1: its data stays in its own rectangle */
	if (pic.px) {
		const struct box b = find_colour(&pic, 0, 0, pic.w);
		CHECK(b.n > 0 && b.x0 >= 300 && b.x1 < 600 && b.y0 >= 200 && b.y1 < 400,
		      "panel 4's series is in x 300..599, y 200..399: x %d..%d, y %d..%d", b.x0, b.x1,
		      b.y0, b.y1);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* y = const across the panel is one row of pixels over most of its width. */
static void test_horizontal_line(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	double x[11], y[11];
	for (int i = 0; i <= 10; i++)
		x[i] = i, y[i] = 2.5;
	CHECK(ss_plot_add(p, 0, x, y, 11, SS_PLOT_LINE, 1, NULL) == SS_OK, "add");
	const char *path = check_file("hline.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		const struct box b = find_colour(&pic, 1, 0, pic.w);
		CHECK(b.n > 0 && b.y0 == b.y1, "the line is in one row: rows %d..%d", b.y0, b.y1);
		CHECK(b.x1 - b.x0 + 1 >= 0.7 * pic.w, "the line spans %d of %d px", b.x1 - b.x0 + 1,
		      pic.w);
		CHECK(b.n == b.x1 - b.x0 + 1, "the line has no holes: %ld px over %d columns", b.n,
		      b.x1 - b.x0 + 1);
		/* a single value is the middle of its axis */
		CHECK(fabs(b.y0 - 0.5 * pic.h) < 0.2 * pic.h, "row %d is near the middle of %d",
		      b.y0, pic.h);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* A vertical line at x = 2.5 is one column, where the markers at x = 0 and
 * x = 10 put 2.5, spanning the plot's height, between the grid lines of
 * two ticks. */
static void test_vline(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	const double x[2] = {0, 10}, y[2] = {0, 1};
	CHECK(ss_plot_add(p, 0, x, y, 2, SS_PLOT_MARKERS, 1, NULL) == SS_OK, "add");
	CHECK(ss_plot_vline(p, 0, 2.5, 2) == SS_OK, "vline");
	const char *path = check_file("vline.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		double cx[4], cy[4];
		const int n = find_blobs(&pic, 1, cx, cy, 4);
		const struct box v = find_colour(&pic, 2, 0, pic.w);
		CHECK(n == 2, "two markers: %d", n);
		CHECK(v.n > 0 && v.x0 == v.x1, "the line is one column: %d..%d", v.x0, v.x1);
		if (n == 2 && v.n > 0) {
			const double want = cx[0] + 0.25 * (cx[1] - cx[0]);
			CHECK_NEAR(v.x0, want, 1.0, "x = 2.5 between the markers at 0 and 10");
		}
		CHECK(v.y1 - v.y0 + 1 >= 0.6 * pic.h && v.n == v.y1 - v.y0 + 1,
		      "the line spans the plot: rows %d..%d, %ld px", v.y0, v.y1, v.n);
		/* grid lines (the ticks') on either side in the line's middle row */
		const uint8_t grid[3] = {0xe4, 0xe4, 0xe4};
		const int row = (v.y0 + v.y1) / 2;
		int left = -1, right = -1;
		for (int c = 0; c < pic.w; c++)
			if (!memcmp(pic_at(&pic, c, row), grid, 3)) {
				if (c < v.x0)
					left = c;
				else if (right < 0)
					right = c;
			}
		CHECK(left >= 0 && right > v.x0, "grid lines left and right of the line: %d, %d",
		      left, right);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* Markers appear left to right in x order, higher values higher up. */
static void test_markers_order(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	const double x[4] = {3, 1, 4, 2}, y[4] = {3, 4, 2, 1};
	CHECK(ss_plot_add(p, 0, x, y, 4, SS_PLOT_MARKERS, 3, NULL) == SS_OK, "add");
	const char *path = check_file("markers.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		double cx[8], cy[8];
		const int n = find_blobs(&pic, 3, cx, cy, 8);
		CHECK(n == 4, "four markers: %d", n);
		if (n == 4) {
			/* left to right: x = 1, 2, 3, 4 with y = 4, 1, 3, 2 */
			CHECK(cy[0] < cy[2] && cy[2] < cy[3] && cy[3] < cy[1],
			      "rows by value: y 4 %g, 3 %g, 2 %g, 1 %g", cy[0], cy[2], cy[3], cy[1]);
			CHECK_NEAR(cx[1] - cx[0], cx[2] - cx[1], 1.0, "equal x steps, equal spacing");
			CHECK_NEAR(cx[2] - cx[1], cx[3] - cx[2], 1.0, "equal x steps, equal spacing");
		}
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* A NaN (or an infinity) breaks the line: no pixel of its colour between
 * the points either side of it; the segments up to them are drawn. */
static void check_gap(double bad, const char *name)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	double x[11], y[11];
	for (int i = 0; i <= 10; i++)
		x[i] = i, y[i] = i;
	y[5] = bad;
	CHECK(ss_plot_add(p, 0, x, y, 11, SS_PLOT_LINE, 0, NULL) == SS_OK, "add");
	const char *path = check_file(name);
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		const struct box b = find_colour(&pic, 0, 0, pic.w);
		const double step = (b.x1 - b.x0) / 10.0;   /* px per unit of x */
		const int c4 = (int)lround(b.x0 + 4 * step), c6 = (int)lround(b.x0 + 6 * step);
		const struct box gap = find_colour(&pic, 0, c4 + 2, c6 - 1);
		CHECK(b.n > 0 && gap.n == 0, "%g at x = 5: %ld px in columns %d..%d", bad, gap.n,
		      c4 + 2, c6 - 2);
		const struct box before = find_colour(&pic, 0, c4 - 3, c4 - 1);
		const struct box after = find_colour(&pic, 0, c6 + 2, c6 + 4);
		CHECK(before.n > 0 && after.n > 0, "segments up to x = 4 and from x = 6: %ld, %ld px",
		      before.n, after.n);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

static void test_nan_breaks_line(void)
{
	check_gap(NAN, "nan.png");
	check_gap(INFINITY, "inf.png");
}

/* On a log x axis 1, 10 and 100 are equally spaced; x <= 0 is not drawn
 * and does not stretch the axis. */
static void test_log_x(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	CHECK(ss_plot_panel(p, 0, "log", "x", "y", 1) == SS_OK, "panel");
	const double x[5] = {1, 0, 10, -5, 100}, y[5] = {1, 1, 1, 1, 1};
	CHECK(ss_plot_add(p, 0, x, y, 5, SS_PLOT_MARKERS, 4, NULL) == SS_OK, "add");
	const char *path = check_file("log.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		double cx[8], cy[8];
		const int n = find_blobs(&pic, 4, cx, cy, 8);
		CHECK(n == 3, "three markers (x = 0 and -5 not drawn): %d", n);
		if (n == 3) {
			CHECK_NEAR(cx[1] - cx[0], cx[2] - cx[1], 1.0, "1 -> 10 as wide as 10 -> 100");
			CHECK(cx[2] - cx[0] >= 0.6 * pic.w, "1 .. 100 spans the axis: %g of %d px",
			      cx[2] - cx[0], pic.w);
		}
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* The legend goes to the corner where it covers no data: with a line
 * along the top and down the right side, the lower left. */
static void test_legend_corner(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	const double x[3] = {0, 10, 10}, y[3] = {10, 10, 0};
	CHECK(ss_plot_add(p, 0, x, y, 3, SS_PLOT_LINE, 0, "edge") == SS_OK, "add");
	const char *path = check_file("legend.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		/* the legend's sample: the colour away from the data's two lines
		 * (the top row and the right column of the data) */
		const struct box all = find_colour(&pic, 0, 0, pic.w);
		const struct box sample = find_in(&pic, 0, 0, all.x1 - 5, all.y0 + 5, pic.h);
		CHECK(sample.n > 0 && sample.y0 == sample.y1 && sample.x1 < pic.w / 2,
		      "one sample row in the left half: rows %d..%d, x up to %d", sample.y0,
		      sample.y1, sample.x1);
		CHECK(sample.y1 > pic.h / 2, "the sample is in the lower half: row %d of %d", sample.y1,
		      pic.h);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* A panel with nothing to draw has its axes and title, and no colour. */
static void test_empty_panel(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 2, 1, 300, 200) == SS_OK, "create");
	CHECK(ss_plot_panel(p, 1, "empty", "x", "y", 1) == SS_OK, "panel");
	const char *path = check_file("empty.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		long colour = 0, dark_top = 0, dark = 0;
		for (int y = 0; y < pic.h; y++)
			for (int x = 0; x < pic.w; x++) {
				const uint8_t *q = pic_at(&pic, x, y);
				colour += q[0] != q[1] || q[1] != q[2];
				dark += x >= 300 && q[0] == 0;
				dark_top += x >= 300 && y < 15 && q[0] == 0;
			}
		CHECK(colour == 0, "no coloured pixel: %ld", colour);
		CHECK(dark_top > 0, "the title is drawn at the top");
		CHECK(dark > 2 * 200, "the frame and ticks are drawn: %ld black px", dark);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* The last row of the first band of rows, from the top, that holds dark
 * pixels (< 128) in columns [x0, x1): a panel's title; -1 if none. */
static int first_band_bottom(const struct pic *p, int x0, int x1)
{
	int in_band = 0;
	for (int y = 0; y < p->h; y++) {
		int dark = 0;
		for (int x = x0; x < x1 && !dark; x++)
			dark = pic_at(p, x, y)[0] < 128;
		if (dark)
			in_band = 1;
		else if (in_band)
			return y - 1;
	}
	return -1;
}

/* The bottom of the title's ink of an empty 400 x 300 panel titled t. */
static int title_bottom(const char *t, const char *name)
{
	struct ss_plot *p;
	int bottom = -1;
	CHECK(ss_plot_create(&p, 1, 1, 400, 300) == SS_OK, "create");
	CHECK(ss_plot_panel(p, 0, t, NULL, NULL, 0) == SS_OK, "panel");
	const char *path = check_file(name);
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px)
		bottom = first_band_bottom(&pic, pic.w / 4, 3 * pic.w / 4);
	free(pic.px);
	ss_plot_destroy(p);
	return bottom;
}

/* Descenders reach below the baseline (issue 36: the bitmap font drew
 * "bin9ham" and "cost alon9 nu", its g within the line): a title with a g
 * ends lower than the same letters without one, and so does one with p
 * and y. */
static void test_descenders(void)
{
	const int g = title_bottom("bingham", "g.png"), no_g = title_bottom("binham", "no_g.png");
	CHECK(g >= 0 && no_g >= 0 && g >= no_g + 2,
	      "\"bingham\" ends at row %d, \"binham\" at row %d: the g descends", g, no_g);
	const int py = title_bottom("cost along nu (py)", "py.png");
	const int plain = title_bottom("cost alon nu", "plain.png");
	CHECK(py >= plain + 2, "\"cost along nu (py)\" ends at row %d, \"cost alon nu\" at %d", py,
	      plain);
}

/* A legend's frame: the bounding box of the runs of 30 px or more along
 * a row of one colour other than white, black, the grid's and the
 * palette's (its top and bottom edges).  Text (antialiased grey) draws no
 * such runs, though its pixels may have the frame's colour.  Returns 0 if
 * there is none. */
static int legend_box(const struct pic *p, struct box *b)
{
	const uint8_t grid[3] = {0xe4, 0xe4, 0xe4};
	uint8_t edge[3];
	int found = 0;
	for (int y = 0; y < p->h && !found; y++)
		for (int x = 0, run = 0; x < p->w && !found; x++) {
			const uint8_t *q = pic_at(p, x, y);
			int plain = (q[0] == 255 && q[1] == 255 && q[2] == 255) ||
			            (q[0] == 0 && q[1] == 0 && q[2] == 0) || !memcmp(q, grid, 3);
			for (int c = 0; c < SS_PLOT_COLOURS; c++)
				plain |= is_colour(p, x, y, c);
			run = !plain && x > 0 && !memcmp(q, pic_at(p, x - 1, y), 3) ? run + 1 : 0;
			if (run >= 30) {
				memcpy(edge, q, 3);
				found = 1;
			}
		}
	if (!found)
		return 0;
	*b = (struct box){p->w, p->h, -1, -1, 0};
	for (int y = 0; y < p->h; y++)
		for (int x = 0, run = 0; x <= p->w; x++) {
			if (x < p->w && !memcmp(pic_at(p, x, y), edge, 3)) {
				run++;
				continue;
			}
			if (run >= 30) {
				b->x0 = x - run < b->x0 ? x - run : b->x0;
				b->x1 = x - 1 > b->x1 ? x - 1 : b->x1;
				b->y0 = y < b->y0 ? y : b->y0;
				b->y1 = y > b->y1 ? y : b->y1;
				b->n++;
			}
			run = 0;
		}
	return 1;
}

/* The plot area's frame: the box of the longest black row run (its top and
 * bottom lines; text is antialiased and draws no long black runs). */
static struct box frame_box(const struct pic *p)
{
	struct box b = {p->w, p->h, -1, -1, 0};
	int longest = 0;
	for (int y = 0; y < p->h; y++)
		for (int x = 0, run = 0; x < p->w; x++) {
			const uint8_t *q = pic_at(p, x, y);
			run = q[0] == 0 && q[1] == 0 && q[2] == 0 ? run + 1 : 0;
			if (run > longest)
				longest = run, b.x1 = x, b.x0 = x - run + 1;
		}
	for (int y = 0; y < p->h; y++) {
		const uint8_t *q = pic_at(p, (b.x0 + b.x1) / 2, y);
		if (q[0] == 0 && q[1] == 0 && q[2] == 0 && longest > 0) {
			int run = 0;
			while (b.x0 + run <= b.x1 && !pic_at(p, b.x0 + run, y)[0])
				run++;
			if (run == longest) {
				b.y0 = b.y0 > y ? y : b.y0;
				b.y1 = y;
			}
		}
	}
	return b;
}

/* fit --plot's first panel as fit draws it (src/app/fit.c: 480 x 360 px,
 * its titles, the observed fronts as markers and each of the four
 * closures' best run as a line, colours 0 and 1 + closure), with the
 * fronts of tests/cli/test_fit.py's transient cone (the observed below the
 * runs: the legend of f9026b5 sat on the last two); with legend entries or
 * without. */
static struct ss_plot *fronts_figure(int legends)
{
	struct ss_plot *p;
	if (ss_plot_create(&p, 1, 1, 480, 360) != SS_OK)
		return NULL;
	ss_plot_panel(p, 0, "front: equivalent radius", "time (s)", "radius (m)", 0);
	static const char *names[4] = {"coulomb", "bingham", "herschel-bulkley", "casson"};
	static const double to[6] = {1, 2, 3, 5, 8, 12};
	static const double ro[6] = {0.749, 0.768, 0.787, 0.795, 0.805, 0.821};
	static const double reach[4] = {0.118, 0.125, 0.126, 0.130};
	ss_plot_add(p, 0, to, ro, 6, SS_PLOT_MARKERS, 0, legends ? "observed" : NULL);
	double t[49], r[49];
	for (int c = 0; c < 4; c++) {
		for (int i = 0; i <= 48; i++) {
			t[i] = 0.25 * i;
			r[i] = 0.784 + reach[c] * (1 - exp(-t[i] / 2.2));
		}
		ss_plot_add(p, 0, t, r, 49, SS_PLOT_LINE, 1 + c, legends ? names[c] : NULL);
	}
	return p;
}

/* Lines through every corner of the plot area (fit's panel size): no
 * corner is free for the legend. */
static struct ss_plot *cross_figure(int legends)
{
	struct ss_plot *p;
	if (ss_plot_create(&p, 1, 1, 480, 360) != SS_OK)
		return NULL;
	ss_plot_panel(p, 0, "cost along nu", "nu", "cost", 0);
	double x[41], y[3][41];
	for (int i = 0; i <= 40; i++) {
		x[i] = 0.05 * i;
		y[0][i] = x[i];          /* corner to corner, both ways */
		y[1][i] = 2.0 - x[i];
		y[2][i] = i < 20 ? 0.0 : 2.0;
	}
	static const char *names[3] = {"coulomb", "bingham", "herschel-bulkley"};
	for (int s = 0; s < 3; s++)
		ss_plot_add(p, 0, x, y[s], 41, SS_PLOT_LINE, s, legends ? names[s] : NULL);
	return p;
}

/*
 * The legend covers no data (issue 36: fit's legend sat on the curves):
 * the figure drawn with legend entries and again without, the legend's
 * box (its frame) holds no pixel of a series of the figure without it,
 * when the plot area is the same in both; when it is not, the legend went
 * outside the area and stays out of it.
 */
static void check_legend_clear(struct ss_plot *(*figure)(int), const char *name,
                               int want_outside)
{
	struct box box[2] = {{0}}, frame[2];
	struct pic pic[2] = {{0}};
	for (int with = 0; with < 2; with++) {
		struct ss_plot *p = figure(with);
		CHECK(p != NULL, "%s: figure made", name);
		char file[64];
		snprintf(file, sizeof file, "%s_%d.png", name, with);
		const char *path = check_file(file);
		CHECK(p && ss_plot_write_png(p, path) == SS_OK, "write");
		CHECK(pic_read(path, &pic[with]) == 0, "read");
		ss_plot_destroy(p);
		if (!pic[with].px)
			goto out;
		frame[with] = frame_box(&pic[with]);
	}
	CHECK(legend_box(&pic[1], &box[1]), "%s: the legend is drawn", name);
	CHECK(!legend_box(&pic[0], &box[0]), "%s: no legend without entries", name);
	const struct box *b = &box[1], *f = &frame[1];
	const int same_area = !memcmp(&frame[0], &frame[1], sizeof frame[0]);
	if (same_area) {
		long covered = 0;
		for (int c = 0; c < SS_PLOT_COLOURS; c++)
			covered += find_in(&pic[0], c, b->x0, b->x1 + 1, b->y0, b->y1 + 1).n;
		CHECK(covered == 0, "%s: the legend (x %d..%d, y %d..%d) covers %ld px of the "
		      "series", name, b->x0, b->x1, b->y0, b->y1, covered);
	} else {
		CHECK(b->x0 > f->x1 || b->x1 < f->x0 || b->y0 > f->y1 || b->y1 < f->y0,
		      "%s: the legend (x %d..%d, y %d..%d) is outside the plot area (x %d..%d, "
		      "y %d..%d)", name, b->x0, b->x1, b->y0, b->y1, f->x0, f->x1, f->y0, f->y1);
	}
	CHECK(want_outside == !same_area, "%s: the legend is %s the plot area", name,
	      same_area ? "inside" : "outside");
	CHECK(b->x1 < pic[1].w && b->y1 < pic[1].h, "%s: the legend is in the panel", name);
out:
	free(pic[0].px);
	free(pic[1].px);
}

/* No corner is free in either: the legend goes under the plot area.  A
 * free corner is test_legend_corner's. */
static void test_legend_covers_no_data(void)
{
	check_legend_clear(fronts_figure, "fronts", 1);
	check_legend_clear(cross_figure, "cross", 1);
}

/* Is there ink (a pixel darker than mid-grey) in column x, rows [y0, y1)? */
static int ink_in_column(const struct pic *p, int x, int y0, int y1)
{
	for (int y = y0; y < y1; y++)
		if (pic_at(p, x, y)[0] < 128)
			return 1;
	return 0;
}

static int ink_in_row(const struct pic *p, int y, int x0, int x1)
{
	for (int x = x0; x < x1; x++)
		if (pic_at(p, x, y)[0] < 128)
			return 1;
	return 0;
}

/*
 * Tick labels do not run into each other, in a proportional font on a
 * small panel with long labels: between the marks of neighbouring x ticks
 * (black pixels just under the frame) a column of the labels' rows is
 * blank, and between neighbouring y ticks a row of the labels' columns.
 */
static void test_tick_labels_apart(void)
{
	struct ss_plot *p;
	CHECK(ss_plot_create(&p, 1, 1, 240, 180) == SS_OK, "create");
	CHECK(ss_plot_panel(p, 0, "ticks", "x", "y", 0) == SS_OK, "panel");
	const double x[2] = {123450.0, 123990.0}, y[2] = {1.2e-4, 9.7e-4};
	CHECK(ss_plot_add(p, 0, x, y, 2, SS_PLOT_LINE, 0, NULL) == SS_OK, "add");
	const char *path = check_file("ticks.png");
	CHECK(ss_plot_write_png(p, path) == SS_OK, "write");
	struct pic pic;
	CHECK(pic_read(path, &pic) == 0, "read");
	if (pic.px) {
		const struct box f = frame_box(&pic);
		/* x: tick marks in the row under the frame, labels below them */
		int ticks[64], n = 0, apart = 1;
		for (int c = f.x0; c <= f.x1 && n < 64; c++)
			if (pic_at(&pic, c, f.y1 + 1)[0] == 0)
				ticks[n++] = c;
		const int y0 = f.y1 + 3, y1 = f.y1 + 3 + 22;
		for (int i = 0; i + 1 < n; i++) {
			int blank = 0;
			for (int c = ticks[i] + 1; c < ticks[i + 1] && !blank; c++)
				blank = !ink_in_column(&pic, c, y0, y1);
			apart &= blank;
		}
		CHECK(n >= 2 && apart, "%d x ticks, their labels apart: %d", n, apart);
		/* y: tick marks in the column left of the frame, labels left of them */
		n = 0, apart = 1;
		for (int r = f.y0; r <= f.y1 && n < 64; r++)
			if (pic_at(&pic, f.x0 - 2, r)[0] == 0)
				ticks[n++] = r;
		for (int i = 0; i + 1 < n; i++) {
			int blank = 0;
			for (int r = ticks[i] + 1; r < ticks[i + 1] && !blank; r++)
				blank = !ink_in_row(&pic, r, f.x0 - 40 < 0 ? 0 : f.x0 - 40, f.x0 - 4);
			apart &= blank;
		}
		CHECK(n >= 2 && apart, "%d y ticks, their labels apart: %d", n, apart);
	}
	free(pic.px);
	ss_plot_destroy(p);
}

/* The demo of sandslide fit --plot: fronts over time and a cost along nu. */
static struct ss_plot *demo_figure(void)
{
	struct ss_plot *p;
	if (ss_plot_create(&p, 2, 1, 640, 480) != SS_OK)
		return NULL;
	ss_plot_panel(p, 0, "front radius", "time (s)", "radius (m)", 0);
	ss_plot_panel(p, 1, "cost along nu", "nu (m^2/s)", "cost [-]", 1);
	double t[41], r[3][41], to[9], ro[9];
	for (int i = 0; i <= 40; i++) {
		t[i] = 0.05 * i;
		r[0][i] = 0.12 + 0.30 * (1 - exp(-2.2 * t[i]));
		r[1][i] = 0.12 + 0.27 * (1 - exp(-2.8 * t[i]));
		r[2][i] = 0.12 + 0.29 * (1 - exp(-2.0 * t[i])) * (1 - 0.05 * t[i]);
	}
	for (int i = 0; i < 9; i++) {
		to[i] = 0.25 * i;
		ro[i] = 0.12 + 0.29 * (1 - exp(-2.3 * to[i])) + 0.006 * ((i * 7) % 5 - 2);
	}
	ss_plot_add(p, 0, to, ro, 9, SS_PLOT_MARKERS, 5, "observed");
	ss_plot_add(p, 0, t, r[0], 41, SS_PLOT_LINE, 0, "coulomb");
	ss_plot_add(p, 0, t, r[1], 41, SS_PLOT_LINE, 1, "bingham");
	ss_plot_add(p, 0, t, r[2], 41, SS_PLOT_LINE, 2, "casson");
	double nu[25], cost[25];
	for (int i = 0; i < 25; i++) {
		nu[i] = pow(10.0, -3.0 + 3.0 * i / 24.0);
		const double d = log10(nu[i] / 0.03);
		cost[i] = 0.002 + 0.01 * d * d;
	}
	ss_plot_add(p, 1, nu, cost, 25, SS_PLOT_LINE_MARKERS, 0, "coulomb");
	ss_plot_vline(p, 1, 0.03, 1);
	return p;
}

/* The same figure written twice, or built twice, gives the same bytes. */
static void test_deterministic(void)
{
	struct ss_plot *p = demo_figure(), *q = demo_figure();
	CHECK(p && q, "demo figures made");
	if (!p || !q) {
		ss_plot_destroy(p);
		ss_plot_destroy(q);
		return;
	}
	const char *a = check_file("demo_a.png"), *b = check_file("demo_b.png");
	CHECK(ss_plot_write_png(p, a) == SS_OK, "write a");
	CHECK(ss_plot_write_png(p, b) == SS_OK, "write b");
	CHECK(same_bytes(a, b), "written twice: the same bytes");
	const char *c = check_file("demo_c.png");
	CHECK(ss_plot_write_png(q, c) == SS_OK, "write c");
	CHECK(same_bytes(a, c), "built twice: the same bytes");
	struct pic pic;
	CHECK(pic_read(a, &pic) == 0 && pic.w == 1280 && pic.h == 480, "demo is 1280 x 480");
	free(pic.px);
	const char *demo = getenv("SANDSLIDE_PLOT_DEMO");
	if (demo && *demo) {
		CHECK(ss_plot_write_png(p, demo) == SS_OK, "write the demo to %s", demo);
		printf("  demo figure: %s\n", demo);
	}
	ss_plot_destroy(p);
	ss_plot_destroy(q);
}

/* A status and that the last message mentions `part`. */
static int refused(int status, int want, const char *part)
{
	const int ok = status == want && strstr(ss_error_last_message(), part) != NULL;
	if (!ok)
		fprintf(stderr, "  status %d (want %d), message \"%s\" (want \"%s\" in it)\n", status,
		        want, ss_error_last_message(), part);
	return ok;
}

/* Bad arguments are refused with a message saying what is accepted, and
 * leave the figure as it was: it draws the same bytes after them. */
static void test_bad_input(void)
{
	ss_error_set_quiet(1);
	struct ss_plot *p = NULL;
	CHECK(refused(ss_plot_create(&p, 0, 1, 300, 200), SS_ERR_INPUT, "at least 1 column") &&
	          !p, "0 columns");
	CHECK(refused(ss_plot_create(&p, 1, 1, 100, 200), SS_ERR_INPUT, "at least 200 x 150") &&
	          !p, "panel too narrow");
	CHECK(refused(ss_plot_create(&p, 100, 1, 300, 200), SS_ERR_INPUT, "at most 16384") && !p,
	      "figure too wide");

	p = demo_figure();
	CHECK(p != NULL, "demo figure");
	if (!p) {
		ss_error_set_quiet(0);
		return;
	}
	const char *before = check_file("bad_before.png");
	CHECK(ss_plot_write_png(p, before) == SS_OK, "write before");
	const double x[2] = {1, 2}, y[2] = {3, 4}, huge[2] = {1, 1e308};
	CHECK(refused(ss_plot_panel(p, 2, "t", "x", "y", 0), SS_ERR_INPUT, "panels 0 to 1"),
	      "panel 2 of 2");
	CHECK(refused(ss_plot_panel(p, -1, "t", "x", "y", 0), SS_ERR_INPUT, "panel -1"),
	      "panel -1");
	CHECK(refused(ss_plot_add(p, 5, x, y, 2, SS_PLOT_LINE, 0, "z"), SS_ERR_INPUT, "panel 5"),
	      "add to panel 5");
	CHECK(refused(ss_plot_add(p, 0, x, y, -1, SS_PLOT_LINE, 0, "z"), SS_ERR_INPUT,
	              "0 or more"), "n = -1");
	CHECK(refused(ss_plot_add(p, 0, NULL, y, 2, SS_PLOT_LINE, 0, "z"), SS_ERR_INPUT,
	              "without x"), "x NULL");
	CHECK(refused(ss_plot_add(p, 0, x, y, 2, (enum ss_plot_style)7, 0, "z"), SS_ERR_INPUT,
	              "style 7"), "style 7");
	CHECK(refused(ss_plot_add(p, 0, x, huge, 2, SS_PLOT_LINE, 0, "z"), SS_ERR_INPUT,
	              "point 1"), "y = 1e308");
	CHECK(refused(ss_plot_vline(p, 0, NAN, 0), SS_ERR_INPUT, "finite"), "vline at NaN");
	CHECK(refused(ss_plot_vline(p, 9, 1.0, 0), SS_ERR_INPUT, "panel 9"), "vline in panel 9");
	CHECK(refused(ss_plot_write_png(p, "/nonexistent/dir/x.png"), SS_ERR_FAIL,
	              "/nonexistent/dir/x.png"), "unwritable path");
	CHECK(strstr(ss_error_last_message(), "No such file or directory") != NULL,
	      "the system's reason: \"%s\"", ss_error_last_message());
	const char *after = check_file("bad_after.png");
	CHECK(ss_plot_write_png(p, after) == SS_OK, "write after");
	CHECK(same_bytes(before, after), "the refused calls changed nothing");
	/* and an empty series is no error */
	CHECK(ss_plot_add(p, 0, NULL, NULL, 0, SS_PLOT_LINE, 0, NULL) == SS_OK, "n = 0 accepted");
	ss_plot_destroy(p);
	ss_plot_destroy(NULL);
	ss_error_set_quiet(0);
}

/* Colours wrap round the palette, negative ones too, and differ within it. */
static void test_palette(void)
{
	uint8_t a[3], b[3];
	ss_plot_palette(0, a);
	ss_plot_palette(SS_PLOT_COLOURS, b);
	CHECK(!memcmp(a, b, 3), "colour %d is colour 0", SS_PLOT_COLOURS);
	ss_plot_palette(-1, a);
	ss_plot_palette(SS_PLOT_COLOURS - 1, b);
	CHECK(!memcmp(a, b, 3), "colour -1 is colour %d", SS_PLOT_COLOURS - 1);
	int distinct = 1;
	for (int i = 0; i < SS_PLOT_COLOURS; i++)
		for (int j = i + 1; j < SS_PLOT_COLOURS; j++) {
			ss_plot_palette(i, a);
			ss_plot_palette(j, b);
			distinct &= abs(a[0] - b[0]) + abs(a[1] - b[1]) + abs(a[2] - b[2]) > 60;
		}
	CHECK(distinct, "the palette's colours are far apart");
}

int main(void)
{
	if (check_scratch_make("test_plot"))
		return 1;
	RUN(test_size);
	RUN(test_horizontal_line);
	RUN(test_vline);
	RUN(test_markers_order);
	RUN(test_nan_breaks_line);
	RUN(test_log_x);
	RUN(test_legend_corner);
	RUN(test_legend_covers_no_data);
	RUN(test_descenders);
	RUN(test_tick_labels_apart);
	RUN(test_empty_panel);
	RUN(test_deterministic);
	RUN(test_bad_input);
	RUN(test_palette);
	check_scratch_remove();
	return check_report();
}
