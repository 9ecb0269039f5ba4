/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * png.c - pictures in memory and their PNG encoding (step 3 of a frame).
 *
 * libpng's simplified API cannot write text chunks, and the frames must
 * carry their time and height scale, so this uses the classic write API:
 * errors come back through a longjmp to the one setjmp below.  16-bit
 * samples are kept native in memory and swapped to the PNG's big-endian
 * order by libpng on little-endian machines.
 *
 * A picture is encoded in memory (ss_render_encode_png, which the HTML
 * viewer embeds as it is) and a frame then written as "NAME.partial" and
 * renamed to NAME once it is complete and closed
 * (ss_render_write_file), so a picture with the final name is always
 * whole, even if the program is killed while writing.
 */
#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>

#include "base/strings.h"
#include "sandslide/error.h"

int ss_render_image_init(struct ss_render_image *img, int width, int height,
                         int channels, int bit_depth)
{
	memset(img, 0, sizeof *img);
	img->time = NAN;
	img->zmin = img->zmax = NAN;
	img->snapshot = -1;
	img->px_dx = img->px_dy = img->x0 = img->y0 = NAN;
	if (width < 1 || height < 1 || (channels != 1 && channels != 3) ||
	    (bit_depth != 8 && bit_depth != 16))
		SS_BUG("image %d x %d, %d channels, %d bits", width, height, channels, bit_depth);
	img->width = width;
	img->height = height;
	img->channels = channels;
	img->bit_depth = bit_depth;
	img->row_bytes = (size_t)width * (size_t)channels * (size_t)(bit_depth / 8);
	/* not zeroed: every style writes every pixel, and the threads that do
	 * so first-touch the pages in parallel instead of one memset here */
	if ((size_t)height > SIZE_MAX / img->row_bytes) {
		ss_error_fail("cannot allocate a picture of %d x %d px: size overflows", width, height);
		return SS_ERR_FAIL;
	}
	img->pixels = malloc((size_t)height * img->row_bytes);
	if (!img->pixels)
		return ss_error_fail("cannot allocate a picture of %d x %d px", width, height);
	return SS_OK;
}

void ss_render_image_release(struct ss_render_image *img)
{
	free(img->pixels);
	img->pixels = NULL;
}

/* libpng reports errors here; the message is kept for ours. */
struct png_failure {
	char message[256];
};

static void on_png_error(png_structp png, png_const_charp message)
{
	struct png_failure *f = png_get_error_ptr(png);
	snprintf(f->message, sizeof f->message, "%s", message);
	png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp message)
{
	(void)png;
	(void)message;   /* nothing we write can warrant one */
}

static int host_is_little_endian(void)
{
	const uint16_t one = 1;
	return *(const uint8_t *)&one == 1;
}

/* The text chunks: enough to know what a frame shows and, for gray16, to
 * turn its samples back into heights. */
enum { NUMBER_SIZE = 40 };

struct png_texts {
	png_text t[12];
	int n;
	char software[64];
	char number[8][NUMBER_SIZE];   /* the values written as text */
	int numbers;
};

static void add_text(struct png_texts *x, const char *key, const char *value)
{
	png_text *t = &x->t[x->n++];
	memset(t, 0, sizeof *t);
	t->compression = PNG_TEXT_COMPRESSION_NONE;
	t->key = (png_charp)key;
	t->text = (png_charp)value;
	t->text_length = strlen(value);
}

/* Two numbers that go together (ss_real_text: the shortest text that
 * reads back exactly), both or neither: a known NaN of either leaves both
 * out. */
static void add_pair(struct png_texts *x, const char *key_a, double a, const char *key_b,
                     double b)
{
	if (isnan(a) || isnan(b))
		return;
	char *text_a = x->number[x->numbers++], *text_b = x->number[x->numbers++];
	snprintf(text_a, NUMBER_SIZE, "%s", SS_REAL(a));
	snprintf(text_b, NUMBER_SIZE, "%s", SS_REAL(b));
	add_text(x, key_a, text_a);
	add_text(x, key_b, text_b);
}

static void fill_texts(struct png_texts *x, const struct ss_render_image *img)
{
	x->n = 0;
	x->numbers = 0;
	snprintf(x->software, sizeof x->software, "sandslide %s", SS_VERSION);
	add_text(x, "Software", x->software);
	if (img->source[0])
		add_text(x, "Source", img->source);
	add_text(x, "style", ss_render_style_name(img->style));
	if (!isnan(img->time)) {
		snprintf(x->number[x->numbers++], NUMBER_SIZE, "%s", SS_REAL(img->time));
		add_text(x, "time_s", x->number[x->numbers - 1]);
	}
	add_pair(x, "zmin_m", img->zmin, "zmax_m", img->zmax);
	if (img->snapshot >= 0) {
		snprintf(x->number[x->numbers++], NUMBER_SIZE, "%lld", img->snapshot);
		add_text(x, "snapshot", x->number[x->numbers - 1]);
	}
	/* the map's geometry, so that a gray16 frame is a DEM (dem.h) */
	add_pair(x, "dx_m", img->px_dx, "dy_m", img->px_dy);
	add_pair(x, "x0_m", img->x0, "y0_m", img->y0);
	if (img->style == SS_RENDER_GRAY16)
		add_text(x, "height_m", "zmin_m + (value - 1) * (zmax_m - zmin_m) / 65534 for "
		                        "value >= 1; value 0: wall or no data (transparent)");
}

/* The PNG's bytes as libpng hands them over: a buffer that grows. */
struct png_sink {
	unsigned char *data;
	size_t size, capacity;
};

static void on_png_write(png_structp png, png_bytep bytes, png_size_t n)
{
	struct png_sink *s = png_get_io_ptr(png);
	if (n > s->capacity - s->size) {
		size_t cap = s->capacity ? s->capacity : 1 << 16;
		while (cap - s->size < n) {
			if (cap > SIZE_MAX / 2)
				png_error(png, "out of memory");
			cap *= 2;
		}
		unsigned char *more = realloc(s->data, cap);
		if (!more)
			png_error(png, "out of memory");
		s->data = more;
		s->capacity = cap;
	}
	memcpy(s->data + s->size, bytes, n);
	s->size += n;
}

static void on_png_flush(png_structp png)
{
	(void)png;   /* memory needs no flushing */
}

/* Encode img into sink; returns 0, or -1 with failure->message (the sink
 * is then freed). */
static int encode(const struct ss_render_image *img, int compression, struct png_sink *sink,
                  struct png_failure *failure)
{
	png_bytep *rows = malloc((size_t)img->height * sizeof *rows);
	if (!rows) {
		snprintf(failure->message, sizeof failure->message, "out of memory");
		return -1;
	}
	for (int y = 0; y < img->height; y++)
		rows[y] = img->pixels + (size_t)y * img->row_bytes;
	struct png_texts texts;
	fill_texts(&texts, img);

	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, failure, on_png_error,
	                                          on_png_warning);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!png || !info) {
		png_destroy_write_struct(&png, &info);
		free(rows);
		snprintf(failure->message, sizeof failure->message, "out of memory");
		return -1;
	}
	if (setjmp(png_jmpbuf(png))) {
		png_destroy_write_struct(&png, &info);
		free(rows);
		free(sink->data);
		*sink = (struct png_sink){0};
		return -1;
	}
	png_set_write_fn(png, sink, on_png_write, on_png_flush);
	png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height,
	             img->bit_depth, img->channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
	             PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	png_set_compression_level(png, compression);
	png_set_text(png, info, texts.t, texts.n);
	if (img->style == SS_RENDER_GRAY16 && img->channels == 1) {
		png_color_16 transparent = {0};   /* grey 0: walls, no data */
		png_set_tRNS(png, info, NULL, 0, &transparent);
	}
	png_write_info(png, info);
	if (img->bit_depth == 16 && host_is_little_endian())
		png_set_swap(png);
	png_write_image(png, rows);
	png_write_end(png, NULL);
	png_destroy_write_struct(&png, &info);
	free(rows);
	return 0;
}

int ss_render_encode_png(const struct ss_render_image *img, int compression,
                         unsigned char **data, size_t *size)
{
	struct png_sink sink = {0};
	struct png_failure failure = {""};
	*data = NULL;
	*size = 0;
	if (encode(img, compression, &sink, &failure))
		return ss_error_fail("cannot encode a picture of %d x %d px as PNG: %s", img->width,
		                     img->height, failure.message);
	*data = sink.data;
	*size = sink.size;
	return SS_OK;
}

int ss_render_write_file(const char *path, const void *data, size_t size)
{
	const size_t n = strlen(path) + sizeof ".partial";
	char *tmp = malloc(n);
	if (!tmp)
		return ss_error_fail("out of memory");
	snprintf(tmp, n, "%s.partial", path);

	FILE *f = fopen(tmp, "wb");
	if (!f) {
		int err = ss_error_fail("cannot write '%s': %s", tmp, strerror(errno));
		free(tmp);
		return err;
	}
	int e = 0;
	errno = 0;
	if (fwrite(data, 1, size, f) != size || fflush(f) != 0 || ferror(f))
		e = errno ? errno : EIO;
	if (fclose(f) != 0 && !e)
		e = errno;
	if (!e && rename(tmp, path) != 0)
		e = errno;
	int err = SS_OK;
	if (e) {
		remove(tmp);
		err = ss_error_fail("cannot write '%s': %s", path, strerror(e));
	}
	free(tmp);
	return err;
}

int ss_render_write_png(const struct ss_render_image *img, const char *path, int compression)
{
	struct png_sink sink = {0};
	struct png_failure failure = {""};
	if (encode(img, compression, &sink, &failure))
		return ss_error_fail("cannot write '%s': %s", path, failure.message);
	const int err = ss_render_write_file(path, sink.data, sink.size);
	free(sink.data);
	return err;
}
