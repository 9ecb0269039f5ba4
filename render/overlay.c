/*
 * overlay.c - what is drawn over a picture: the time label and the colour
 * bar, in a built-in 5 x 7 bitmap font (so no font library or file is
 * needed), magnified by an integer for large pictures.
 *
 * The font has the digits, the lower-case letters (upper case is drawn as
 * lower case), the space and . , - + = : / ( ) % _ ^ * [ ] < > ' ; ! ? |;
 * anything else is a hollow box.
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
	/* for the axis labels, titles and legends of plot.c */
	{'_', {".....", ".....", ".....", ".....", ".....", ".....", "#####"}},
	{'^', {"..#..", ".#.#.", "#...#", ".....", ".....", ".....", "....."}},
	{'*', {".....", "..#..", "#.#.#", ".###.", "#.#.#", "..#..", "....."}},
	{'[', {".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###."}},
	{']', {".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###."}},
	{'<', {"...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#."}},
	{'>', {".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#..."}},
	{'\'', {"..#..", "..#..", ".#...", ".....", ".....", ".....", "....."}},
	{';', {".....", ".##..", ".##..", ".....", ".##..", "..#..", ".#..."}},
	{'!', {"..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."}},
	{'?', {".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."}},
	{'|', {"..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
};

static const struct glyph unknown = {
	'\0', {"#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"}};

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

/* The label strip: a line of text with 2 font pixels above and below. */
int ss_render_label_height(int pic_w, int pic_h)
{
	return (GLYPH_H + 4) * ss_render_font_scale(pic_w, pic_h);
}

void ss_render_draw_label(struct ss_render_image *img, int pic_w, int pic_h, double time)
{
	const int k = ss_render_font_scale(pic_w, pic_h);
	static const uint8_t black[3] = {0, 0, 0};
	char text[64];
	snprintf(text, sizeof text, "t = %g s", time);
	for (int y = 0; y < ss_render_label_height(pic_w, pic_h) && y < img->height; y++)
		memset(img->pixels + (size_t)y * img->row_bytes, SS_RENDER_BACKGROUND,
		       3 * (size_t)(pic_w < img->width ? pic_w : img->width));
	ss_render_draw_text(img, 2 * k, 2 * k, k, text, black);
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
 * Layout of the strip, in multiples of the font scale k:
 *
 *     margin | bar (framed) | tick | gap | labels | margin
 *
 * The ticks stick out of the bar's frame, and a gap of 4 k separates them
 * from the labels, so a tick never reads as a minus sign.
 */
struct bar_layout {
	int k, margin, bar_w, tick, gap, text_w;
};

static struct bar_layout bar_layout(int pic_w, int pic_h, double zmin, double zmax)
{
	struct bar_layout l;
	l.k = ss_render_font_scale(pic_w, pic_h);
	l.margin = 4 * l.k;
	l.bar_w = 5 * l.k;
	l.tick = 2 * l.k;
	l.gap = 4 * l.k;
	l.text_w = ss_render_text_width("m", l.k);
	const double step = tick_step(zmin, zmax);
	char s[32];
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		ss_render_format_height(z, step, s, sizeof s);
		l.text_w = fmax(l.text_w, ss_render_text_width(s, l.k));
	}
	for (int end = 0; end < 2; end++) {
		end_label(end ? zmax : zmin, step, s, sizeof s);
		l.text_w = fmax(l.text_w, ss_render_text_width(s, l.k));
	}
	return l;
}

int ss_render_colorbar_width(int pic_w, int pic_h, double zmin, double zmax)
{
	const struct bar_layout l = bar_layout(pic_w, pic_h, zmin, zmax);
	return 2 * l.margin + l.bar_w + l.tick + l.gap + l.text_w;
}

/* Fill the box [x0, x1) x [y0, y1) with rgb. */
static void fill(struct ss_render_image *img, int x0, int y0, int x1, int y1,
                 const uint8_t rgb[3])
{
	for (int y = y0; y < y1; y++)
		for (int x = x0; x < x1; x++)
			put(img, x, y, rgb);
}

void ss_render_draw_colorbar(struct ss_render_image *img, int x0, int y0, int pic_h,
                             enum ss_render_cmap cmap, double zmin, double zmax)
{
	const struct bar_layout l = bar_layout(x0, pic_h, zmin, zmax);
	static const uint8_t black[3] = {0, 0, 0};
	uint8_t lut[256][3];
	ss_render_cmap_table(cmap, lut);

	for (int y = 0; y < img->height; y++)   /* white strip */
		memset(img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x0,
		       SS_RENDER_BACKGROUND, 3 * (size_t)(img->width - x0));

	const int k = l.k, line = (k + 1) / 2, text_h = GLYPH_H * k;
	const int bx = x0 + l.margin, top = y0 + 2 * l.margin + text_h;
	const int bottom = y0 + pic_h - l.margin - text_h / 2 - 1;
	if (bottom - top < 2 * text_h)
		return;   /* a picture too small for a bar */
	ss_render_draw_text(img, bx, y0 + l.margin, k, "m", black);
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
		ss_render_draw_text(img, text_x, y - text_h / 2, k, s, black);
	}
	for (double z = ceil(zmin / step - 1e-9) * step; z <= zmax + 1e-9 * step; z += step) {
		const int y = top + (int)lround((zmax - z) / (zmax - zmin) * (bottom - top));
		if (y - top < text_h + 2 * k || bottom - y < text_h + 2 * k)
			continue;   /* an end's label is there */
		ss_render_format_height(z, step, s, sizeof s);
		fill(img, tick_x0, y - line / 2, tick_x0 + l.tick, y - line / 2 + line, black);
		ss_render_draw_text(img, text_x, y - text_h / 2, k, s, black);
	}
}
