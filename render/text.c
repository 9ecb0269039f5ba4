/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * text.c - text in a real font: DejaVu Sans (Debian's fonts-dejavu-core),
 * rasterised by FreeType, drawn antialiased into the renderer's 8-bit RGB
 * pictures: the time label, the colour bar (overlay.c) and the figures of
 * `fit --plot` (plot.c).
 *
 * A font is made for one size: the face is opened, the printable ASCII
 * glyphs and the face's missing-glyph box are rendered once into 8-bit
 * coverage bitmaps (light hinting: vertical only, so the shapes keep
 * their proportions) with their advances and the face's kerning pairs,
 * and the face and FreeType are closed again.  Drawing then only reads
 * those bitmaps: frames drawn at once on several threads share one font,
 * nothing is locked, and the same text gives the same bytes.  Each font
 * has its own FreeType library object, so fonts may be made in several
 * threads at once too.  Why FreeType rather than Cairo, measured:
 * render/README.md.
 *
 * The font file is $SANDSLIDE_FONT when set, else the path the build was
 * given (the Makefile's FONT: where fonts-dejavu-core installs DejaVu
 * Sans).  Text is ASCII; any other character (a UTF-8 sequence counts as
 * one) is the face's missing-glyph box.
 */
#include "internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ft2build.h>
#include FT_FREETYPE_H

#include "sandslide/error.h"

#ifndef SS_FONT_FILE
#define SS_FONT_FILE "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#endif

#define FIRST 0x20              /* ' ' */
#define LAST 0x7e               /* '~' */
#define MISSING (LAST - FIRST + 1)   /* the slot of the missing-glyph box */
#define SLOTS (MISSING + 1)

struct glyph {
	int w, h;                   /* the bitmap, px */
	int left, top;              /* its top-left corner from the pen on the
	                             * baseline, px: right, up */
	int advance;                /* px to the next pen position */
	size_t at;                  /* its first byte in the font's coverage */
};

struct ss_render_font {
	int px;                     /* the em, px */
	int ascent, descent;        /* px above and below the baseline of a line */
	int digit_h;                /* px of a digit above the baseline */
	struct glyph glyph[SLOTS];
	int16_t kern[SLOTS][SLOTS]; /* px added between a pair (left, right) */
	uint8_t *coverage;          /* every glyph's bitmap, w * h bytes each, 0..255 */
};

const char *ss_render_font_file(void)
{
	const char *env = getenv("SANDSLIDE_FONT");
	return env && *env ? env : SS_FONT_FILE;
}

int ss_render_font_px(int w, int h)
{
	const int m = w < h ? w : h;
	const int px = (m + 12) / 24;   /* a line of text about 1/20 of the picture */
	return px < 12 ? 12 : px > SS_RENDER_FONT_PX_MAX / 2 ? SS_RENDER_FONT_PX_MAX / 2 : px;
}

/* The slot of character c (a byte of ASCII): MISSING for any other. */
static int slot_of(unsigned char c)
{
	return c >= FIRST && c <= LAST ? c - FIRST : MISSING;
}

/* The next character of UTF-8 text at *s: its slot, *s moved past it (a
 * sequence of bytes >= 0x80 is one character, drawn as the missing box). */
static int next_slot(const char **s)
{
	const unsigned char c = (unsigned char)*(*s)++;
	if (c >= 0x80)
		while (((unsigned char)**s & 0xc0) == 0x80)
			(*s)++;
	return slot_of(c);
}

/* Why FreeType refused: its own words where the build has them. */
static const char *ft_reason(FT_Error e)
{
	switch (e) {
	case FT_Err_Unknown_File_Format:
		return "not a font file FreeType reads (TrueType, OpenType, Type 1 ...)";
	case FT_Err_Out_Of_Memory:
		return "out of memory";
	default:
		return "FreeType cannot read it";
	}
}

/* The font file's name and where it came from, for messages. */
static const char *font_origin(void)
{
	const char *env = getenv("SANDSLIDE_FONT");
	return env && *env ? "SANDSLIDE_FONT" : "the build's default";
}

#define FONT_HINT "install Debian package fonts-dejavu-core, or set SANDSLIDE_FONT to a " \
                  "TrueType or OpenType file"

int ss_render_font_check(void)
{
	const char *path = ss_render_font_file();
	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_fail("cannot open the font '%s' (%s), which text in pictures is "
		                     "drawn with: %s; " FONT_HINT, path, font_origin(),
		                     strerror(errno));
	fclose(f);
	return SS_OK;
}

/* Render every slot of face at its size into f (its coverage grown here
 * as the bitmaps come). */
static int rasterise(struct ss_render_font *f, FT_Face face, const char *path)
{
	size_t used = 0, cap = 0;
	for (int k = 0; k < SLOTS; k++) {
		const FT_UInt index = k == MISSING ? 0 : FT_Get_Char_Index(face, FIRST + k);
		const FT_Error e = FT_Load_Glyph(face, index, FT_LOAD_RENDER | FT_LOAD_TARGET_LIGHT);
		if (e)
			return ss_error_fail("cannot draw glyph %u of the font '%s': %s", index, path,
			                     ft_reason(e));
		const FT_GlyphSlot g = face->glyph;
		const FT_Bitmap *b = &g->bitmap;
		if (b->rows && b->width && b->pixel_mode != FT_PIXEL_MODE_GRAY)
			return ss_error_fail("the font '%s' has bitmaps but no outlines: a scalable "
			                     "font (TrueType, OpenType) is accepted", path);
		struct glyph *q = &f->glyph[k];
		q->w = (int)b->width;
		q->h = (int)b->rows;
		q->left = g->bitmap_left;
		q->top = g->bitmap_top;
		q->advance = (int)((g->advance.x + 32) >> 6);
		q->at = used;
		const size_t n = (size_t)q->w * (size_t)q->h;
		if (used + n > cap) {
			const size_t more = 2 * (used + n) + 1024;
			uint8_t *c = ss_alloc(more, 1, "the font's glyphs");
			if (!c)
				return SS_ERR_FAIL;
			if (used)
				memcpy(c, f->coverage, used);
			ss_free(f->coverage);
			f->coverage = c;
			cap = more;
		}
		for (int r = 0; r < q->h; r++)
			memcpy(f->coverage + used + (size_t)r * q->w, b->buffer + (ptrdiff_t)r * b->pitch,
			       (size_t)q->w);
		used += n;
	}
	return SS_OK;
}

/* The face's kerning between every pair of slots, rounded to pixels. */
static void kerning(struct ss_render_font *f, FT_Face face)
{
	memset(f->kern, 0, sizeof f->kern);
	if (!FT_HAS_KERNING(face))
		return;
	FT_UInt index[SLOTS];
	for (int k = 0; k < SLOTS; k++)
		index[k] = k == MISSING ? 0 : FT_Get_Char_Index(face, FIRST + k);
	for (int a = 0; a < SLOTS; a++)
		for (int b = 0; b < SLOTS; b++) {
			FT_Vector d;
			if (FT_Get_Kerning(face, index[a], index[b], FT_KERNING_DEFAULT, &d))
				continue;
			const long px = (d.x + (d.x < 0 ? -32 : 32)) / 64;
			f->kern[a][b] = (int16_t)(px < -4096 ? -4096 : px > 4096 ? 4096 : px);
		}
}

int ss_render_font_create(struct ss_render_font **out, int px)
{
	*out = NULL;
	if (px < 1 || px > SS_RENDER_FONT_PX_MAX)
		SS_BUG("a font of %d px", px);
	const char *path = ss_render_font_file();
	int err = ss_render_font_check();
	if (err)
		return err;
	struct ss_render_font *f = ss_alloc(1, sizeof *f, "a font");
	if (!f)
		return SS_ERR_FAIL;
	FT_Library lib;
	FT_Face face;
	FT_Error e = FT_Init_FreeType(&lib);
	if (e) {
		err = ss_error_fail("cannot start FreeType to draw text: %s", ft_reason(e));
		goto out_free;
	}
	if ((e = FT_New_Face(lib, path, 0, &face))) {
		err = ss_error_fail("cannot read the font '%s' (%s): %s; " FONT_HINT, path,
		                    font_origin(), ft_reason(e));
		goto out_library;
	}
	if (!FT_IS_SCALABLE(face) || (e = FT_Set_Pixel_Sizes(face, 0, (FT_UInt)px))) {
		err = ss_error_fail("the font '%s' (%s) cannot be drawn at %d px: a scalable font "
		                    "(TrueType, OpenType) is accepted", path, font_origin(), px);
		goto out_face;
	}
	f->px = px;
	f->ascent = (int)((face->size->metrics.ascender + 63) >> 6);
	f->descent = (int)((-face->size->metrics.descender + 63) >> 6);
	if ((err = rasterise(f, face, path)))
		goto out_face;
	kerning(f, face);
	f->digit_h = f->glyph[slot_of('0')].top;
	if (f->digit_h <= 0)
		f->digit_h = (7 * px + 5) / 10;
out_face:
	FT_Done_Face(face);
out_library:
	FT_Done_FreeType(lib);
out_free:
	if (err) {
		ss_render_font_destroy(f);
		return err;
	}
	*out = f;
	return SS_OK;
}

void ss_render_font_destroy(struct ss_render_font *f)
{
	if (!f)
		return;
	ss_free(f->coverage);
	ss_free(f);
}

int ss_render_font_ascent(const struct ss_render_font *f)
{
	return f->ascent;
}

int ss_render_font_descent(const struct ss_render_font *f)
{
	return f->descent;
}

int ss_render_font_line(const struct ss_render_font *f)
{
	return f->ascent + f->descent;
}

int ss_render_font_digit_height(const struct ss_render_font *f)
{
	return f->digit_h;
}

int ss_render_font_em(const struct ss_render_font *f)
{
	return f->px;
}

int ss_render_text_width(const struct ss_render_font *f, const char *text)
{
	int w = 0, prev = -1;
	while (*text) {
		const int k = next_slot(&text);
		if (prev >= 0)
			w += f->kern[prev][k];
		w += f->glyph[k].advance;
		prev = k;
	}
	return w;
}

/* Pixel (x, y) of img (8-bit RGB) moved towards rgb by coverage a/255,
 * unless outside the picture. */
static void blend(struct ss_render_image *img, int x, int y, int a, const uint8_t rgb[3])
{
	if (x < 0 || y < 0 || x >= img->width || y >= img->height || a == 0)
		return;
	uint8_t *p = img->pixels + (size_t)y * img->row_bytes + 3 * (size_t)x;
	for (int c = 0; c < 3; c++)
		p[c] = (uint8_t)((p[c] * (255 - a) + rgb[c] * a + 127) / 255);
}

/* Text along a line, turned by a quarter anticlockwise when `up`; (x, y)
 * is the top-left of its box. */
static void draw(struct ss_render_image *img, const struct ss_render_font *f, int x, int y,
                 const char *text, const uint8_t rgb[3], int up)
{
	if (img->channels != 3 || img->bit_depth != 8)
		SS_BUG("text on a picture of %d channels of %d bits", img->channels, img->bit_depth);
	const int width = up ? ss_render_text_width(f, text) : 0;
	int pen = 0, prev = -1;
	while (*text) {
		const int k = next_slot(&text);
		if (prev >= 0)
			pen += f->kern[prev][k];
		const struct glyph *g = &f->glyph[k];
		const uint8_t *cov = f->coverage + g->at;
		/* (u, v): along the line from its start, down from its top */
		for (int r = 0; r < g->h; r++)
			for (int c = 0; c < g->w; c++) {
				const int u = pen + g->left + c, v = f->ascent - g->top + r;
				const int a = cov[(size_t)r * g->w + c];
				if (up)
					blend(img, x + v, y + width - 1 - u, a, rgb);
				else
					blend(img, x + u, y + v, a, rgb);
			}
		pen += g->advance;
		prev = k;
	}
}

void ss_render_draw_text(struct ss_render_image *img, const struct ss_render_font *f, int x,
                         int y, const char *text, const uint8_t rgb[3])
{
	draw(img, f, x, y, text, rgb, 0);
}

void ss_render_draw_text_up(struct ss_render_image *img, const struct ss_render_font *f,
                            int x, int y, const char *text, const uint8_t rgb[3])
{
	draw(img, f, x, y, text, rgb, 1);
}
