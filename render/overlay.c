/*
 * overlay.c - what is drawn over a picture: the time label and the colour
 * bar, in a built-in 5 x 7 bitmap font (so no font library or file is
 * needed), magnified by an integer for large pictures.
 *
 * The font has the digits, the lower-case letters (upper case is drawn as
 * lower case) and . , - + = : / ( ) %; anything else is a hollow box.
 */
#include "internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define GLYPH_W 5
#define GLYPH_H 7
#define ADVANCE 6               /* glyph and one column of space */

struct glyph {
	char c;
	const char *rows[GLYPH_H];
};

static const struct glyph font[] = {
	{'0', {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
	{'1', {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
	{'2', {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}},
	{'3', {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}},
	{'4', {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}},
	{'5', {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
	{'6', {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}},
	{'7', {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}},
	{'8', {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}},
	{'9', {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}},
	{'a', {".....", ".....", ".###.", "....#", ".####", "#...#", ".####"}},
	{'b', {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "####."}},
	{'c', {".....", ".....", ".###.", "#....", "#....", "#...#", ".###."}},
	{'d', {"....#", "....#", ".##.#", "#..##", "#...#", "#...#", ".####"}},
	{'e', {".....", ".....", ".###.", "#...#", "#####", "#....", ".###."}},
	{'f', {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#..."}},
	{'g', {".....", ".####", "#...#", "#...#", ".####", "....#", ".###."}},
	{'h', {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
	{'i', {"..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."}},
	{'j', {"...#.", ".....", "..##.", "...#.", "...#.", "#..#.", ".##.."}},
	{'k', {"#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."}},
	{'l', {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
	{'m', {".....", ".....", "##.#.", "#.#.#", "#.#.#", "#...#", "#...#"}},
	{'n', {".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
	{'o', {".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."}},
	{'p', {".....", ".....", "####.", "#...#", "####.", "#....", "#...."}},
	{'q', {".....", ".....", ".##.#", "#..##", ".####", "....#", "....#"}},
	{'r', {".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."}},
	{'s', {".....", ".....", ".###.", "#....", ".###.", "....#", "####."}},
	{'t', {".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##."}},
	{'u', {".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#"}},
	{'v', {".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
	{'w', {".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#."}},
	{'x', {".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"}},
	{'y', {".....", ".....", "#...#", "#...#", ".####", "....#", ".###."}},
	{'z', {".....", ".....", "#####", "...#.", "..#..", ".#...", "#####"}},
	{'.', {".....", ".....", ".....", ".....", ".....", ".##..", ".##.."}},
	{',', {".....", ".....", ".....", ".....", ".##..", "..#..", ".#..."}},
	{'-', {".....", ".....", ".....", "#####", ".....", ".....", "....."}},
	{'+', {".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."}},
	{'=', {".....", ".....", "#####", ".....", "#####", ".....", "....."}},
	{':', {".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."}},
	{'/', {".....", "....#", "...#.", "..#..", ".#...", "#....", "....."}},
	{'(', {"...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."}},
	{')', {".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."}},
	{'%', {"##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"}},
	{' ', {".....", ".....", ".....", ".....", ".....", ".....", "....."}},
};

static const struct glyph unknown = {
	'?', {"#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"}};

static const struct glyph *glyph_of(char c)
{
	c = (char)tolower((unsigned char)c);
	for (size_t k = 0; k < sizeof font / sizeof font[0]; k++)
		if (font[k].c == c)
			return &font[k];
	return &unknown;
}

int ss_render_font_scale(int w, int h)
{
	const int m = w < h ? w : h;
	const int s = (m + 120) / 240;   /* a line of text about 1/30 of the picture */
	return s < 1 ? 1 : s;
}

int ss_render_text_width(const char *text, int scale)
{
	const int n = (int)strlen(text);
	return n ? (n * ADVANCE - 1) * scale : 0;
}

static void put(struct ss_render_image *img, int x, int y, const uint8_t rgb[3])
{
	if (x < 0 || y < 0 || x >= img->width || y >= img->height)
		return;
	uint8_t *p = img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
	p[0] = rgb[0], p[1] = rgb[1], p[2] = rgb[2];
}

void ss_render_draw_text(struct ss_render_image *img, int x, int y, int scale,
                         const char *text, const uint8_t rgb[3])
{
	for (; *text; text++, x += ADVANCE * scale) {
		const struct glyph *g = glyph_of(*text);
		for (int r = 0; r < GLYPH_H; r++)
			for (int c = 0; c < GLYPH_W; c++)
				if (g->rows[r][c] == '#')
					for (int v = 0; v < scale; v++)
						for (int u = 0; u < scale; u++)
							put(img, x + c * scale + u, y + r * scale + v, rgb);
	}
}

/* Darken a box to `keep` of its colour, so light text on it reads over
 * any map colour. */
static void darken_box(struct ss_render_image *img, int x0, int y0, int x1, int y1,
                       double keep)
{
	for (int y = y0 < 0 ? 0 : y0; y < y1 && y < img->height; y++)
		for (int x = x0 < 0 ? 0 : x0; x < x1 && x < img->width; x++) {
			uint8_t *p = img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
			for (int c = 0; c < 3; c++)
				p[c] = (uint8_t)(p[c] * keep + 0.5);
		}
}

void ss_render_draw_label(struct ss_render_image *img, int pic_w, int pic_h, double time)
{
	const int k = ss_render_font_scale(pic_w, pic_h), pad = 2 * k;
	char text[64];
	snprintf(text, sizeof text, "t = %g s", time);
	const int w = ss_render_text_width(text, k), h = GLYPH_H * k;
	static const uint8_t white[3] = {255, 255, 255};
	darken_box(img, pad, pad, pad + w + 2 * pad, pad + h + 2 * pad, 0.35);
	ss_render_draw_text(img, 2 * pad, 2 * pad, k, text, white);
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

/* Layout of the strip, in multiples of the font scale k. */
struct bar_layout {
	int k, margin, bar_w, text_w;
};

static struct bar_layout bar_layout(int pic_w, int pic_h, double zmin, double zmax)
{
	struct bar_layout l;
	l.k = ss_render_font_scale(pic_w, pic_h);
	l.margin = 4 * l.k;
	l.bar_w = 5 * l.k;
	l.text_w = ss_render_text_width("m", l.k);
	const double step = tick_step(zmin, zmax);
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		char s[32];
		ss_render_format_height(z, step, s, sizeof s);
		const int w = ss_render_text_width(s, l.k);
		if (w > l.text_w)
			l.text_w = w;
	}
	return l;
}

int ss_render_colorbar_width(int pic_w, int pic_h, double zmin, double zmax)
{
	const struct bar_layout l = bar_layout(pic_w, pic_h, zmin, zmax);
	return 3 * l.margin + l.bar_w + 2 * l.k + l.text_w;
}

void ss_render_draw_colorbar(struct ss_render_image *img, int x0, int pic_h,
                             enum ss_render_cmap cmap, double zmin, double zmax)
{
	const struct bar_layout l = bar_layout(x0, pic_h, zmin, zmax);
	static const uint8_t black[3] = {0, 0, 0};
	uint8_t lut[256][3];
	ss_render_cmap_table(cmap, lut);

	for (int y = 0; y < img->height; y++)   /* white strip */
		memset(img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x0,
		       SS_RENDER_BACKGROUND, 3 * (size_t)(img->width - x0));

	const int bx = x0 + l.margin, top = 2 * l.margin + GLYPH_H * l.k;
	const int bottom = pic_h - l.margin - GLYPH_H * l.k / 2 - 1;
	if (bottom - top < 2)
		return;   /* a picture too small for a bar */
	ss_render_draw_text(img, bx, l.margin, l.k, "m", black);
	for (int y = top; y <= bottom; y++) {
		const double z = zmax - (double)(y - top) / (bottom - top) * (zmax - zmin);
		const uint8_t *c = lut[ss_render_cmap_index(z, zmin, zmax)];
		for (int x = bx; x < bx + l.bar_w; x++)
			put(img, x, y, c);
	}
	const double step = tick_step(zmin, zmax);
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		const int y = top + (int)lround((zmax - z) / (zmax - zmin) * (bottom - top));
		char s[32];
		ss_render_format_height(z, step, s, sizeof s);
		for (int x = bx + l.bar_w; x < bx + l.bar_w + l.k + 1; x++)
			for (int v = 0; v < (l.k + 1) / 2; v++)
				put(img, x, y + v, black);
		ss_render_draw_text(img, bx + l.bar_w + 2 * l.k + l.margin / 2, y - GLYPH_H * l.k / 2,
		                    l.k, s, black);
	}
}
