/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * png_mask.c - mask images decoded with libpng's simplified API (see
 * png_mask.h).
 */
#include "io/png_mask.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include <png.h>

#include "io/png_check.h"
#include "sandslide/error.h"

int ss_png_read_mask(const char *path, const char *where, long long nx, long long ny,
                     uint8_t **pixels)
{
	*pixels = NULL;
	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_input("%s: cannot open mask '%s': %s", where, path, strerror(errno));
	char chunk[5];
	unsigned long chunk_bytes;
	const int bad = ss_png_check_chunks(f, chunk, &chunk_bytes);
	fclose(f);
	if (bad)
		return ss_error_input("%s: mask '%s' is not a readable PNG: chunk %s claims %lu bytes, "
		                      "more than the file holds (truncated or corrupt)", where, path,
		                      chunk, chunk_bytes);

	png_image image;
	memset(&image, 0, sizeof image);
	image.version = PNG_IMAGE_VERSION;
	if (!png_image_begin_read_from_file(&image, path))
		return ss_error_input("%s: mask '%s' is not a readable PNG: %s", where, path,
		                      image.message);
	if (image.width != (png_uint_32)nx || image.height != (png_uint_32)ny) {
		png_image_free(&image);
		return ss_error_input("%s: mask '%s' is %u x %u pixels: expected the grid's "
		                      "%lld x %lld (nx x ny)", where, path, (unsigned)image.width,
		                      (unsigned)image.height, nx, ny);
	}
	image.format = PNG_FORMAT_GRAY;
	uint8_t *p = ss_alloc(PNG_IMAGE_SIZE(image), 1, "mask pixels");
	if (!p) {
		png_image_free(&image);
		return SS_ERR_FAIL;
	}
	if (!png_image_finish_read(&image, NULL, p, 0, NULL)) {
		ss_free(p);
		return ss_error_input("%s: cannot decode mask '%s': %s", where, path, image.message);
	}
	*pixels = p;
	return SS_OK;
}
