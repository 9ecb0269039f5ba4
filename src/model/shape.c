/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * shape.c - rasterising case regions onto the grid (see shape.h).
 *
 * Mask images are decoded by io/png_mask.c; the image's top row is the
 * grid's north row.
 */
#include "sandslide/shape.h"

#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "io/png_mask.h"
#include "sandslide/error.h"

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

/* A mask image (io/png_mask.h decodes it): its top row is the grid's
 * north row; a block (a rank's slab, grid.h) takes its own rows. */
static int read_mask(const struct ss_shape *s, const struct ss_grid *g, uint8_t *mask,
                     long long *covered)
{
	uint8_t *pixels;
	const int err = ss_png_read_mask(s->mask_path, s->where, g->global_nx, g->global_ny,
	                                 &pixels);
	if (err)
		return err;
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

int ss_shape_parse_numbers(enum ss_shape_kind kind, const char *value, struct ss_shape *s)
{
	double v[4];
	const int want = kind == SS_SHAPE_RECT ? 4 : kind == SS_SHAPE_DISK ? 3 : 0;
	if (!want || ss_parse_numbers(value, 1, v, 4) != want)
		return -1;
	if (kind == SS_SHAPE_RECT && !(v[0] < v[2] && v[1] < v[3]))
		return -1;
	if (kind == SS_SHAPE_DISK && !(v[2] > 0.0))
		return -1;
	s->kind = kind;
	memcpy(s->v, v, sizeof v);
	return 0;
}

const char *ss_shape_expected(enum ss_shape_kind kind)
{
	switch (kind) {
	case SS_SHAPE_RECT:
		return "'X0 Y0 X1 Y1' in m with X0 < X1 and Y0 < Y1";
	case SS_SHAPE_DISK:
		return "'X Y R' in m with R > 0";
	case SS_SHAPE_POLYGON:
		return "pairs of numbers 'X Y X Y ...' in m, at least 3";
	default:
		return "rect, disk, polygon or mask";
	}
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
