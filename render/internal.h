/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * internal.h - what the files of render/ share and nothing else sees (the
 * public interface is include/sandslide/render.h).  No HDF5 or libpng type
 * appears here: the files are read through include/sandslide/snapshot.h,
 * and png.c alone includes <png.h>.
 */
#ifndef SANDSLIDE_RENDER_INTERNAL_H
#define SANDSLIDE_RENDER_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "sandslide/grid.h"
#include "sandslide/render.h"
#include "sandslide/snapshot.h"

#define SS_RENDER_BACKGROUND 0xff               /* white: oblique sky, colour bar,
                                                 * cells without data */

/* Cell and pixel types: enum ss_cell_type (flow 0, wall 1, open 2) and
 * SS_RENDER_CELL_NODATA (3); anything else is taken for a wall. */
static inline uint8_t ss_render_type_of(int t)
{
	return (uint8_t)(t >= 0 && t <= SS_RENDER_CELL_NODATA ? t : SS_CELL_WALL);
}

/* Walls and cells without data hold no sand: no height of theirs enters
 * a mean, a gradient or the height scale (bit 0 is set in both, 1 and 3). */
_Static_assert(SS_CELL_FLOW == 0 && SS_CELL_WALL == 1 && SS_CELL_OPEN == 2 &&
               SS_RENDER_CELL_NODATA == 3 && SS_SNAPSHOT_CELL_NODATA == 3,
               "the renderer's types are the file's, and bit 0 marks no sand");
static inline int ss_render_no_sand(int t)
{
	return t & 1;
}

/* ---- resample.c: cells -> pixels ------------------------------------- */

/* Weights of one axis: output pixel k (counted from the south or west)
 * takes source cells first[k] .. first[k] + count[k] - 1 with weights
 * w[k * span + m]. */
struct ss_render_axis {
	int n_out, span;
	int *first, *count;
	double *w;
};

/* The cells-to-pixels map of a picture.  Heights use `ix`/`iy` (area
 * averaging when shrinking, bilinear between cell centres when growing);
 * cell types always use the area weights `bx`/`by` so walls stay cell-sharp. */
struct ss_render_resampler {
	int nx, ny;                 /* cells */
	int width, height;          /* px */
	double px_dx, px_dy;        /* m per pixel */
	struct ss_render_axis bx, by, ix, iy;
};

int ss_render_resampler_init(struct ss_render_resampler *r, int nx, int ny, double dx,
                             double dy, int width, int height);
void ss_render_resampler_release(struct ss_render_resampler *r);

/* One pixel per cell: the heights need no resampling at all. */
static inline int ss_render_resampler_is_identity(const struct ss_render_resampler *r)
{
	return r->width == r->nx && r->height == r->ny;
}

/* Pixel types (width * height, north row first) from the cell types
 * (nx * ny with row stride `stride`, south row first; NULL: all flow): the
 * type covering most of the pixel, ties going to walls, then cells without
 * data, then open cells. */
void ss_render_resample_types(const struct ss_render_resampler *r, const uint8_t *cell_type,
                              ptrdiff_t stride, uint8_t *pixel_type, int parallel);

/*
 * Add cell rows j0 .. j0 + rows - 1 (south-first numbering; h points at
 * row j0, cell_type at row 0 of the whole field) to the accumulators of
 * the weighted height sum and the weight sum (width * height each, north
 * row first).  Walls carry no weight.  Rows may come in blocks in any
 * order; the same order gives the same bits.
 */
void ss_render_resample_rows(const struct ss_render_resampler *r, const double *h,
                             ptrdiff_t stride, const uint8_t *cell_type,
                             ptrdiff_t type_stride, int j0, int rows, double *acc_hw,
                             double *acc_w, int parallel);

/* acc_hw / acc_w into acc_hw: the pixel heights (NAN without weight). */
void ss_render_resample_finish(const struct ss_render_resampler *r, double *acc_hw,
                               const double *acc_w, int parallel);

/* ---- the resampled field a style colours ----------------------------- */

struct ss_render_raster {
	int width, height;          /* px */
	double px_dx, px_dy;        /* m per pixel */
	const double *h;            /* m at pixel (x, y) = h[y * stride + x], y = 0
	                             * the north row; NAN: none */
	ptrdiff_t stride;           /* negative when the rows are the cells' own,
	                             * stored south first */
	const uint8_t *type;        /* enum ss_cell_type, width * height, north first */
	int step_x, step_y;         /* px between the points of the gradient
	                             * stencil: one cell (at least one px) */
	const float *gx, *gy;       /* the gradient per pixel (width * height, north
	                             * first), or NULL: from h (ss_render_gradient) */
	double wall_m[4];           /* oblique: thickness of the wall drawn along
	                             * each side (enum ss_side: west, east, south,
	                             * north), m; 0: none */
};

static inline double ss_render_raster_h(const struct ss_render_raster *r, int x, int y)
{
	return r->h[(ptrdiff_t)y * r->stride + x];
}

/* Height gradient (dh/dx east, dh/dy north) at pixel (x, y): r->gx, r->gy
 * when given, else Horn's 3 x 3 weighted differences over points step_x,
 * step_y pixels apart; next to a wall, NaN or the edge, the lines that
 * reach one take one-sided differences instead.  Only for pixels with
 * sand.  A grid enlarged K times gives gx, gy: the cells' own gradients
 * (step 1 on the cells), interpolated like the heights, so the shading
 * varies smoothly instead of in flat squares per cell, and the half cell
 * beyond the last cell centre at an edge or wall, where the interpolated
 * surface is flat, takes the slope of its cell instead of a band of
 * different shading (plan.c). */
void ss_render_gradient(const struct ss_render_raster *r, int x, int y, double *gx,
                        double *gy);

/* Brightness in [ambient, 1] of a surface of gradient (gx, gy) lit from
 * azimuth/altitude (degrees), heights exaggerated by zscale. */
struct ss_render_light {
	double lx, ly, lz;          /* unit vector towards the light */
	double zscale;
};
void ss_render_light_init(struct ss_render_light *l, double azimuth_deg,
                          double altitude_deg, double zscale);
double ss_render_hillshade(const struct ss_render_light *l, double gx, double gy);

/* Colour-map index 0..255 of height h on [zmin, zmax], clamped. */
static inline int ss_render_cmap_index(double h, double zmin, double zmax)
{
	const double t = (h - zmin) / (zmax - zmin) * 255.0;
	return t <= 0.0 ? 0 : t >= 255.0 ? 255 : (int)(t + 0.5);
}

/* ---- the styles: raster -> the first raster->width columns of img ---- */

void ss_render_shaded(const struct ss_render_raster *r, const struct ss_render_options *o,
                      double zmin, double zmax, struct ss_render_image *img, int parallel);
void ss_render_gray16(const struct ss_render_raster *r, double zmin, double zmax,
                      struct ss_render_image *img, int parallel);

/* oblique.c: picture size for a raster (the camera framing depends only on
 * the grid and the height scale, so every frame of a series matches). */
void ss_render_oblique_size(const struct ss_render_raster *r,
                            const struct ss_render_options *o, double zmin, double zmax,
                            int *width, int *height);
int ss_render_oblique(const struct ss_render_raster *r, const struct ss_render_options *o,
                      double zmin, double zmax, struct ss_render_image *img, int parallel);

/* ---- text.c: a real font (FreeType, DejaVu Sans) ------------------- */

/* A font at one size: its glyphs rendered once, read-only afterwards, so
 * that threads drawing at once may share it. */
struct ss_render_font;

/* The font file text is drawn with: $SANDSLIDE_FONT, else the build's
 * default (the Makefile's FONT). */
const char *ss_render_font_file(void);
/* SS_ERR_FAIL, with one line naming the file and what to install or set,
 * unless the font file can be opened: checked before work that would end
 * in drawing text (fit --plot). */
int ss_render_font_check(void);
/* The largest font, px: the plots' titles are a fifth larger than the
 * text of their panels, whose size ss_render_font_px caps at half this. */
#define SS_RENDER_FONT_PX_MAX 1024
/* The font size (its em, px) of text on a picture of w x h px: about 1/24
 * of the shorter side, at least 12 px and at most SS_RENDER_FONT_PX_MAX / 2. */
int ss_render_font_px(int w, int h);
/* A font whose em is px (1 .. SS_RENDER_FONT_PX_MAX) px, into *out;
 * SS_ERR_FAIL with a message naming the file when it cannot be read
 * (ss_render_font_check's), or out of memory.  ss_render_font_destroy(NULL)
 * is a no-op. */
int ss_render_font_create(struct ss_render_font **out, int px);
void ss_render_font_destroy(struct ss_render_font *f);
/* Its sizes, px: the em; above and below the baseline of a line of text
 * (so a line is ascent + descent high: a descender such as g's ends
 * within it); a digit's height above the baseline (to centre numbers). */
int ss_render_font_em(const struct ss_render_font *f);
int ss_render_font_ascent(const struct ss_render_font *f);
int ss_render_font_descent(const struct ss_render_font *f);
int ss_render_font_line(const struct ss_render_font *f);
int ss_render_font_digit_height(const struct ss_render_font *f);
/* The advance of a line of text, px (kerned). */
int ss_render_text_width(const struct ss_render_font *f, const char *text);
/* Draw text antialiased in colour rgb into an 8-bit RGB picture, clipped
 * to it, the top-left corner of its line box at (x, y): the baseline is
 * at y + ascent.  _up: turned a quarter anticlockwise (reading upwards,
 * as a y axis's title), its box ss_render_font_line wide and
 * ss_render_text_width high with its top-left corner at (x, y). */
void ss_render_draw_text(struct ss_render_image *img, const struct ss_render_font *f, int x,
                         int y, const char *text, const uint8_t rgb[3]);
void ss_render_draw_text_up(struct ss_render_image *img, const struct ss_render_font *f,
                            int x, int y, const char *text, const uint8_t rgb[3]);

/* ---- overlay.c: label and colour bar --------------------------------- */

/* Rows of the strip that holds the label, in font f. */
int ss_render_label_height(const struct ss_render_font *f);
/* "t = 12.5 s" in the strip: rows 0 .. ss_render_label_height - 1 of img,
 * columns 0 .. pic_w - 1, white, the text black, so it covers nothing of
 * the picture. */
void ss_render_draw_label(struct ss_render_image *img, const struct ss_render_font *f,
                          int pic_w, double time);
/* Width of the colour-bar strip added right of the picture. */
int ss_render_colorbar_width(const struct ss_render_font *f, double zmin, double zmax);
/* Draw the colour bar in columns x0 .. img->width - 1 beside the picture's
 * rows y0 .. y0 + pic_h - 1: the bar with a frame, ticks at round heights
 * outside it, each end labelled. */
void ss_render_draw_colorbar(struct ss_render_image *img, const struct ss_render_font *f,
                             int x0, int y0, int pic_h, enum ss_render_cmap cmap, double zmin,
                             double zmax);

/* ---- png.c: encoding and atomic writes ------------------------------ */

/* img as PNG bytes in memory: *data (malloc'd: free it) of *size bytes,
 * the same bytes ss_render_write_png writes. */
int ss_render_encode_png(const struct ss_render_image *img, int compression,
                         unsigned char **data, size_t *size);

/* size bytes to "path.partial", renamed to path once complete and closed
 * (an existing path is replaced only then). */
int ss_render_write_file(const char *path, const void *data, size_t size);

/* ---- source.c: a sandslide file and its cell types ------------------ */

/* The file (sizes, geometry, times; heights are read through it with
 * ss_snapshot_file_read_rows) and its cell types, read once. */
struct ss_render_source {
	struct ss_snapshot_file file;
	uint8_t *cell_type;         /* nx * ny, south row first */
};

/* Open and check a sandslide output file (SS_ERR_INPUT with a message if
 * it is not one or is damaged) and read its cell types, with the cells
 * without data as SS_RENDER_CELL_NODATA. */
int ss_render_source_open(struct ss_render_source *s, const char *path);
void ss_render_source_close(struct ss_render_source *s);

/* Lowest and highest finite height on flow and open cells of snapshots
 * first .. last (inclusive); +INFINITY/-INFINITY when there are none. */
int ss_render_source_range(struct ss_render_source *s, long long first, long long last,
                           double *zmin, double *zmax);

/* ---- plan.c: what the frames of a series share ----------------------- */

/* Fill in a missing zmin or zmax (NAN) from the data's range [lo, hi]
 * (empty: 0..1, flat: widened by 0.5 m each way); SS_ERR_INPUT naming
 * `what` if the scale is then empty. */
int ss_render_scale_resolve(double *zmin, double *zmax, double lo, double hi,
                            const char *what);

/*
 * Everything that is the same for all frames of a series.  A frame is laid
 * out as
 *
 *     +---------------------------+--------+
 *     | label strip (label_h rows)|        |
 *     +---------------------------+ colour |
 *     | wall | map rs.width x     |  bar   |
 *     | side | rs.height px  ...  |        |
 *     +---------------------------+--------+
 *
 * where the picture (pic_w x pic_h) is the map with a wall drawn outside
 * each grid side that is a wall (border[side] px; the map styles), or the
 * oblique view.
 */
struct ss_render_plan {
	struct ss_render_options look;
	double zmin, zmax;          /* m, resolved */
	struct ss_render_resampler rs;
	uint8_t *pixel_type;        /* rs.width * rs.height */
	int border[4];              /* px of wall outside each side (enum ss_side) */
	int label_h;                /* rows of the label strip, 0 without label */
	int image_w, image_h;       /* the whole frame */
	int pic_w, pic_h;           /* the picture, without label strip and colour bar */
	double wall_m[4];           /* border[] in m, for the oblique view */
	struct ss_render_font *font;   /* the label's and colour bar's text, owned;
	                                * NULL without either */
};

/* Set up a plan for a grid of nx x ny cells (cell_type with stride, NULL:
 * all flow; wall_sides: bit 1 << enum ss_side for each wall side) once
 * zmin and zmax are known. */
int ss_render_plan_init(struct ss_render_plan *p, const struct ss_render_options *look,
                        int nx, int ny, double dx, double dy, const uint8_t *cell_type,
                        ptrdiff_t type_stride, unsigned wall_sides, double zmin,
                        double zmax, int parallel);
void ss_render_plan_release(struct ss_render_plan *p);

/* Whether the plan enlarges the grid, so that frames take their gradients
 * from the cells (ss_render_plan_gradients). */
static inline int ss_render_plan_enlarges(const struct ss_render_plan *p)
{
	return p->rs.width > p->rs.nx || p->rs.height > p->rs.ny;
}

/* The cells' gradients (Horn, one-sided at walls and edges) interpolated
 * onto the pixels like the heights: *gx, *gy (rs.width * rs.height each,
 * north first; ss_free both).  h and cell_type are the whole grid, south
 * row first, with strides. */
int ss_render_plan_gradients(const struct ss_render_plan *p, const double *h,
                             ptrdiff_t stride, const uint8_t *cell_type,
                             ptrdiff_t type_stride, float **gx, float **gy, int parallel);

/* Colour the pixel heights (pixel (x, y) at pixel_h[y * stride + x], y = 0
 * north; gx, gy from ss_render_plan_gradients or NULL) into img
 * (initialised here), with the wall sides, label and colour bar. */
int ss_render_plan_draw(const struct ss_render_plan *p, const double *pixel_h,
                        ptrdiff_t stride, const float *gx, const float *gy, double time,
                        struct ss_render_image *img, int parallel);

/* ---- frame.c: one frame of a source, drawn with a plan ---------------- */

/* Render snapshot t of s into img (initialised here; release it, also
 * after a failure), with its time, snapshot, source and map corner; when
 * pixel_h is not NULL, also copy there the pixel heights it was coloured
 * from (rs.width x rs.height, north row first, NAN without sand). */
int ss_render_plan_image(const struct ss_render_plan *p, struct ss_render_source *s,
                         long long t, struct ss_render_image *img, double *pixel_h,
                         int parallel);

/* Render snapshot t of s to path (parallel: split rows between threads). */
int ss_render_plan_snapshot(const struct ss_render_plan *p, struct ss_render_source *s,
                            long long t, const char *path, int parallel);

/* ---- html.c: the self-contained viewer (--html) ---------------------- */

struct ss_render_html;

/* SS_ERR_INPUT unless the viewer can be written to path: its folder exists
 * and is writable, and path is not a folder, nor an existing file unless
 * force. */
int ss_render_html_check_path(const char *path, int force);

/* A viewer of the n snapshots sel (in the order shown) of s drawn with
 * plan p (both must outlive it).  scale_given: --zmin or --zmax was
 * given, so the heights are quantised over the scale widened to the
 * snapshots' range, which is read here. */
int ss_render_html_create(struct ss_render_html **out, const struct ss_render_plan *p,
                          struct ss_render_source *s, const long long *sel, long long n,
                          int scale_given);

/* 1 if ss_render_html_add needs the pixel heights (the picture is smaller
 * than the grid on some axis), 0 if it reads the cells itself. */
int ss_render_html_wants_pixels(const struct ss_render_html *h);

/* Frame k: snapshot t, its PNG (malloc'd; the viewer owns it from here on,
 * also on failure), and its pixel heights if wanted (ss_render_plan_image).
 * Distinct k may be added from several threads at once. */
int ss_render_html_add(struct ss_render_html *h, long long k, long long t, unsigned char *png,
                       size_t png_size, const double *pixel_h);

/* Write the page (every frame added) to path atomically; *bytes its size.
 * fps: the speed it starts with. */
int ss_render_html_write(struct ss_render_html *h, const char *path, int fps, size_t *bytes);

/* ss_render_html_destroy(NULL) is a no-op. */
void ss_render_html_destroy(struct ss_render_html *h);

/* video.c: 1 when ffmpeg is on PATH (ss_render_video can make a video). */
int ss_render_ffmpeg_found(void);

/* command.c: dir must be a writable folder, or a missing one whose
 * parent is (created when `create`); SS_ERR_INPUT says which it is not. */
int ss_render_check_dir(const char *dir, int create);

/* Nice round numbers: z formatted with the fewest digits that tell apart
 * values `step` apart ("0.35", "12"). */
void ss_render_format_height(double z, double step, char *out, size_t size);

#endif
