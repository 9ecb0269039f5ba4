/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_render.c - pixel-level properties of the renderer (render.h).
 *
 * PNGs are decoded here with libpng directly, not with the renderer's own
 * code, so the encoding is checked independently.  Every field is
 * synthetic with known heights.
 */
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <png.h>

#include "sandslide/boundary.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"
#include "sandslide/render.h"

#include "render/internal.h"   /* the font (text.c), which frames and plots share */

static char tmpdir[256];

/* ---- helpers ---------------------------------------------------------- */

/* A field of nx x ny cells of 1 cm, heights and types owned. */
struct field {
	struct ss_render_field f;
	double *h;
	uint8_t *type;
};

static void field_init(struct field *t, int nx, int ny)
{
	t->h = calloc((size_t)nx * ny, sizeof *t->h);
	t->type = calloc((size_t)nx * ny, 1);
	t->f = (struct ss_render_field){nx, ny, 0.01, 0.01, nx, t->h, t->type, 12.5, 0};
}

static void field_release(struct field *t)
{
	free(t->h);
	free(t->type);
}

static double *H(struct field *t, int i, int j)
{
	return &t->h[(size_t)j * t->f.nx + i];
}

static uint8_t *T(struct field *t, int i, int j)
{
	return &t->type[(size_t)j * t->f.nx + i];
}

static const uint8_t *rgb_at(const struct ss_render_image *img, int x, int y)
{
	return img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
}

/* A decoded PNG: samples (16-bit native or 8-bit) and its text chunks. */
struct decoded {
	int width, height, bit_depth, color_type, has_trns;
	unsigned char *pixels;
	size_t row_bytes;
	char keys[16][80], values[16][512];
	int texts;
};

static int decode_png(const char *path, struct decoded *d)
{
	memset(d, 0, sizeof *d);
	FILE *f = fopen(path, "rb");
	if (!f)
		return -1;
	png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png_create_info_struct(png);
	if (setjmp(png_jmpbuf(png))) {
		png_destroy_read_struct(&png, &info, NULL);
		fclose(f);
		return -1;
	}
	png_init_io(png, f);
	png_read_info(png, info);
	d->width = (int)png_get_image_width(png, info);
	d->height = (int)png_get_image_height(png, info);
	d->bit_depth = png_get_bit_depth(png, info);
	d->color_type = png_get_color_type(png, info);
	d->has_trns = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
	const uint16_t one = 1;
	if (d->bit_depth == 16 && *(const uint8_t *)&one)
		png_set_swap(png);   /* to native order */
	png_read_update_info(png, info);
	d->row_bytes = png_get_rowbytes(png, info);
	d->pixels = malloc(d->row_bytes * (size_t)d->height);
	png_bytep *rows = malloc((size_t)d->height * sizeof *rows);
	for (int y = 0; y < d->height; y++)
		rows[y] = d->pixels + (size_t)y * d->row_bytes;
	png_read_image(png, rows);
	png_read_end(png, info);
	png_textp text;
	int n = 0;
	png_get_text(png, info, &text, &n);
	for (int k = 0; k < n && k < 16; k++) {
		snprintf(d->keys[k], sizeof d->keys[k], "%s", text[k].key);
		snprintf(d->values[k], sizeof d->values[k], "%s", text[k].text);
	}
	d->texts = n < 16 ? n : 16;
	free(rows);
	png_destroy_read_struct(&png, &info, NULL);
	fclose(f);
	return 0;
}

static const char *text_of(const struct decoded *d, const char *key)
{
	for (int k = 0; k < d->texts; k++)
		if (!strcmp(d->keys[k], key))
			return d->values[k];
	return NULL;
}

static double text_number(const struct decoded *d, const char *key)
{
	const char *v = text_of(d, key);
	return v ? strtod(v, NULL) : NAN;
}

/* ---- gray16 ----------------------------------------------------------- */

/* Known heights survive gray16 -> PNG -> libpng within one quantisation
 * step, walls are 0 and transparent, and the text holds range and time. */
static void test_gray16_round_trip(void)
{
	struct field t;
	field_init(&t, 37, 23);
	for (int j = 0; j < 23; j++)
		for (int i = 0; i < 37; i++) {
			*H(&t, i, j) = 0.05 + 0.3 * (0.5 + 0.5 * sin(0.37 * i) * cos(0.29 * j));
			if (i >= 30 && j < 5)
				*T(&t, i, j) = SS_CELL_WALL;
			if (i < 2)
				*T(&t, i, j) = SS_CELL_OPEN;
		}
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_GRAY16;
	o.zmin = 0.01;
	o.zmax = 0.42;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.width == 37 && img.height == 23 && img.bit_depth == 16 && img.channels == 1,
	      "gray16 is one 16-bit sample per cell: %d x %d", img.width, img.height);
	char path[512];
	snprintf(path, sizeof path, "%s/gray.png", tmpdir);
	CHECK(ss_render_write_png(&img, path, 6) == SS_OK, "write");
	ss_render_image_release(&img);

	struct decoded d;
	CHECK(decode_png(path, &d) == 0, "libpng decodes %s", path);
	CHECK(d.bit_depth == 16 && d.color_type == PNG_COLOR_TYPE_GRAY && d.has_trns,
	      "16-bit grey with tRNS: depth %d, type %d", d.bit_depth, d.color_type);
	const double zmin = text_number(&d, "zmin_m"), zmax = text_number(&d, "zmax_m");
	CHECK(zmin == 0.01 && zmax == 0.42, "range in the text chunks: %.17g %.17g", zmin, zmax);
	CHECK(text_number(&d, "time_s") == 12.5, "time in the text chunks");
	CHECK(text_of(&d, "height_m") != NULL, "the decoding rule is written down");
	const double step = (zmax - zmin) / 65534;
	double worst = 0.0;
	int walls_ok = 1;
	for (int y = 0; y < d.height; y++)
		for (int x = 0; x < d.width; x++) {
			const int i = x, j = d.height - 1 - y;   /* north row first */
			const uint16_t v = ((const uint16_t *)(d.pixels + (size_t)y * d.row_bytes))[x];
			if (*T(&t, i, j) == SS_CELL_WALL) {
				walls_ok &= v == 0;
				continue;
			}
			const double h = zmin + (v - 1.0) * step;
			worst = fmax(worst, fabs(h - *H(&t, i, j)));
		}
	CHECK(walls_ok, "walls are 0");
	CHECK(worst <= 0.5 * step + 1e-15, "heights back within half a step: worst %.3g, step %.3g",
	      worst, step);
	free(d.pixels);
	field_release(&t);
}

/* Without zmin/zmax the scale is the field's range on flow and open cells
 * (walls ignored, however high). */
static void test_gray16_default_scale(void)
{
	struct field t;
	field_init(&t, 10, 10);
	for (int k = 0; k < 100; k++)
		t.h[k] = 0.1 + 0.001 * k;
	t.h[55] = 99.0;
	t.type[55] = SS_CELL_WALL;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_GRAY16;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.zmin == 0.1 && img.zmax == 0.1 + 0.001 * 99, "scale %g .. %g", img.zmin,
	      img.zmax);
	const uint16_t *top = (const uint16_t *)img.pixels;   /* north row: j = 9 */
	const uint16_t *bottom = (const uint16_t *)(img.pixels + 9 * img.row_bytes);
	CHECK(bottom[0] == 1 && top[9] == 65535, "lowest -> 1, highest -> 65535: %u %u",
	      bottom[0], top[9]);
	ss_render_image_release(&img);
	field_release(&t);
}

/* --max-size shrinks by area averaging over flow and open cells only. */
static void test_max_size_area_average(void)
{
	struct field t;
	field_init(&t, 64, 48);
	for (int j = 0; j < 48; j++)
		for (int i = 0; i < 64; i++)
			*H(&t, i, j) = 0.002 * i + 0.003 * j;
	*T(&t, 10, 10) = SS_CELL_WALL;   /* one wall in the 2 x 2 block (5, 5) */
	*H(&t, 10, 10) = 50.0;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_GRAY16;
	o.zmin = 0.0;
	o.zmax = 0.3;
	o.max_size = 32;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.width == 32 && img.height == 24, "64 x 48 at most 32 px: %d x %d", img.width,
	      img.height);
	const double step = 0.3 / 65534;
	double worst = 0.0;
	for (int y = 0; y < 24; y++)
		for (int x = 0; x < 32; x++) {
			const int q = 23 - y;   /* block row from the south */
			double sum = 0.0;
			int n = 0;
			for (int j = 2 * q; j < 2 * q + 2; j++)
				for (int i = 2 * x; i < 2 * x + 2; i++)
					if (*T(&t, i, j) != SS_CELL_WALL) {
						sum += *H(&t, i, j);
						n++;
					}
			const uint16_t v = ((const uint16_t *)(img.pixels + (size_t)y * img.row_bytes))[x];
			worst = fmax(worst, fabs((v - 1.0) * step - sum / n));
		}
	CHECK(worst <= 0.5 * step + 1e-15, "2 x 2 area means (wall excluded): worst %.3g", worst);
	ss_render_image_release(&img);

	/* a factor that is not an integer: each pixel covers 1.6 x 1.6 cells,
	 * and is the mean of the cells weighted by the area they share with
	 * it (cells are constant over their area) */
	o.max_size = 40;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.width == 40 && img.height == 30, "64 x 48 at most 40 px: %d x %d", img.width,
	      img.height);
	worst = 0.0;
	for (int y = 0; y < 30; y++)
		for (int x = 0; x < 40; x++) {
			const double x0 = 1.6 * x, x1 = x0 + 1.6, y0 = 1.6 * (29 - y), y1 = y0 + 1.6;
			double sum = 0.0, area = 0.0;
			for (int j = 0; j < 48; j++)
				for (int i = 0; i < 64; i++) {
					const double a = fmax(0.0, fmin(x1, i + 1.0) - fmax(x0, (double)i)) *
					                 fmax(0.0, fmin(y1, j + 1.0) - fmax(y0, (double)j));
					if (a > 0.0 && *T(&t, i, j) != SS_CELL_WALL) {
						sum += a * *H(&t, i, j);
						area += a;
					}
				}
			const uint16_t v = ((const uint16_t *)(img.pixels + (size_t)y * img.row_bytes))[x];
			worst = fmax(worst, fabs((v - 1.0) * step - sum / area));
		}
	CHECK(worst <= 0.5 * step + 1e-12, "1.6 x 1.6 area means, wall excluded: worst %.3g",
	      worst);
	ss_render_image_release(&img);
	field_release(&t);
}

/* ---- shaded ----------------------------------------------------------- */

static double flat_brightness(double altitude_deg)
{
	return 0.4 + 0.6 * sin(altitude_deg * M_PI / 180.0);
}

/* A flat surface: every pixel the same colour, the map's colour at that
 * height times the brightness of a level face. */
static void test_shaded_flat_uniform(void)
{
	struct field t;
	field_init(&t, 40, 30);
	for (int k = 0; k < 1200; k++)
		t.h[k] = 0.25;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.zmin = 0.0;
	o.zmax = 1.0;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	uint8_t lut[256][3];
	ss_render_cmap_table(o.cmap, lut);
	const uint8_t *m = lut[(int)(0.25 * 255 + 0.5)];
	const double b = flat_brightness(45.0);
	int same = 1;
	for (int y = 0; y < img.height; y++)
		for (int x = 0; x < img.width; x++)
			same &= !memcmp(rgb_at(&img, x, y), rgb_at(&img, 0, 0), 3);
	CHECK(same, "flat surface: one colour");
	const uint8_t *p = rgb_at(&img, 0, 0);
	CHECK(p[0] == (uint8_t)(m[0] * b + 0.5) && p[1] == (uint8_t)(m[1] * b + 0.5) &&
	      p[2] == (uint8_t)(m[2] * b + 0.5), "flat colour %u %u %u, map %u %u %u x %.3f",
	      p[0], p[1], p[2], m[0], m[1], m[2], b);
	ss_render_image_release(&img);
	field_release(&t);
}

static double mean_luminance(const struct ss_render_image *img)
{
	double s = 0.0;
	for (int y = 0; y < img->height; y++)
		for (int x = 0; x < img->width; x++) {
			const uint8_t *p = rgb_at(img, x, y);
			s += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
		}
	return s / ((double)img->width * img->height);
}

/* Planes with the same heights, one facing the light (north-west), one
 * facing away: the first is brighter, and an inside pixel has exactly the
 * brightness of Lambert's law for its normal. */
static void test_shaded_tilt_towards_light(void)
{
	const double slope = 0.4;   /* dh per unit of horizontal distance */
	struct field to, away;
	field_init(&to, 50, 50);
	field_init(&away, 50, 50);
	for (int j = 0; j < 50; j++)
		for (int i = 0; i < 50; i++) {
			const double x = (i + 0.5) * 0.01, y = (j + 0.5) * 0.01;
			*H(&to, i, j) = 0.5 + slope * (x - y);     /* rises to the south-east */
			*H(&away, i, j) = 0.5 + slope * (y - x);   /* rises to the north-west */
		}
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.zmin = 0.0;
	o.zmax = 1.0;
	o.scale = 1;
	o.cmap = SS_RENDER_CMAP_GRAY;
	struct ss_render_image a, b;
	CHECK(ss_render_field(&to.f, &o, &a) == SS_OK && ss_render_field(&away.f, &o, &b) == SS_OK,
	      "render");
	const double la = mean_luminance(&a), lb = mean_luminance(&b);
	CHECK(la > 1.5 * lb, "facing the light %.1f, facing away %.1f", la, lb);

	/* Lambert: n = (-s, s, 1)/|.|, L = (-cos45 sin45, cos45 cos45, sin45) */
	const double n = sqrt(1.0 + 2.0 * slope * slope);
	const double c = (slope * 0.5 + slope * 0.5 + sqrt(0.5)) / n;
	const double expect = (0.4 + 0.6 * c) * (int)(0.5 * 255 + 0.5);
	const uint8_t *p = rgb_at(&a, 25, 24);   /* height 0.5 + s (x - y) = 0.5 at the centre */
	CHECK(fabs(p[0] - expect) <= 1.0, "lit face grey %u, Lambert %.2f", p[0], expect);
	ss_render_image_release(&a);
	ss_render_image_release(&b);

	/* the light's direction is an option: from the south-east it flips */
	o.azimuth_deg = 135.0;
	CHECK(ss_render_field(&to.f, &o, &a) == SS_OK && ss_render_field(&away.f, &o, &b) == SS_OK,
	      "render");
	CHECK(mean_luminance(&b) > 1.5 * mean_luminance(&a), "light from the south-east");
	ss_render_image_release(&a);
	ss_render_image_release(&b);
	field_release(&to);
	field_release(&away);
}

/* Walls and open cells have their own colours, whatever the heights. */
static void test_shaded_wall_and_open_colours(void)
{
	struct field t;
	field_init(&t, 20, 20);
	for (int j = 0; j < 20; j++)
		for (int i = 0; i < 20; i++) {
			*H(&t, i, j) = 0.01 * i;
			if (i >= 5 && i < 8 && j >= 5 && j < 15)
				*T(&t, i, j) = SS_CELL_WALL;
			if (j == 0)
				*T(&t, i, j) = SS_CELL_OPEN;
		}
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.scale = 4;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	const uint8_t wall[3] = {SS_RENDER_WALL_RGB}, open[3] = {SS_RENDER_OPEN_RGB};
	int walls = 1, opens = 1, sand = 1;
	for (int y = 0; y < img.height; y++)
		for (int x = 0; x < img.width; x++) {
			const int i = x / 4, j = 19 - y / 4;
			const uint8_t *p = rgb_at(&img, x, y);
			if (*T(&t, i, j) == SS_CELL_WALL)
				walls &= !memcmp(p, wall, 3);
			else if (*T(&t, i, j) == SS_CELL_OPEN)
				opens &= !memcmp(p, open, 3);
			else
				sand &= memcmp(p, wall, 3) && memcmp(p, open, 3);
		}
	CHECK(walls, "every wall pixel is the wall colour (cell-sharp at 4 px per cell)");
	CHECK(opens, "every open pixel is the open colour");
	CHECK(sand, "no sand pixel takes either colour");
	ss_render_image_release(&img);
	field_release(&t);
}

/* The picture's size: K pixels per cell, the automatic enlargement of
 * small grids, --max-size, non-square cells, the colour bar. */
static void test_picture_sizes(void)
{
	struct ss_render_options o;
	ss_render_options_default(&o);
	int w, h;
	ss_render_picture_size(50, 40, 0.02, 0.02, &o, &w, &h);
	CHECK(w == 550 && h == 440, "auto: 11 px per cell for a side >= 512: %d x %d", w, h);
	o.scale = 3;
	ss_render_picture_size(50, 40, 0.02, 0.02, &o, &w, &h);
	CHECK(w == 150 && h == 120, "--scale 3: %d x %d", w, h);
	o.scale = 0;
	o.style = SS_RENDER_GRAY16;
	ss_render_picture_size(50, 40, 0.02, 0.02, &o, &w, &h);
	CHECK(w == 50 && h == 40, "gray16: a pixel per cell: %d x %d", w, h);
	o.style = SS_RENDER_SHADED;
	o.max_size = 1024;
	ss_render_picture_size(16384, 8192, 1e-3, 1e-3, &o, &w, &h);
	CHECK(w == 1024 && h == 512, "16384 x 8192 at most 1024: %d x %d", w, h);
	o.max_size = 0;
	ss_render_picture_size(600, 300, 0.01, 0.02, &o, &w, &h);
	CHECK(w == 600 && h == 600, "cells twice as tall as wide: square pixels: %d x %d", w, h);

	/* the rendered picture has that size, plus the bar's strip */
	struct field t;
	field_init(&t, 64, 48);
	for (int k = 0; k < 64 * 48; k++)
		t.h[k] = 0.001 * (k % 64);
	o.max_size = 32;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.width == 32 && img.height == 24 && img.channels == 3 && img.bit_depth == 8,
	      "shaded --max-size 32: %d x %d", img.width, img.height);
	ss_render_image_release(&img);
	o.max_size = 0;
	o.colorbar = 1;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
	CHECK(img.height == 384 && img.width > 512 + 20 && img.width < 512 + 200,
	      "the colour bar widens the picture: %d x %d", img.width, img.height);
	ss_render_image_release(&img);
	field_release(&t);
}

/* Contour lines every dz: on a ramp h = x, lines at each level and only
 * there, one pixel wide. */
static void test_contours(void)
{
	struct field t;
	field_init(&t, 100, 10);
	for (int j = 0; j < 10; j++)
		for (int i = 0; i < 100; i++)
			*H(&t, i, j) = 0.01 * i + 0.001;   /* levels 0.25, 0.5, 0.75 between cells */
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.scale = 1;
	o.zmin = 0.0;
	o.zmax = 1.0;
	struct ss_render_image plain, lined;
	CHECK(ss_render_field(&t.f, &o, &plain) == SS_OK, "render");
	o.contour = 0.25;
	CHECK(ss_render_field(&t.f, &o, &lined) == SS_OK, "render");
	int columns[8], n = 0, rows_agree = 1;
	for (int x = 0; x < 100; x++) {
		const int dark = memcmp(rgb_at(&plain, x, 5), rgb_at(&lined, x, 5), 3) != 0;
		if (dark && n < 8)
			columns[n++] = x;
		for (int y = 0; y < 10; y++)
			rows_agree &= (memcmp(rgb_at(&plain, x, y), rgb_at(&lined, x, y), 3) != 0) == dark;
	}
	CHECK(n == 3, "three lines: %d", n);
	CHECK(n == 3 && columns[0] == 24 && columns[1] == 49 && columns[2] == 74,
	      "on the cells just below 0.25, 0.5, 0.75 m: %d %d %d", columns[0], columns[1],
	      columns[2]);
	CHECK(rows_agree, "straight lines across every row");
	CHECK(rgb_at(&lined, 24, 5)[1] < rgb_at(&plain, 24, 5)[1], "lines are darker");
	ss_render_image_release(&plain);
	ss_render_image_release(&lined);
	field_release(&t);
}

static int is_rgb(const uint8_t *p, int r, int g, int b)
{
	return p[0] == r && p[1] == g && p[2] == b;
}

/* The time label sits in a white strip above the map, so it covers none
 * of it; the colour bar is framed, its ticks stand clear of their labels
 * (a tick that touches a label reads as a minus sign) and both its ends
 * are labelled. */
static void test_label_and_colorbar(void)
{
	struct field t;
	field_init(&t, 64, 64);
	for (int k = 0; k < 64 * 64; k++)
		t.h[k] = 0.3;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.zmin = 0.0;
	o.zmax = 0.797;
	struct ss_render_image plain, labelled;
	CHECK(ss_render_field(&t.f, &o, &plain) == SS_OK, "render");
	o.label = 1;
	CHECK(ss_render_field(&t.f, &o, &labelled) == SS_OK, "render");
	const int strip = labelled.height - plain.height;
	CHECK(labelled.width == plain.width && strip > 7,
	      "the label adds a strip of rows above the map: %d x %d -> %d x %d", plain.width,
	      plain.height, labelled.width, labelled.height);
	int map_same = strip > 0;
	for (int y = 0; y < plain.height && map_same; y++)
		map_same &= !memcmp(rgb_at(&plain, 0, y), rgb_at(&labelled, 0, y + strip),
		                    3 * (size_t)plain.width);
	CHECK(map_same, "the label covers no pixel of the map");
	/* black text on white in a real font: antialiased, so grey at the
	 * edges of the strokes (and no other colour) */
	int black = 0, white = 0, grey = 0, other = 0;
	for (int y = 0; y < strip; y++)
		for (int x = 0; x < labelled.width; x++) {
			const uint8_t *p = rgb_at(&labelled, x, y);
			black += is_rgb(p, 0, 0, 0);
			white += is_rgb(p, 255, 255, 255);
			grey += p[0] == p[1] && p[1] == p[2] && p[0] != 0 && p[0] != 255;
			other += p[0] != p[1] || p[1] != p[2];
		}
	CHECK(black > 100 && white > black && other == 0,
	      "the strip is black text on white: %d black, %d white, %d other", black, white,
	      other);
	CHECK(grey > black / 2, "the text is antialiased: %d grey pixels, %d black", grey, black);
	ss_render_image_release(&labelled);

	o.label = 0;
	o.colorbar = 1;
	struct ss_render_image bar;
	CHECK(ss_render_field(&t.f, &o, &bar) == SS_OK, "render");
	map_same = bar.height == plain.height;
	for (int y = 0; y < plain.height && map_same; y++)
		map_same &= !memcmp(rgb_at(&plain, 0, y), rgb_at(&bar, 0, y), 3 * (size_t)plain.width);
	CHECK(map_same, "the bar leaves the map as it was");
	/* the bar's colours run from the top of the map (top) to its bottom */
	uint8_t lut[256][3];
	ss_render_cmap_table(o.cmap, lut);
	int top = -1, bottom = -1, bar_x0 = -1, bar_x1 = -1;
	for (int y = 0; y < bar.height; y++)
		for (int x = plain.width; x < bar.width; x++) {
			if (!memcmp(rgb_at(&bar, x, y), lut[255], 3) && top < 0)
				top = y, bar_x0 = x;
			if (!memcmp(rgb_at(&bar, x, y), lut[0], 3))
				bottom = y;
		}
	CHECK(top >= 0 && top < bar.height / 4 && bottom > 3 * bar.height / 4,
	      "zmax's colour at the top (row %d), zmin's at the bottom (row %d)", top, bottom);
	if (top < 0 || bottom < 0)
		goto out;
	for (bar_x1 = bar_x0; bar_x1 < bar.width && !memcmp(rgb_at(&bar, bar_x1, top), lut[255], 3);
	     bar_x1++)
		;
	CHECK(is_rgb(rgb_at(&bar, bar_x0 - 1, (top + bottom) / 2), 0, 0, 0) &&
	      is_rgb(rgb_at(&bar, bar_x1, (top + bottom) / 2), 0, 0, 0) &&
	      is_rgb(rgb_at(&bar, (bar_x0 + bar_x1) / 2, top - 1), 0, 0, 0) &&
	      is_rgb(rgb_at(&bar, (bar_x0 + bar_x1) / 2, bottom + 1), 0, 0, 0),
	      "a black frame round the bar");
	/* Right of the frame, in each row: a tick (black run from the frame),
	 * a white gap of at least 3 px, then the label's first pixels. */
	int ticks = 0, close = 0, labelled_top = 0, labelled_bottom = 0;
	for (int y = top - 1; y <= bottom + 1; y++) {
		int x = bar_x1 + 1;
		if (!is_rgb(rgb_at(&bar, x, y), 0, 0, 0))
			continue;
		ticks++;
		while (x < bar.width && is_rgb(rgb_at(&bar, x, y), 0, 0, 0))
			x++;
		const int gap0 = x;
		while (x < bar.width && is_rgb(rgb_at(&bar, x, y), 255, 255, 255))
			x++;
		close += x < bar.width && x - gap0 < 3;
	}
	for (int y = 0; y < bar.height; y++)
		for (int x = bar_x1 + 4; x < bar.width; x++)
			if (is_rgb(rgb_at(&bar, x, y), 0, 0, 0)) {
				labelled_top |= abs(y - top) <= 3;
				labelled_bottom |= abs(y - bottom) <= 3;
			}
	CHECK(ticks >= 3 && close == 0, "%d tick rows, %d closer than 3 px to their label",
	      ticks, close);
	CHECK(labelled_top && labelled_bottom, "both ends labelled: top %d, bottom %d",
	      labelled_top, labelled_bottom);
out:
	ss_render_image_release(&bar);
	ss_render_image_release(&plain);
	field_release(&t);
}

/* A grid side that is a wall is drawn as one, outside the map, in the
 * walls' colour; the map itself is the same pixels. */
static void test_wall_sides_drawn(void)
{
	struct field t;
	field_init(&t, 60, 40);
	for (int j = 0; j < 40; j++)
		for (int i = 0; i < 60; i++)
			*H(&t, i, j) = 0.01 * i + 0.002 * j;
	struct ss_render_options o;
	ss_render_options_default(&o);
	struct ss_render_image open, walled;
	CHECK(ss_render_field(&t.f, &o, &open) == SS_OK, "render");
	t.f.wall_sides = 1u << SS_WEST | 1u << SS_NORTH;
	CHECK(ss_render_field(&t.f, &o, &walled) == SS_OK, "render");
	const int bw = walled.width - open.width, bn = walled.height - open.height;
	CHECK(bw >= 9 && bw == bn, "a wall of at least a cell (9 px) west and north: %d, %d", bw,
	      bn);
	int wall = 1, same = 1;
	for (int y = 0; y < walled.height; y++)
		for (int x = 0; x < walled.width; x++) {
			const uint8_t *p = rgb_at(&walled, x, y);
			if (x < bw || y < bn)
				wall &= is_rgb(p, SS_RENDER_WALL_RGB);
			else
				same &= !memcmp(p, rgb_at(&open, x - bw, y - bn), 3);
		}
	CHECK(wall, "the west and north strips are wall coloured");
	CHECK(same, "the map is the same pixels beside them");
	ss_render_image_release(&open);
	ss_render_image_release(&walled);
	field_release(&t);
}

/* A plane with walls inside and along its sides shades as one face: no
 * band of other brightness along the edges or the walls, enlarged (the
 * half cell beyond the last cell centre) or one pixel per cell.  The
 * height scale lies below the plane, so every sand pixel has the map's
 * top colour and differs only by its shading. */
static void test_no_shading_band(void)
{
	struct field t;
	field_init(&t, 30, 20);
	for (int j = 0; j < 20; j++)
		for (int i = 0; i < 30; i++) {
			*H(&t, i, j) = 1.0 + 0.02 * i - 0.013 * j;
			if (i >= 12 && i < 16 && j >= 5 && j < 14)
				*T(&t, i, j) = SS_CELL_WALL;
		}
	t.f.wall_sides = 1u << SS_WEST | 1u << SS_NORTH;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.zmin = -2.0;
	o.zmax = -1.0;
	for (int scale = 1; scale <= 7; scale += 6) {
		o.scale = scale;
		struct ss_render_image img;
		CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "render");
		uint8_t first[3] = {0, 0, 0};
		int n = 0, differ = 0, worst = 0;
		for (int y = 0; y < img.height; y++)
			for (int x = 0; x < img.width; x++) {
				const uint8_t *p = rgb_at(&img, x, y);
				if (is_rgb(p, SS_RENDER_WALL_RGB))
					continue;
				if (!n++)
					memcpy(first, p, 3);
				const int d = abs(p[0] - first[0]) + abs(p[1] - first[1]) + abs(p[2] - first[2]);
				differ += d > 1;
				worst = d > worst ? d : worst;
			}
		CHECK(n > 500 && differ == 0, "%d px a cell: %d of %d sand pixels shade differently "
		      "(by up to %d levels)", scale, differ, n, worst);
		ss_render_image_release(&img);
	}
	field_release(&t);
}

/* ---- oblique ---------------------------------------------------------- */

/* Pixels that differ between two pictures of the same size: count and
 * centroid. */
static int diff_centroid(const struct ss_render_image *a, const struct ss_render_image *b,
                         double *cx, double *cy)
{
	int n = 0;
	double sx = 0.0, sy = 0.0;
	for (int y = 0; y < a->height; y++)
		for (int x = 0; x < a->width; x++)
			if (memcmp(rgb_at(a, x, y), rgb_at(b, x, y), 3)) {
				n++;
				sx += x;
				sy += y;
			}
	*cx = n ? sx / n / a->width : NAN;
	*cy = n ? sy / n / a->height : NAN;
	return n;
}

/* A single raised block of sand in the north-east quarter, seen from the
 * south, shows in the upper right of the picture; a wall block in the
 * south-west in the lower left, in grey.  The picture is the same bits
 * twice and on 1 and 2 threads. */
static void test_oblique_block(void)
{
	struct field flat, block, wall;
	field_init(&flat, 60, 60);
	field_init(&block, 60, 60);
	field_init(&wall, 60, 60);
	for (int j = 0; j < 60; j++)
		for (int i = 0; i < 60; i++) {
			const int in_ne = i >= 40 && i < 50 && j >= 40 && j < 50;
			const int in_sw = i >= 10 && i < 20 && j >= 10 && j < 20;
			*H(&block, i, j) = in_ne ? 0.3 : 0.0;
			if (in_sw)
				*T(&wall, i, j) = SS_CELL_WALL;
		}
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_OBLIQUE;
	o.zmin = 0.0;
	o.zmax = 0.3;
	o.view_azimuth_deg = 180.0;
	o.view_elevation_deg = 50.0;
	struct ss_render_image a, b, c;
	CHECK(ss_render_field(&flat.f, &o, &a) == SS_OK && ss_render_field(&block.f, &o, &b) == SS_OK &&
	      ss_render_field(&wall.f, &o, &c) == SS_OK, "render");
	CHECK(a.width == b.width && a.height == b.height && a.width == c.width,
	      "the camera depends on the grid and scale only");
	double cx, cy;
	int n = diff_centroid(&a, &b, &cx, &cy);
	CHECK(n > 2000, "the block changes the picture: %d pixels", n);
	CHECK(cx > 0.55 && cy < 0.5, "sand block in the upper right: centroid (%.2f, %.2f)", cx,
	      cy);
	n = diff_centroid(&a, &c, &cx, &cy);
	CHECK(n > 2000 && cx < 0.45 && cy > 0.45, "wall block in the lower left: %d px at (%.2f, "
	      "%.2f)", n, cx, cy);
	int grey = 0, total = 0;
	for (int y = 0; y < c.height; y++)
		for (int x = 0; x < c.width; x++)
			if (memcmp(rgb_at(&a, x, y), rgb_at(&c, x, y), 3)) {
				const uint8_t *p = rgb_at(&c, x, y);
				total++;
				grey += abs(p[0] - p[1]) < 12 && abs(p[1] - p[2]) < 16;
			}
	CHECK(grey > 0.9 * total, "the wall block is grey: %d of %d", grey, total);

	/* deterministic: again, and on 1 and 2 threads (b had the default) */
	struct ss_render_image again;
	CHECK(ss_render_field(&block.f, &o, &again) == SS_OK, "render");
	CHECK(!memcmp(again.pixels, b.pixels, b.row_bytes * b.height), "same bits twice");
	ss_render_image_release(&again);
	const int threads = ss_parallel_max_threads();
	for (int t = 1; t <= 2; t++) {
		ss_parallel_set_threads(t);
		CHECK(ss_render_field(&block.f, &o, &again) == SS_OK, "render");
		CHECK(!memcmp(again.pixels, b.pixels, b.row_bytes * b.height),
		      "same bits on %d and %d threads", t, threads);
		ss_render_image_release(&again);
	}
	ss_parallel_set_threads(threads);
	if (!CHECK_OPENMP)
		CHECK_SKIP("1 thread against 2: this build has no OpenMP (OPENMP=0)");
	ss_render_image_release(&a);
	ss_render_image_release(&b);
	ss_render_image_release(&c);
	field_release(&flat);
	field_release(&block);
	field_release(&wall);
}

/* Walls are drawn a little taller than the sand beside them, not as tall
 * as the scale: a wall block among sand at 0.1 m of a 0 .. 1 m scale
 * (with a pile of 0.9 m in a far corner) seen from the south at 45
 * degrees changes a region about as tall as it is wide: its top and a
 * side 0.06 m tall.  Up to the scale's top (1.06 m) it would be six times
 * taller than wide. */
static void test_oblique_walls_follow_sand(void)
{
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_OBLIQUE;
	o.zmin = 0.0;
	o.zmax = 1.0;
	o.view_azimuth_deg = 180.0;
	o.view_elevation_deg = 45.0;
	struct field bare, walled;
	field_init(&bare, 60, 60);
	field_init(&walled, 60, 60);
	for (int j = 0; j < 60; j++)
		for (int i = 0; i < 60; i++) {
			*H(&bare, i, j) = *H(&walled, i, j) = i >= 52 && j >= 52 ? 0.9 : 0.1;
			if (i >= 25 && i < 35 && j >= 20 && j < 30)
				*T(&walled, i, j) = SS_CELL_WALL;
		}
	struct ss_render_image a, b;
	CHECK(ss_render_field(&bare.f, &o, &a) == SS_OK &&
	      ss_render_field(&walled.f, &o, &b) == SS_OK, "render");
	int x0 = a.width, x1 = -1, y0 = a.height, y1 = -1;
	for (int y = 0; y < a.height; y++)
		for (int x = 0; x < a.width; x++)
			if (memcmp(rgb_at(&a, x, y), rgb_at(&b, x, y), 3)) {
				x0 = x < x0 ? x : x0, x1 = x > x1 ? x : x1;
				y0 = y < y0 ? y : y0, y1 = y > y1 ? y : y1;
			}
	CHECK(x1 > x0 && y1 - y0 < 2 * (x1 - x0),
	      "the wall block changes %d rows of %d columns: a low wall", y1 - y0 + 1, x1 - x0 + 1);
	ss_render_image_release(&a);
	ss_render_image_release(&b);
	field_release(&bare);
	field_release(&walled);
}

/* Pixels of a picture that are neither white (sky) nor grey (walls). */
static int coloured_pixels(const struct ss_render_image *img)
{
	int n = 0;
	for (int y = 0; y < img->height; y++)
		for (int x = 0; x < img->width; x++) {
			const uint8_t *p = rgb_at(img, x, y);
			const int lo = p[0] < p[1] ? (p[0] < p[2] ? p[0] : p[2]) : (p[1] < p[2] ? p[1] : p[2]);
			const int hi = p[0] > p[1] ? (p[0] > p[2] ? p[0] : p[2]) : (p[1] > p[2] ? p[1] : p[2]);
			n += hi - lo > 30;
		}
	return n;
}

/* A grid side that is a wall follows the sand along it, a little above:
 * walls on all four sides of sand at 0.1 m round a pile of 0.9 m hide
 * little of it (as tall as the pile, the near wall would hide most). */
static void test_oblique_wall_sides_follow_sand(void)
{
	struct field t;
	field_init(&t, 60, 40);
	for (int j = 0; j < 40; j++)
		for (int i = 0; i < 60; i++)
			*H(&t, i, j) = 0.1 + 0.8 * exp(-(pow(i - 30, 2) + pow(j - 20, 2)) / 50.0);
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_OBLIQUE;
	o.view_azimuth_deg = 180.0;
	o.view_elevation_deg = 40.0;
	struct ss_render_image open, walled;
	CHECK(ss_render_field(&t.f, &o, &open) == SS_OK, "render");
	t.f.wall_sides = 0xf;
	CHECK(ss_render_field(&t.f, &o, &walled) == SS_OK, "render");
	const int a = coloured_pixels(&open), b = coloured_pixels(&walled);
	CHECK(b > 0.85 * a, "walls all round leave %d of %d sand pixels in view", b, a);
	ss_render_image_release(&open);
	ss_render_image_release(&walled);
	field_release(&t);
}

/* Without --view-azimuth the camera looks from the open side: walls on
 * the west put it east-south-east (120), on the east west-north-west
 * (300); with no walls, 200 as before. */
static void test_oblique_view_from_open_side(void)
{
	struct field t;
	field_init(&t, 40, 30);
	for (int j = 0; j < 30; j++)
		for (int i = 0; i < 40; i++)
			*H(&t, i, j) = 0.1 + 0.004 * i + 0.002 * j;
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.style = SS_RENDER_OBLIQUE;
	const unsigned sides[3] = {1u << SS_WEST, 1u << SS_EAST, 0};
	const double bearing[3] = {120.0, 300.0, 200.0};
	for (int k = 0; k < 3; k++) {
		t.f.wall_sides = sides[k];
		struct ss_render_options given = o;
		given.view_azimuth_deg = bearing[k];
		struct ss_render_image a, b;
		CHECK(ss_render_field(&t.f, &o, &a) == SS_OK && ss_render_field(&t.f, &given, &b) ==
		      SS_OK, "render");
		CHECK(a.width == b.width && a.height == b.height &&
		      !memcmp(a.pixels, b.pixels, a.row_bytes * a.height),
		      "wall sides 0x%x: the default view is from %g degrees", sides[k], bearing[k]);
		ss_render_image_release(&a);
		ss_render_image_release(&b);
	}
	field_release(&t);
}

/* ---- the colour map and the options ----------------------------------- */

static double srgb_to_linear(double c)
{
	return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static double lightness(const uint8_t p[3])
{
	const double y = 0.2126729 * srgb_to_linear(p[0] / 255.0) +
	                 0.7151522 * srgb_to_linear(p[1] / 255.0) +
	                 0.0721750 * srgb_to_linear(p[2] / 255.0);
	return y > 216.0 / 24389 ? 116.0 * cbrt(y) - 16.0 : y * 24389.0 / 27.0;
}

/* dune is perceptually uniform in lightness: L* linear from 30 to 92. */
static void test_dune_lightness_linear(void)
{
	uint8_t lut[256][3];
	ss_render_cmap_table(SS_RENDER_CMAP_DUNE, lut);
	double worst = 0.0;
	for (int k = 0; k < 256; k++)
		worst = fmax(worst, fabs(lightness(lut[k]) - (30.0 + 62.0 * k / 255.0)));
	CHECK(worst < 0.6, "L* within %.2f of the line (8-bit rounding)", worst);
	CHECK(lut[0][2] > lut[0][1] && lut[255][0] > lut[255][2], "violet to yellow");
}

static void test_bad_options(void)
{
	struct ss_render_options o;
	ss_render_options_default(&o);
	CHECK(ss_render_options_check(&o) == SS_OK, "defaults are valid");
	o.zmin = 0.5;
	o.zmax = 0.5;
	CHECK(ss_render_options_check(&o) == SS_ERR_INPUT, "zmin >= zmax");
	ss_render_options_default(&o);
	o.style = SS_RENDER_GRAY16;
	o.label = 1;
	CHECK(ss_render_options_check(&o) == SS_ERR_INPUT, "a label on data");
	ss_render_options_default(&o);
	o.altitude_deg = 0.0;
	CHECK(ss_render_options_check(&o) == SS_ERR_INPUT, "light on the horizon");
	ss_render_options_default(&o);
	o.view_elevation_deg = 90.0;
	CHECK(ss_render_options_check(&o) == SS_ERR_INPUT, "camera straight overhead");

	/* only zmin given, above all the heights */
	struct field t;
	field_init(&t, 4, 4);
	ss_render_options_default(&o);
	o.zmin = 1.0;
	struct ss_render_image img;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_ERR_INPUT, "--zmin above the data");
	field_release(&t);
}

/* Ink of a picture drawn on white: the rows and columns of pixels darker
 * than mid-grey. */
struct ink {
	int x0, y0, x1, y1;   /* inclusive; x0 > x1 when none */
};

static struct ink ink_of(const struct ss_render_image *img)
{
	struct ink k = {img->width, img->height, -1, -1};
	for (int y = 0; y < img->height; y++)
		for (int x = 0; x < img->width; x++)
			if (rgb_at(img, x, y)[0] < 128) {
				k.x0 = x < k.x0 ? x : k.x0;
				k.x1 = x > k.x1 ? x : k.x1;
				k.y0 = y < k.y0 ? y : k.y0;
				k.y1 = y > k.y1 ? y : k.y1;
			}
	return k;
}

/* text in a picture of its own: w x h px of white, drawn at (0, 0) */
static struct ink ink_of_text(const struct ss_render_font *f, const char *text, int up)
{
	struct ss_render_image img;
	static const uint8_t black[3] = {0, 0, 0};
	struct ink k = {1, 1, 0, 0};
	const int line = ss_render_font_line(f), w = ss_render_text_width(f, text);
	if (ss_render_image_init(&img, up ? line : w, up ? w : line, 3, 8))
		return k;
	memset(img.pixels, 0xff, img.row_bytes * (size_t)img.height);
	if (up)
		ss_render_draw_text_up(&img, f, 0, 0, text, black);
	else
		ss_render_draw_text(&img, f, 0, 0, text, black);
	k = ink_of(&img);
	ss_render_image_release(&img);
	return k;
}

/*
 * The font has descenders (the 5 x 7 bitmap font before issue 36 drew
 * "g" within the line's height: "bin9ham"): a g reaches below the
 * baseline, by a sixth of the em or more, and ends inside its line box, as
 * do p and y; an o stays on the baseline.  Turned to read upwards, the
 * same g's descender points right, away from the tops.
 */
static void test_font_descenders(void)
{
	struct ss_render_font *f = NULL;
	CHECK(ss_render_font_create(&f, 20) == SS_OK, "the font at 20 px (%s)",
	      ss_render_font_file());
	if (!f)
		return;
	const int base = ss_render_font_ascent(f), line = ss_render_font_line(f);
	const struct ink g = ink_of_text(f, "g", 0), o = ink_of_text(f, "o", 0);
	/* the baseline runs between rows base - 1 and base */
	CHECK(g.y1 - base + 1 >= 20 / 6 && g.y1 < line,
	      "g's ink reaches %d rows below the baseline (above row %d), inside its line of "
	      "%d px", g.y1 - base + 1, base, line);
	CHECK(o.y1 <= base && o.y1 >= base - 1, "o sits on the baseline (row %d): it ends at %d",
	      base, o.y1);
	CHECK(g.y0 >= o.y0 - 1 && g.y0 <= o.y0 + 1, "g and o start at the x-height: rows %d, %d",
	      g.y0, o.y0);
	const struct ink py = ink_of_text(f, "py", 0), bingham = ink_of_text(f, "bingham", 0);
	CHECK(py.y1 - base + 1 >= 20 / 6, "p and y descend too: to row %d", py.y1);
	CHECK(bingham.y1 == g.y1 && bingham.y0 < g.y0,
	      "\"bingham\": the g's descender and the b's ascender: rows %d..%d", bingham.y0,
	      bingham.y1);
	const struct ink up = ink_of_text(f, "g", 1);
	CHECK(up.x1 == g.y1 && up.x0 == g.y0, "turned up: the g's rows become columns %d..%d "
	      "(%d..%d)", up.x0, up.x1, g.y0, g.y1);
	/* kerning and advances: a wider text is wider */
	CHECK(ss_render_text_width(f, "bingham") > ss_render_text_width(f, "binham"),
	      "text widths add up");
	ss_render_font_destroy(f);
	ss_render_font_destroy(NULL);
}

/* Without the font file, a picture with text is refused with one line
 * naming the file, where its name came from and the package to install;
 * one without text needs no font. */
static void test_font_missing(void)
{
	const char *was = getenv("SANDSLIDE_FONT");
	char saved[4096] = "";
	if (was)
		snprintf(saved, sizeof saved, "%s", was);
	setenv("SANDSLIDE_FONT", "/nonexistent/DejaVuSans.ttf", 1);
	struct field t;
	field_init(&t, 8, 8);
	struct ss_render_options o;
	ss_render_options_default(&o);
	struct ss_render_image img = {0};
	ss_error_set_quiet(1);
	o.label = 1;
	const int status = ss_render_field(&t.f, &o, &img);
	const char *m = ss_error_last_message();
	CHECK(status == SS_ERR_FAIL && strstr(m, "'/nonexistent/DejaVuSans.ttf'") &&
	          strstr(m, "SANDSLIDE_FONT") && strstr(m, "fonts-dejavu-core") && !strchr(m, '\n'),
	      "a label without the font: status %d, \"%s\"", status, m);
	if (status == SS_OK)
		ss_render_image_release(&img);
	ss_error_set_quiet(0);
	o.label = 0;
	CHECK(ss_render_field(&t.f, &o, &img) == SS_OK, "no text, no font needed");
	ss_render_image_release(&img);
	if (was)
		setenv("SANDSLIDE_FONT", saved, 1);
	else
		unsetenv("SANDSLIDE_FONT");
	field_release(&t);
}

/* A failed write leaves neither the picture nor its temporary file. */
static void test_write_failure_leaves_nothing(void)
{
	struct ss_render_image img;
	CHECK(ss_render_image_init(&img, 8, 8, 3, 8) == SS_OK, "init");
	memset(img.pixels, 0x80, img.row_bytes * img.height);
	char path[512];
	snprintf(path, sizeof path, "%s/missing-folder/frame.png", tmpdir);
	CHECK(ss_render_write_png(&img, path, 6) != SS_OK, "no folder: an error");
	CHECK(access(path, F_OK) != 0, "no picture");
	snprintf(path, sizeof path, "%s/ok.png", tmpdir);
	CHECK(ss_render_write_png(&img, path, 6) == SS_OK, "write");
	char partial[600];
	snprintf(partial, sizeof partial, "%s.partial", path);
	CHECK(access(path, F_OK) == 0 && access(partial, F_OK) != 0,
	      "the picture under its name, no temporary left");
	ss_render_image_release(&img);
}

/* ---- cells without data ------------------------------------------------ */

/* Is p a lit face of an oblique wall: 8c 8c 96 (oblique.c) times a
 * brightness, red and green equal and blue a little above? */
static int wall_grey(const uint8_t *p)
{
	return p[0] == p[1] && p[2] > p[1] && p[2] - p[1] <= 12;
}

/*
 * Cells without data (SS_RENDER_CELL_NODATA: a DEM's nodata round its
 * outline) are absent in every style: the background (white) in shaded
 * and oblique, 0 (transparent) in gray16, never a wall; their heights
 * (1000 m here) reach no colour, no gradient and not the height scale; a
 * wall side with no data all along it is not drawn.  The same field with
 * walls there instead is the check that each property can fail.
 */
static void test_nodata_cells_are_absent(void)
{
	const int n = 40;
	struct field t, w;
	field_init(&t, n, n);
	field_init(&w, n, n);
	int cells_without = 0;
	for (int j = 0; j < n; j++)
		for (int i = 0; i < n; i++) {
			const int inside = hypot(i + 0.5 - 20.0, j + 0.5 - 20.0) < 15.0;
			*H(&t, i, j) = *H(&w, i, j) = inside ? 1.0 : 1000.0;
			*T(&t, i, j) = inside ? SS_CELL_FLOW : SS_RENDER_CELL_NODATA;
			*T(&w, i, j) = inside ? SS_CELL_FLOW : SS_CELL_WALL;
			cells_without += !inside;
		}
	t.f.wall_sides = w.f.wall_sides = 0xf;   /* relax's sides are walls */
	struct ss_render_options o;
	ss_render_options_default(&o);
	struct ss_render_image a, b;

	/* shaded: white where there is no data, one colour on the flat sand */
	CHECK(ss_render_field(&t.f, &o, &a) == SS_OK && ss_render_field(&w.f, &o, &b) == SS_OK,
	      "render shaded");
	int pw, ph;
	ss_render_picture_size(n, n, t.f.dx, t.f.dy, &o, &pw, &ph);
	CHECK(a.width == pw && a.height == ph, "no wall side drawn along sides without data: "
	      "%d x %d px, the map is %d x %d", a.width, a.height, pw, ph);
	CHECK(b.width > pw && b.height > ph, "with walls there, the wall sides are drawn");
	CHECK(a.zmin == 0.5 && a.zmax == 1.5, "the scale is the flat sand's, widened: %g .. %g "
	      "(1000 m of the cells without data must not enter it)", a.zmin, a.zmax);
	const uint8_t *sand = rgb_at(&a, a.width / 2, a.height / 2), *corner = rgb_at(&a, 0, 0);
	CHECK(corner[0] == 255 && corner[1] == 255 && corner[2] == 255,
	      "a cell without data is the white background: (%d, %d, %d)", corner[0], corner[1],
	      corner[2]);
	int white = 0, other = 0;
	for (int y = 0; y < a.height; y++)
		for (int x = 0; x < a.width; x++) {
			const uint8_t *p = rgb_at(&a, x, y);
			if (p[0] == 255 && p[1] == 255 && p[2] == 255)
				white++;
			else
				other += memcmp(p, sand, 3) != 0;
		}
	CHECK(other == 0, "%d pixels of the flat sand differ from its colour: the cells without "
	      "data leaked into the shading", other);
	CHECK(white > 0.3 * a.width * a.height, "cells without data are white: %d px", white);
	ss_render_image_release(&a);
	ss_render_image_release(&b);

	/* gray16: 0, transparent, as walls are */
	o.style = SS_RENDER_GRAY16;
	CHECK(ss_render_field(&t.f, &o, &a) == SS_OK, "render gray16");
	int zeros = 0;
	for (int y = 0; y < a.height; y++)
		for (int x = 0; x < a.width; x++)
			zeros += ((const uint16_t *)(a.pixels + (size_t)y * a.row_bytes))[x] == 0;
	CHECK(a.width == n && zeros == cells_without, "gray16: %d zero (transparent) pixels, "
	      "%d cells without data", zeros, cells_without);
	ss_render_image_release(&a);

	/* oblique: no grey wall anywhere, where the walls make plenty */
	ss_render_options_default(&o);
	o.style = SS_RENDER_OBLIQUE;
	o.zmin = 0.0;
	o.zmax = 2.0;
	o.view_azimuth_deg = 200.0;
	CHECK(ss_render_field(&t.f, &o, &a) == SS_OK && ss_render_field(&w.f, &o, &b) == SS_OK,
	      "render oblique");
	int grey_a = 0, grey_b = 0, white_a = 0, white_b = 0;
	for (int y = 0; y < a.height; y++)
		for (int x = 0; x < a.width; x++) {
			const uint8_t *p = rgb_at(&a, x, y);
			grey_a += wall_grey(p);
			white_a += p[0] == 255 && p[1] == 255 && p[2] == 255;
		}
	for (int y = 0; y < b.height; y++)
		for (int x = 0; x < b.width; x++) {
			const uint8_t *p = rgb_at(&b, x, y);
			grey_b += wall_grey(p);
			white_b += p[0] == 255 && p[1] == 255 && p[2] == 255;
		}
	CHECK(grey_a == 0, "oblique: %d grey wall pixels where cells have no data", grey_a);
	CHECK(grey_b > 1000, "oblique: the same cells as walls make grey blocks: %d px", grey_b);
	CHECK(white_a > white_b + 1000, "oblique: the cells without data show the background: "
	      "%d white px, %d with walls there", white_a, white_b);
	struct ss_render_image again;
	const int threads = ss_parallel_max_threads();
	ss_parallel_set_threads(1);
	CHECK(ss_render_field(&t.f, &o, &again) == SS_OK, "render");
	ss_parallel_set_threads(threads);
	CHECK(again.width == a.width && again.height == a.height &&
	      !memcmp(again.pixels, a.pixels, a.row_bytes * a.height),
	      "oblique with cells without data: same bits on 1 and %d threads", threads);
	ss_render_image_release(&again);
	ss_render_image_release(&a);
	ss_render_image_release(&b);
	field_release(&t);
	field_release(&w);
}

int main(void)
{
	const char *base = getenv("TMPDIR");
	snprintf(tmpdir, sizeof tmpdir, "%s/test_render.XXXXXX", base && *base ? base : "/tmp");
	if (!mkdtemp(tmpdir)) {
		perror("mkdtemp");
		return 1;
	}
	RUN(test_gray16_round_trip);
	RUN(test_gray16_default_scale);
	RUN(test_max_size_area_average);
	RUN(test_shaded_flat_uniform);
	RUN(test_shaded_tilt_towards_light);
	RUN(test_shaded_wall_and_open_colours);
	RUN(test_picture_sizes);
	RUN(test_contours);
	RUN(test_label_and_colorbar);
	RUN(test_wall_sides_drawn);
	RUN(test_no_shading_band);
	RUN(test_oblique_block);
	RUN(test_oblique_walls_follow_sand);
	RUN(test_oblique_wall_sides_follow_sand);
	RUN(test_oblique_view_from_open_side);
	RUN(test_dune_lightness_linear);
	RUN(test_nodata_cells_are_absent);
	RUN(test_bad_options);
	RUN(test_write_failure_leaves_nothing);
	RUN(test_font_descenders);
	RUN(test_font_missing);
	char cmd[600];
	snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
	if (system(cmd) != 0)
		fprintf(stderr, "could not remove %s\n", tmpdir);
	return check_report();
}
