/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * overlay.c - what is drawn over a picture: the time label and the colour
 * bar, with their text in the renderer's font (text.c: DejaVu Sans through
 * FreeType), sized with the picture (ss_render_font_px).
 */
#include "internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const uint8_t black[3] = {0, 0, 0};

/* A quarter of the em, at least 2 px: the strip's padding above and
 * below its line of text. */
static int label_pad(const struct ss_render_font *f)
{
	const int p = ss_render_font_em(f) / 4;
	return p < 2 ? 2 : p;
}

int ss_render_label_height(const struct ss_render_font *f)
{
	return ss_render_font_line(f) + 2 * label_pad(f);
}

void ss_render_draw_label(struct ss_render_image *img, const struct ss_render_font *f,
                          int pic_w, double time)
{
	char text[64];
	snprintf(text, sizeof text, "t = %g s", time);
	for (int y = 0; y < ss_render_label_height(f) && y < img->height; y++)
		memset(img->pixels + (size_t)y * img->row_bytes, SS_RENDER_BACKGROUND,
		       3 * (size_t)(pic_w < img->width ? pic_w : img->width));
	ss_render_draw_text(img, f, ss_render_font_em(f) / 2, label_pad(f), text, black);
}

void ss_render_format_height(double z, double step, char *out, size_t size)
{
	int decimals = step > 0.0 ? (int)-floor(log10(step) + 1e-9) : 3;
	if (decimals < 0)
		decimals = 0;
	if (decimals > 9)
		decimals = 9;
	if (fabs(z) < 0.5 * step)
		z = 0.0;   /* no "-0.00" */
	snprintf(out, size, "%.*f", decimals, z);
}

/* Tick spacing: 1, 2 or 5 times a power of ten, about four ticks. */
static double tick_step(double zmin, double zmax)
{
	const double raw = (zmax - zmin) / 4.0;
	const double mag = pow(10.0, floor(log10(raw)));
	const double n = raw / mag;
	return (n < 1.5 ? 1.0 : n < 3.5 ? 2.0 : n < 7.5 ? 5.0 : 10.0) * mag;
}

/* An end of the scale that is not a tick is labelled one digit finer
 * than the ticks ("0.80" at the top of ticks 0.0 .. 0.6). */
static void end_label(double z, double step, char *out, size_t size)
{
	const double q = z / step;
	ss_render_format_height(z, fabs(q - round(q)) < 1e-9 ? step : step / 10.0, out, size);
}

/*
 * Layout of the strip, from the font's em:
 *
 *     margin | bar (framed) | tick | gap | labels | margin
 *
 * The ticks stick out of the bar's frame, and a gap of a quarter em (at
 * least 4 px) separates them from the labels, so a tick never reads as a
 * minus sign.
 */
struct bar_layout {
	int em, margin, bar_w, tick, gap, text_w;
};

static int at_least(int v, int lo)
{
	return v < lo ? lo : v;
}

static struct bar_layout bar_layout(const struct ss_render_font *f, double zmin, double zmax)
{
	struct bar_layout l;
	l.em = ss_render_font_em(f);
	l.margin = at_least(l.em / 3, 4);
	l.bar_w = at_least(l.em / 2, 5);
	l.tick = at_least(l.em / 5, 2);
	l.gap = at_least(l.em / 4, 4);
	l.text_w = ss_render_text_width(f, "m");
	const double step = tick_step(zmin, zmax);
	char s[32];
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		ss_render_format_height(z, step, s, sizeof s);
		l.text_w = fmax(l.text_w, ss_render_text_width(f, s));
	}
	for (int end = 0; end < 2; end++) {
		end_label(end ? zmax : zmin, step, s, sizeof s);
		l.text_w = fmax(l.text_w, ss_render_text_width(f, s));
	}
	return l;
}

int ss_render_colorbar_width(const struct ss_render_font *f, double zmin, double zmax)
{
	const struct bar_layout l = bar_layout(f, zmin, zmax);
	return 2 * l.margin + l.bar_w + l.tick + l.gap + l.text_w;
}

/* Fill the box [x0, x1) x [y0, y1) of img with rgb, clipped to it. */
static void fill(struct ss_render_image *img, int x0, int y0, int x1, int y1,
                 const uint8_t rgb[3])
{
	for (int y = y0 < 0 ? 0 : y0; y < y1 && y < img->height; y++)
		for (int x = x0 < 0 ? 0 : x0; x < x1 && x < img->width; x++)
			memcpy(img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x, rgb, 3);
}

void ss_render_draw_colorbar(struct ss_render_image *img, const struct ss_render_font *f,
                             int x0, int y0, int pic_h, enum ss_render_cmap cmap, double zmin,
                             double zmax)
{
	const struct bar_layout l = bar_layout(f, zmin, zmax);
	uint8_t lut[256][3];
	ss_render_cmap_table(cmap, lut);

	for (int y = 0; y < img->height; y++)   /* white strip */
		memset(img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x0,
		       SS_RENDER_BACKGROUND, 3 * (size_t)(img->width - x0));

	/* a number's digits are centred on its tick: its line box starts
	 * ascent - digit_h / 2 above it */
	const int line = at_least((l.em + 8) / 16, 1), digit_h = ss_render_font_digit_height(f);
	const int centre = ss_render_font_ascent(f) - digit_h / 2;
	const int bx = x0 + l.margin, top = y0 + 2 * l.margin + ss_render_font_line(f);
	const int bottom = y0 + pic_h - l.margin - (digit_h + 1) / 2 - 1;
	if (bottom - top < 2 * ss_render_font_line(f))
		return;   /* a picture too small for a bar */
	ss_render_draw_text(img, f, bx, y0 + l.margin, "m", black);
	for (int y = top; y <= bottom; y++) {
		const double z = zmax - (double)(y - top) / (bottom - top) * (zmax - zmin);
		fill(img, bx, y, bx + l.bar_w, y + 1, lut[ss_render_cmap_index(z, zmin, zmax)]);
	}
	/* the frame: one line round the bar */
	fill(img, bx - line, top - line, bx + l.bar_w + line, top, black);
	fill(img, bx - line, bottom + 1, bx + l.bar_w + line, bottom + 1 + line, black);
	fill(img, bx - line, top, bx, bottom + 1, black);
	fill(img, bx + l.bar_w, top, bx + l.bar_w + line, bottom + 1, black);

	const int tick_x0 = bx + l.bar_w + line, text_x = tick_x0 + l.tick + l.gap;
	const double step = tick_step(zmin, zmax);
	char s[32];
	/* the ends, then the ticks between that leave room for their labels */
	for (int end = 0; end < 2; end++) {
		const int y = end ? top : bottom;
		end_label(end ? zmax : zmin, step, s, sizeof s);
		fill(img, tick_x0, y - line / 2, tick_x0 + l.tick, y - line / 2 + line, black);
		ss_render_draw_text(img, f, text_x, y - centre, s, black);
	}
	const int room = digit_h + l.em / 2;
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		const int y = top + (int)lround((zmax - z) / (zmax - zmin) * (bottom - top));
		if (y - top < room || bottom - y < room)
			continue;   /* an end's label is there */
		ss_render_format_height(z, step, s, sizeof s);
		fill(img, tick_x0, y - line / 2, tick_x0 + l.tick, y - line / 2 + line, black);
		ss_render_draw_text(img, f, text_x, y - centre, s, black);
	}
}
