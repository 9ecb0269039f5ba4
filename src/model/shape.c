/*
 * shape.c - rasterising case regions onto the grid (see shape.h).
 *
 * Mask images are read with libpng's simplified API as 8-bit grey; the
 * image's top row is the grid's north row.
 */
#include "sandslide/shape.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>

#include "sandslide/error.h"
#include "io/png_check.h"

/* Even-odd rule: count crossings of the ray from (x, y) towards +x. */
static int polygon_contains(const double *xy, int n, double x, double y)
{
	int inside = 0;
	for (int a = 0, b = n - 1; a < n; b = a++) {
		const double xa = xy[2 * a], ya = xy[2 * a + 1];
		const double xb = xy[2 * b], yb = xy[2 * b + 1];
		if ((ya > y) != (yb > y) && x < (xb - xa) * (y - ya) / (yb - ya) + xa)
			inside = !inside;
	}
	return inside;
}

static int read_mask(const struct ss_shape *s, const struct ss_grid *g, uint8_t *mask,
                     long long *covered)
{
	FILE *f = fopen(s->mask_path, "rb");
	if (!f)
		return ss_error_input("%s: cannot open mask '%s': %s", s->where, s->mask_path,
		                      strerror(errno));
	char chunk[5];
	unsigned long chunk_bytes;
	const int bad = ss_png_check_chunks(f, chunk, &chunk_bytes);
	fclose(f);
	if (bad)
		return ss_error_input("%s: mask '%s' is not a readable PNG: chunk %s claims %lu bytes, "
		                      "more than the file holds (truncated or corrupt)", s->where,
		                      s->mask_path, chunk, chunk_bytes);

	png_image image;
	memset(&image, 0, sizeof image);
	image.version = PNG_IMAGE_VERSION;
	if (!png_image_begin_read_from_file(&image, s->mask_path))
		return ss_error_input("%s: mask '%s' is not a readable PNG: %s", s->where,
		                      s->mask_path, image.message);
	if (image.width != (png_uint_32)g->global_nx || image.height != (png_uint_32)g->global_ny) {
		png_image_free(&image);
		return ss_error_input("%s: mask '%s' is %u x %u pixels: expected the grid's "
		                      "%lld x %lld (nx x ny)", s->where, s->mask_path,
		                      (unsigned)image.width, (unsigned)image.height,
		                      g->global_nx, g->global_ny);
	}
	image.format = PNG_FORMAT_GRAY;
	uint8_t *pixels = ss_alloc(PNG_IMAGE_SIZE(image), 1, "mask pixels");
	if (!pixels) {
		png_image_free(&image);
		return SS_ERR_FAIL;
	}
	if (!png_image_finish_read(&image, NULL, pixels, 0, NULL)) {
		ss_free(pixels);
		return ss_error_input("%s: cannot decode mask '%s': %s", s->where,
		                      s->mask_path, image.message);
	}
	/* the image's top row is the grid's north row; a block (a rank's
	 * slab, grid.h) takes its own rows */
	for (int j = 0; j < g->ny; j++) {
		const uint8_t *row = pixels + (size_t)(g->global_ny - 1 - (g->offset_j + j)) * g->nx;
		for (int i = 0; i < g->nx; i++) {
			if (row[i]) {
				mask[(size_t)j * g->nx + i] = 1;
				(*covered)++;
			}
		}
	}
	ss_free(pixels);
	return SS_OK;
}

int ss_shape_rasterize(const struct ss_shape *s, const struct ss_grid *g,
                       uint8_t *mask, long long *covered)
{
	*covered = 0;
	if (s->kind == SS_SHAPE_MASK)
		return read_mask(s, g, mask, covered);

	long long count = 0;
	#pragma omp parallel for schedule(static) reduction(+:count)
	for (int j = 0; j < g->ny; j++) {
		const double y = ss_grid_y(g, j);
		for (int i = 0; i < g->nx; i++) {
			const double x = ss_grid_x(g, i);
			int in = 0;
			switch (s->kind) {
			case SS_SHAPE_RECT:
				in = x >= s->v[0] && x <= s->v[2] && y >= s->v[1] && y <= s->v[3];
				break;
			case SS_SHAPE_DISK:
				in = (x - s->v[0]) * (x - s->v[0]) + (y - s->v[1]) * (y - s->v[1]) <=
				     s->v[2] * s->v[2];
				break;
			case SS_SHAPE_POLYGON:
				in = polygon_contains(s->polygon, s->polygon_points, x, y);
				break;
			default:
				break;
			}
			if (in) {
				mask[(size_t)j * g->nx + i] = 1;
				count++;
			}
		}
	}
	*covered = count;
	return SS_OK;
}
