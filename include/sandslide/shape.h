/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * shape.h - regions of the case file (walls, open cells, sources) and their
 * rasterisation: a cell belongs to a shape when its centre does (rect and
 * disk boundaries included, polygons by the even-odd rule), or, for a mask,
 * when its pixel is not black.
 */
#ifndef SANDSLIDE_SHAPE_H
#define SANDSLIDE_SHAPE_H

#include <stdint.h>

#include "sandslide/grid.h"

/* Size of a "file:line" location string. */
#define SS_CASE_WHERE_SIZE 320

enum ss_shape_kind {
	SS_SHAPE_NONE,
	SS_SHAPE_RECT,      /* v = x0 y0 x1 y1, m */
	SS_SHAPE_DISK,      /* v = x y r, m */
	SS_SHAPE_POLYGON,   /* polygon = x y pairs, m */
	SS_SHAPE_MASK,      /* mask_path: PNG of nx x ny pixels, north row first */
};

struct ss_shape {
	enum ss_shape_kind kind;
	double v[4];
	double *polygon;        /* 2 * polygon_points values */
	int polygon_points;
	char *mask_path;        /* resolved against the case file's folder */
	char where[SS_CASE_WHERE_SIZE]; /* "file:line" of the shape key */
};

/* Parse the numbers of a rect ("X0 Y0 X1 Y1", X0 < X1 and Y0 < Y1) or a
 * disk ("X Y R", R > 0), in m, separated by white space or commas (the
 * case file writes "0 0 1 1", relax's --add-sand "rect=0,0,1,1"), into s's
 * kind and v: 0, or -1 when value is not one (s unchanged).  The one
 * place these rules are checked. */
int ss_shape_parse_numbers(enum ss_shape_kind kind, const char *value, struct ss_shape *s);

/* What a shape's value must be, for messages: "'X0 Y0 X1 Y1' in m with
 * X0 < X1 and Y0 < Y1", ... (RECT, DISK, POLYGON). */
const char *ss_shape_expected(enum ss_shape_kind kind);

/*
 * Set mask[j * nx + i] = 1 (south row first) for every cell of g inside the
 * shape, leaving the others as they are.  *covered counts the cells inside.
 * Returns SS_ERR_INPUT for an unreadable or mis-sized mask image.
 */
int ss_shape_rasterize(const struct ss_shape *s, const struct ss_grid *g,
                       uint8_t *mask, long long *covered);

#endif
