/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem_png.c - 16-bit greyscale PNG heightmaps (see dem.h).
 *
 * The format is the renderer's gray16 style (render/shade.c, render/png.c),
 * so a picture `sandslide render --style gray16` made is a DEM, and a DEM
 * written here is a gray16 picture:
 *
 *   grey 0        no data (a wall, a missing cell); marked transparent by a
 *                 tRNS chunk
 *   grey v >= 1   height zmin + (v - 1) (zmax - zmin) / 65534, with zmin
 *                 and zmax from the tEXt chunks zmin_m and zmax_m ("%.17g"),
 *                 so grey 1 is zmin and grey 65535 is zmax exactly
 *
 * plus the optional chunks dx_m, dy_m (when not dx_m), x0_m, y0_m (cell
 * size and lower-left corner, m), which this writer adds and the renderer
 * leaves out when its pixels are not cells.  A PNG without zmin_m and
 * zmax_m is read as height = zoffset + zscale * grey with zscale and
 * zoffset from the read options, and then only a tRNS grey marks no data.
 * Rows are north first in the file.
 *
 * libpng's full API (the simplified one neither reads nor writes text
 * chunks); each setjmp sits in a small function whose changing state lives
 * behind a pointer, so nothing local is indeterminate after a longjmp.
 */
#include "io/dem_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <png.h>

#include "sandslide/error.h"
#include "io/png_check.h"

#define KEY_ZMIN "zmin_m"
#define KEY_ZMAX "zmax_m"
#define KEY_DX   "dx_m"
#define KEY_DY   "dy_m"
#define KEY_X0   "x0_m"
#define KEY_Y0   "y0_m"
#define NO_GREY  (-1)

/* The error pointer is a char[ERROR_SIZE] for libpng's message. */
#define ERROR_SIZE 256

/* What a libpng call sequence leaves behind, reachable after a longjmp. */
struct png_job {
	char message[ERROR_SIZE]; /* libpng's error */
	uint8_t *pixels;         /* big-endian 16-bit samples, north row first */
	png_bytep *rows;         /* row pointers into pixels */
	uint8_t *skip;           /* a row outside the window */
	png_uint_32 first, held; /* pixels holds file rows first .. first + held - 1
	                            (north first): the window asked for, or the
	                            whole image of an interlaced PNG */
	long long want_first, want_rows; /* the window asked for (dem.h: rows
	                            from the south; want_rows < 0 the whole) */
	double file_bytes;       /* size of the file */
	png_uint_32 width, height;
	int bit_depth, color_type;
};

static void on_error(png_structp png, png_const_charp msg)
{
	snprintf(png_get_error_ptr(png), ERROR_SIZE, "%s", msg);
	png_longjmp(png, 1);
}

static void on_warning(png_structp png, png_const_charp msg)
{
	(void)png;   /* benign (e.g. an unusual ICC profile): heights are unaffected */
	(void)msg;
}

/* ------------------------------------------------------------------ */
/* reading                                                              */

enum { DECODE_OK, DECODE_PNG_ERROR, DECODE_NOT_GRAY16, DECODE_NO_MEMORY, DECODE_TOO_SHORT };

/* Deflate expands its input at most 1032 times (a 258-byte match in 2
 * bits), so a file of B bytes holds at most 1032 B bytes of image data. */
#define DEFLATE_MAX_RATIO 1032.0

static int decode(png_structp png, png_infop info, png_infop end, FILE *f, struct png_job *job)
{
	if (setjmp(png_jmpbuf(png)))
		return DECODE_PNG_ERROR;
	png_init_io(png, f);
	png_set_sig_bytes(png, 8);
	png_read_info(png, info);
	job->width = png_get_image_width(png, info);
	job->height = png_get_image_height(png, info);
	job->bit_depth = png_get_bit_depth(png, info);
	job->color_type = png_get_color_type(png, info);
	if (job->bit_depth != 16 || job->color_type != PNG_COLOR_TYPE_GRAY)
		return DECODE_NOT_GRAY16;
	/* a header of a few bytes must not make us allocate gigabytes: the
	 * rows, each with its filter byte, must fit in what the file can hold */
	if ((double)job->height * (1.0 + 2.0 * job->width) > DEFLATE_MAX_RATIO * job->file_bytes)
		return DECODE_TOO_SHORT;
	/* the window's rows only, decoded row by row; Adam7 spreads every
	 * row over seven passes, so an interlaced image is held whole */
	const int passes = png_set_interlace_handling(png);
	png_read_update_info(png, info);
	job->first = 0;
	job->held = job->height;
	if (passes == 1 && job->want_rows >= 0 && job->want_first >= 0 &&
	    job->want_first + job->want_rows <= (long long)job->height) {
		job->first = (png_uint_32)(job->height - job->want_first - job->want_rows);
		job->held = (png_uint_32)job->want_rows;
	}
	const size_t row_bytes = 2 * (size_t)job->width;
	job->pixels = ss_alloc(job->held ? job->held : 1, row_bytes, "PNG pixels");
	job->rows = ss_alloc(job->held ? job->held : 1, sizeof *job->rows, "PNG rows");
	uint8_t *skip = passes == 1 ? ss_alloc(1, row_bytes, "a PNG row") : NULL;
	if (!job->pixels || !job->rows || (passes == 1 && !skip)) {
		ss_free(skip);
		return DECODE_NO_MEMORY;
	}
	for (png_uint_32 y = 0; y < job->held; y++)
		job->rows[y] = job->pixels + y * row_bytes;
	if (passes > 1) {
		png_read_image(png, job->rows);
	} else {
		/* every row is decoded (the text chunks may follow the image), the
		 * window's kept; on a libpng error skip is lost to the longjmp,
		 * so it lives in the job */
		job->skip = skip;
		for (png_uint_32 y = 0; y < job->height; y++)
			png_read_row(png, y >= job->first && y - job->first < job->held
			                  ? job->rows[y - job->first] : skip, NULL);
	}
	png_read_end(png, end);   /* text chunks may also follow the image */
	return DECODE_OK;
}

static const char *color_name(int color_type)
{
	switch (color_type) {
	case PNG_COLOR_TYPE_GRAY:       return "greyscale";
	case PNG_COLOR_TYPE_GRAY_ALPHA: return "greyscale+alpha";
	case PNG_COLOR_TYPE_PALETTE:    return "palette";
	case PNG_COLOR_TYPE_RGB:        return "RGB";
	case PNG_COLOR_TYPE_RGB_ALPHA:  return "RGBA";
	}
	return "unknown colour type";
}

/* The text chunks we know, NAN when absent. */
struct png_meta {
	double zmin, zmax, dx, dy, x0, y0;
};

static int read_meta(png_structp png, png_infop info, const char *path, const char *context,
                     struct png_meta *m)
{
	static const struct {
		const char *key;
		size_t offset;
	} keys[] = {
		{KEY_ZMIN, offsetof(struct png_meta, zmin)},
		{KEY_ZMAX, offsetof(struct png_meta, zmax)},
		{KEY_DX, offsetof(struct png_meta, dx)},
		{KEY_DY, offsetof(struct png_meta, dy)},
		{KEY_X0, offsetof(struct png_meta, x0)},
		{KEY_Y0, offsetof(struct png_meta, y0)},
	};
	png_textp text;
	const int count = png_get_text(png, info, &text, NULL);
	for (int a = 0; a < count; a++) {
		for (size_t k = 0; k < sizeof keys / sizeof *keys; k++) {
			if (strcmp(text[a].key, keys[k].key))
				continue;
			char *end;
			const double v = strtod(text[a].text, &end);
			if (end == text[a].text || *end != '\0' || !isfinite(v))
				return ss_error_input_at(context, "%s: text chunk %s = '%s' is not a finite "
				                         "number", path, text[a].key, text[a].text);
			*(double *)((char *)m + keys[k].offset) = v;
		}
	}
	return SS_OK;
}

/* A PNG being read: the file, libpng's structures and what they decoded. */
struct png_reader {
	FILE *f;
	png_structp png;
	png_infop info, end;
	struct png_job job;
};

static void reader_close(struct png_reader *rd)
{
	png_destroy_read_struct(rd->png ? &rd->png : NULL, rd->info ? &rd->info : NULL,
	                        rd->end ? &rd->end : NULL);
	ss_free(rd->job.rows);
	ss_free(rd->job.pixels);
	ss_free(rd->job.skip);
	if (rd->f)
		fclose(rd->f);
}

/* Open path and check what libpng does not before it reads: the
 * signature, and that every chunk fits in the file (png_check.h). */
static int reader_open(struct png_reader *rd, const char *path, const char *context)
{
	memset(rd, 0, sizeof *rd);
	if (!(rd->f = fopen(path, "rb")))
		return ss_error_input_at(context, "cannot open '%s': %s", path, strerror(errno));
	png_byte sig[8];
	if (fread(sig, 1, 8, rd->f) != 8 || png_sig_cmp(sig, 0, 8))
		return ss_error_input_at(context, "'%s' is not a PNG file: expected a 16-bit "
		                         "greyscale PNG heightmap", path);
	char chunk[5];
	unsigned long chunk_bytes;
	if (ss_png_check_chunks(rd->f, chunk, &chunk_bytes))
		return ss_error_input_at(context, "cannot decode PNG '%s': chunk %s claims %lu "
		                         "bytes, more than the file holds: the file is truncated "
		                         "or corrupt", path, chunk, chunk_bytes);
	struct stat st;
	rd->job.file_bytes = fstat(fileno(rd->f), &st) == 0 ? (double)st.st_size : INFINITY;
	rd->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, rd->job.message, on_error,
	                                 on_warning);
	rd->info = rd->png ? png_create_info_struct(rd->png) : NULL;
	rd->end = rd->png ? png_create_info_struct(rd->png) : NULL;
	if (!rd->png || !rd->info || !rd->end)
		return ss_error_fail("cannot read '%s': out of memory in libpng", path);
	return SS_OK;
}

/* Decode the image, saying why one is refused. */
static int reader_decode(struct png_reader *rd, const char *path, const char *context)
{
	const struct png_job *job = &rd->job;
	switch (decode(rd->png, rd->info, rd->end, rd->f, &rd->job)) {
	case DECODE_OK:
		break;
	case DECODE_PNG_ERROR:
		return ss_error_input_at(context, "cannot decode PNG '%s': %s", path, job->message);
	case DECODE_NOT_GRAY16:
		return ss_error_input_at(context, "'%s' is a %d-bit %s PNG: expected a 16-bit "
		                         "greyscale heightmap (colour type grey, bit depth 16, no "
		                         "alpha)", path, job->bit_depth, color_name(job->color_type));
	case DECODE_NO_MEMORY:
		return SS_ERR_FAIL;
	case DECODE_TOO_SHORT:
		return ss_error_input_at(context, "cannot decode PNG '%s': %.0f bytes cannot hold "
		                         "%u x %u 16-bit pixels: the file is truncated or corrupt",
		                         path, job->file_bytes, (unsigned)job->width,
		                         (unsigned)job->height);
	}
	if (job->width > 1u << 30 || job->height > 1u << 30)
		return ss_error_input_at(context, "'%s' is %u x %u pixels: at most 2^30 a side",
		                         path, (unsigned)job->width, (unsigned)job->height);
	return SS_OK;
}

/* How grey becomes height: zoffset + zscale * grey with the options' scale,
 * else the gray16 rule between the text chunks' zmin and zmax. */
struct grey_map {
	int given;              /* the options' zscale */
	double zscale, zoffset;
	int trns_grey;          /* the tRNS grey (no data), or NO_GREY */
	struct png_meta m;
};

static int grey_map(const struct png_reader *rd, const struct ss_dem_read_options *opt,
                    const char *path, const char *context, struct grey_map *g)
{
	int err;
	g->m = (struct png_meta){NAN, NAN, NAN, NAN, NAN, NAN};
	if ((err = read_meta(rd->png, rd->info, path, context, &g->m)) ||
	    (err = read_meta(rd->png, rd->end, path, context, &g->m)))
		return err;
	if ((!isnan(g->m.dx) && !(g->m.dx > 0.0)) || (!isnan(g->m.dy) && !(g->m.dy > 0.0)))
		return ss_error_input_at(context, "%s: text chunk " KEY_DX " or " KEY_DY " is not > 0",
		                         path);
	g->given = !isnan(opt->zscale);
	if (!g->given && (isnan(g->m.zmin) || isnan(g->m.zmax)))
		return ss_error_input_at(context, "%s: 16-bit PNG without a height range (no text "
		                         "chunks " KEY_ZMIN " and " KEY_ZMAX "): give the vertical "
		                         "scale zscale (m per grey level) and zoffset (m at grey 0)",
		                         path);
	g->zscale = g->given ? opt->zscale : (g->m.zmax - g->m.zmin) / 65534.0;
	g->zoffset = g->given && !isnan(opt->zoffset) ? opt->zoffset : 0.0;
	png_color_16p trns = NULL;
	g->trns_grey = png_get_tRNS(rd->png, rd->info, NULL, NULL, &trns) && trns ? trns->gray
	                                                                        : NO_GREY;
	return SS_OK;
}

/* The pixels as heights into r (south row first), no data where grey 0
 * (the gray16 rule) or the tRNS grey says. */
static int greys_to_heights(const struct png_reader *rd, const struct grey_map *g,
                            const char *path, const char *context, struct ss_raster *r)
{
	const size_t n = ss_raster_cells(r);
	if (!(r->values = ss_alloc(n ? n : 1, sizeof(double), "raster heights")))
		return SS_ERR_FAIL;
	const int north = r->ny - r->row_first - r->rows;   /* file rows before the window */
	for (int row = north; row < north + r->rows; row++) {   /* north row first in the file */
		const size_t j = (size_t)(r->ny - 1 - row - r->row_first);
		const uint8_t *p = rd->job.rows[row - (int)rd->job.first];
		for (int i = 0; i < r->nx; i++) {
			const int grey = p[2 * i] << 8 | p[2 * i + 1];
			if (grey == g->trns_grey || (grey == 0 && !g->given)) {
				if (!r->nodata && !(r->nodata = ss_alloc(n, 1, "nodata flags")))
					return SS_ERR_FAIL;
				r->nodata[j * r->nx + i] = 1;
				continue;
			}
			/* both ends of the stored range come back exactly */
			const double h = g->given ? g->zoffset + g->zscale * grey
			               : grey == 65535 ? g->m.zmax : g->m.zmin + (grey - 1) * g->zscale;
			if (!isfinite(h))
				return ss_error_input_at(context, "%s: grey %d of %s gives height %g: the "
				                         "range is too large", path, grey,
				                         SS_RASTER_CELL(r, i, r->ny - 1 - row), h);
			r->values[j * r->nx + i] = h;
		}
	}
	return SS_OK;
}

int ss_dem_read_png(const char *path, const char *context, const struct ss_dem_read_options *opt,
                    struct ss_raster *r)
{
	struct png_reader rd;
	struct grey_map g;
	int err = reader_open(&rd, path, context);
	rd.job.want_first = opt->row_first;
	rd.job.want_rows = opt->rows;
	if (!err)
		err = reader_decode(&rd, path, context);
	if (!err)
		err = grey_map(&rd, opt, path, context, &g);
	if (!err) {
		r->nx = (int)rd.job.width;
		r->ny = (int)rd.job.height;
		if (!g.given) {
			r->png_zmin = g.m.zmin;
			r->png_zmax = g.m.zmax;
		}
		r->cellsize = g.m.dx;
		r->cellsize_y = isnan(g.m.dy) ? g.m.dx : g.m.dy;
		r->x0 = g.m.x0;
		r->y0 = g.m.y0;
		err = ss_dem_window(opt, path, context, r);
		if (!err)
			err = greys_to_heights(&rd, &g, path, context, r);
	}
	reader_close(&rd);
	return err;
}

/* ------------------------------------------------------------------ */
/* writing                                                              */

/* A PNG being written: libpng's structures and one row of samples. */
struct png_out {
	char message[ERROR_SIZE];
	png_structp png;
	png_infop info;
	uint8_t *row;   /* one row of big-endian samples */
};

static int encode_header(struct png_out *o, FILE *f, const struct ss_raster *r,
                         png_textp text, int text_count)
{
	if (setjmp(png_jmpbuf(o->png)))
		return -1;
	png_init_io(o->png, f);
	png_set_IHDR(o->png, o->info, (png_uint_32)r->nx, (png_uint_32)r->ny, 16,
	             PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
	             PNG_FILTER_TYPE_DEFAULT);
	png_set_text(o->png, o->info, text, text_count);
	png_color_16 transparent = {0};   /* grey 0: no data */
	png_set_tRNS(o->png, o->info, NULL, 0, &transparent);
	png_write_info(o->png, o->info);
	return 0;
}

static int encode_row(struct png_out *o)
{
	if (setjmp(png_jmpbuf(o->png)))
		return -1;
	png_write_row(o->png, o->row);
	return 0;
}

static int encode_end(struct png_out *o)
{
	if (setjmp(png_jmpbuf(o->png)))
		return -1;
	png_write_end(o->png, o->info);
	return 0;
}

int ss_dem_png_begin(struct ss_dem_writer *w)
{
	const struct ss_raster *r = w->head;
	struct png_out *o = ss_alloc(1, sizeof *o, "a PNG writer");
	if (!o)
		return SS_ERR_FAIL;
	memset(o, 0, sizeof *o);
	w->state = o;

	/* the renderer's gray16 chunks, then the geometry; numbers as "%.17g"
	 * so they read back exactly */
	enum { MAX_TEXT = 10 };
	char num[MAX_TEXT][40];
	const char *keys[MAX_TEXT], *values[MAX_TEXT];
	int n = 0;
	const double dy = ss_dem_dy(r);
#define TEXT(k, v) (keys[n] = (k), values[n] = (v), n++)
#define NUMBER(k, x) (snprintf(num[n], sizeof num[n], "%.17g", (x)), TEXT(k, num[n]))
	TEXT("Software", "sandslide " SS_VERSION);
	TEXT("style", "gray16");
	NUMBER(KEY_ZMIN, w->zmin);
	NUMBER(KEY_ZMAX, w->zmax);
	TEXT("height_m", "zmin_m + (value - 1) * (zmax_m - zmin_m) / 65534 for value >= 1; "
	                 "value 0: wall or no data (transparent)");
	if (r->cellsize > 0.0)
		NUMBER(KEY_DX, r->cellsize);
	if (r->cellsize > 0.0 && dy > 0.0 && dy != r->cellsize)
		NUMBER(KEY_DY, dy);
	if (isfinite(r->x0) && isfinite(r->y0)) {
		NUMBER(KEY_X0, r->x0);
		NUMBER(KEY_Y0, r->y0);
	}
#undef NUMBER
#undef TEXT
	png_text text[MAX_TEXT];
	memset(text, 0, sizeof text);
	for (int a = 0; a < n; a++) {
		text[a].compression = PNG_TEXT_COMPRESSION_NONE;
		text[a].key = (png_charp)keys[a];
		text[a].text = (png_charp)values[a];
		text[a].text_length = strlen(values[a]);
	}
	o->row = ss_alloc((size_t)r->nx, 2, "a PNG row");
	o->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, o->message, on_error, on_warning);
	o->info = o->png ? png_create_info_struct(o->png) : NULL;
	if (!o->row)
		return SS_ERR_FAIL;
	if (!o->png || !o->info)
		return ss_error_fail("cannot write '%s': out of memory in libpng", w->path);
	if (encode_header(o, w->f, r, text, n))
		return ss_error_fail("cannot write '%s': %s", w->path, o->message);
	return SS_OK;
}

int ss_dem_png_rows(struct ss_dem_writer *w, const double *values, const uint8_t *nodata,
                    int rows)
{
	struct png_out *o = w->state;
	const int nx = w->head->nx;
	/* the renderer's rounding: v = 1 + round((h - zmin) / (zmax - zmin) * 65534) */
	const double to_steps = w->zmax > w->zmin ? 65534.0 / (w->zmax - w->zmin) : 0.0;
	for (int k = 0; k < rows; k++) {
		const double *h = values + (size_t)k * nx;
		const uint8_t *flag = nodata ? nodata + (size_t)k * nx : NULL;
		for (int i = 0; i < nx; i++) {
			long grey = 0;
			if (!flag || !flag[i]) {
				const double s = (h[i] - w->zmin) * to_steps;
				grey = 1 + (s <= 0.0 ? 0 : s >= 65534.0 ? 65534 : (long)(s + 0.5));
			}
			o->row[2 * i] = (uint8_t)(grey >> 8);
			o->row[2 * i + 1] = (uint8_t)(grey & 0xff);
		}
		if (encode_row(o))
			return ss_error_fail("cannot write '%s': %s", w->path, o->message);
	}
	return SS_OK;
}

int ss_dem_png_end(struct ss_dem_writer *w)
{
	struct png_out *o = w->state;
	int err = SS_OK;
	if (!o)
		return SS_OK;
	if (o->png && o->info && !w->err && w->line == w->head->ny && encode_end(o))
		err = ss_error_fail("cannot write '%s': %s", w->path, o->message);
	png_destroy_write_struct(o->png ? &o->png : NULL, o->info ? &o->info : NULL);
	ss_free(o->row);
	ss_free(o);
	w->state = NULL;
	return err;
}
