/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * font_bench.c - the measurement behind render/text.c's choice of FreeType
 * over Cairo (render/README.md#text-freetype-not-cairo): the text of a
 * door frame (the time label and the colour bar's seven labels, at the
 * 15 px a default 608 x 384 px door frame gets) drawn into an 8-bit RGB
 * picture N times,
 *
 *   freetype  as render/text.c does: DejaVu Sans opened once, the printable
 *             ASCII glyphs rendered once (light hinting), then per frame
 *             each glyph's coverage blended into the picture;
 *   cairo     Cairo's text API ("DejaVu Sans" through fontconfig, the way a
 *             Cairo program names a font): per frame each label into an
 *             RGB24 surface of its box, copied into the RGB picture (Cairo
 *             draws into 32-bit pixels, never into 24-bit RGB);
 *
 * and prints the start-up (font found, opened, first glyphs) and the cost
 * per frame of each, then compares the two pictures pixel by pixel.  Not
 * built by make (Cairo is no dependency of sandslide); with libcairo2-dev
 * and libfreetype-dev installed:
 *
 *   cc -O2 -std=c11 tools/font_bench.c $(pkg-config --cflags --libs freetype2 cairo) \
 *      -o /tmp/font_bench && /tmp/font_bench [PX [FRAMES]]
 */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cairo.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#define W 608
#define H 384
#define N_TEXT 8

static const char *font_file = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
static const char *texts[N_TEXT] = {"t = 600 s", "m", "0.797", "0.6", "0.4", "0.2", "0.0",
                                    "0.00"};
static const int text_x[N_TEXT] = {7, 554, 570, 570, 570, 570, 570, 570};
static const int text_y[N_TEXT] = {6, 29, 50, 120, 190, 260, 300, 350};

static uint8_t ft_pic[H][W][3], cairo_pic[H][W][3];

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* ---- FreeType, as render/text.c ------------------------------------- */

struct glyph {
	int w, h, left, top, advance;
	uint8_t *bits;
};
static struct glyph glyphs[128];
static int ascent;

static int ft_start(int px)
{
	FT_Library lib;
	FT_Face face;
	if (FT_Init_FreeType(&lib) || FT_New_Face(lib, font_file, 0, &face) ||
	    FT_Set_Pixel_Sizes(face, 0, (FT_UInt)px))
		return -1;
	ascent = (int)((face->size->metrics.ascender + 63) >> 6);
	for (int c = 32; c < 127; c++) {
		if (FT_Load_Char(face, (FT_ULong)c, FT_LOAD_RENDER | FT_LOAD_TARGET_LIGHT))
			return -1;
		const FT_GlyphSlot g = face->glyph;
		struct glyph *q = &glyphs[c];
		q->w = (int)g->bitmap.width;
		q->h = (int)g->bitmap.rows;
		q->left = g->bitmap_left;
		q->top = g->bitmap_top;
		q->advance = (int)((g->advance.x + 32) >> 6);
		q->bits = malloc((size_t)q->w * q->h + 1);
		for (int r = 0; r < q->h; r++)
			memcpy(q->bits + r * q->w, g->bitmap.buffer + r * g->bitmap.pitch, (size_t)q->w);
	}
	FT_Done_Face(face);
	FT_Done_FreeType(lib);
	return 0;
}

static void ft_text(int x, int y, const char *s)
{
	for (; *s; s++) {
		const struct glyph *q = &glyphs[(unsigned char)*s];
		for (int r = 0; r < q->h; r++)
			for (int c = 0; c < q->w; c++) {
				const int X = x + q->left + c, Y = y + ascent - q->top + r;
				const int a = q->bits[r * q->w + c];
				if (X < 0 || Y < 0 || X >= W || Y >= H || !a)
					continue;
				for (int k = 0; k < 3; k++)   /* black text */
					ft_pic[Y][X][k] = (uint8_t)((ft_pic[Y][X][k] * (255 - a) + 127) / 255);
			}
		x += q->advance;
	}
}

/* ---- Cairo ------------------------------------------------------------ */

static cairo_font_face_t *cairo_face;
static double cairo_ascent;

static void cairo_start(int px)
{
	cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, 8, 8);
	cairo_t *c = cairo_create(s);
	cairo_select_font_face(c, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
	cairo_set_font_size(c, px);
	cairo_font_extents_t fe;
	cairo_font_extents(c, &fe);
	cairo_ascent = fe.ascent;
	cairo_face = cairo_font_face_reference(cairo_get_font_face(c));
	cairo_destroy(c);
	cairo_surface_destroy(s);
}

static void cairo_text(int px, int x, int y, const char *text)
{
	const int bw = 8 * px, bh = 2 * px;
	cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, bw, bh);
	cairo_t *c = cairo_create(s);
	cairo_set_source_rgb(c, 1, 1, 1);
	cairo_paint(c);
	cairo_set_font_face(c, cairo_face);
	cairo_set_font_size(c, px);
	cairo_set_source_rgb(c, 0, 0, 0);
	cairo_move_to(c, 0, cairo_ascent);
	cairo_show_text(c, text);
	cairo_surface_flush(s);
	const uint8_t *d = cairo_image_surface_get_data(s);
	const int stride = cairo_image_surface_get_stride(s);
	for (int r = 0; r < bh && y + r < H; r++)
		for (int q = 0; q < bw && x + q < W; q++) {
			uint32_t v;
			memcpy(&v, d + r * stride + 4 * q, 4);
			cairo_pic[y + r][x + q][0] = (uint8_t)(v >> 16);
			cairo_pic[y + r][x + q][1] = (uint8_t)(v >> 8);
			cairo_pic[y + r][x + q][2] = (uint8_t)v;
		}
	cairo_destroy(c);
	cairo_surface_destroy(s);
}

int main(int argc, char **argv)
{
	const int px = argc > 1 ? atoi(argv[1]) : 15, frames = argc > 2 ? atoi(argv[2]) : 2000;
	if (px < 6 || px > 200 || frames < 1) {
		fprintf(stderr, "usage: font_bench [PX (6..200, default 15) [FRAMES (2000)]]\n");
		return 2;
	}
	double t0 = now();
	if (ft_start(px)) {
		fprintf(stderr, "font_bench: FreeType cannot open '%s'\n", font_file);
		return 1;
	}
	const double ft_startup = now() - t0;
	t0 = now();
	for (int f = 0; f < frames; f++)
		for (int i = 0; i < N_TEXT; i++)
			ft_text(text_x[i], text_y[i], texts[i]);
	const double ft_frame = (now() - t0) / frames;

	t0 = now();
	cairo_start(px);
	cairo_text(px, text_x[0], text_y[0], texts[0]);   /* the glyphs it caches */
	const double cairo_startup = now() - t0;
	t0 = now();
	for (int f = 0; f < frames; f++)
		for (int i = 0; i < N_TEXT; i++)
			cairo_text(px, text_x[i], text_y[i], texts[i]);
	const double cairo_frame = (now() - t0) / frames;

	/* the pictures of one frame each, on white */
	memset(ft_pic, 255, sizeof ft_pic);
	memset(cairo_pic, 255, sizeof cairo_pic);
	for (int i = 0; i < N_TEXT; i++) {
		ft_text(text_x[i], text_y[i], texts[i]);
		cairo_text(px, text_x[i], text_y[i], texts[i]);
	}
	long ink = 0, differ = 0;
	int most = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			ink += ft_pic[y][x][0] != 255;
			const int d = abs(ft_pic[y][x][0] - cairo_pic[y][x][0]);
			differ += d != 0;
			most = d > most ? d : most;
		}
	printf("text of a door frame at %d px, %d frames:\n", px, frames);
	printf("  freetype: start %.2f ms, %.1f us a frame\n", 1e3 * ft_startup, 1e6 * ft_frame);
	printf("  cairo:    start %.2f ms, %.1f us a frame\n", 1e3 * cairo_startup,
	       1e6 * cairo_frame);
	printf("  pictures: %ld px of ink; %ld px differ (by up to %d of 255)\n", ink, differ, most);
	return 0;
}
