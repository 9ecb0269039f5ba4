/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * grid.c - block geometry (see grid.h).
 */
#include "sandslide/grid.h"

#include <math.h>

#include "sandslide/error.h"

int ss_grid_init(struct ss_grid *g, int nx, int ny, double dx, double dy,
                 double origin_x, double origin_y)
{
	if (nx < 1 || ny < 1)
		return ss_error_input("grid size %d x %d: nx and ny must be >= 1", nx, ny);
	if (!(dx > 0.0) || !(dy > 0.0) || !isfinite(dx) || !isfinite(dy))
		return ss_error_input("cell size %g x %g m: dx and dy must be finite and > 0",
		                      dx, dy);
	const ptrdiff_t row = (ptrdiff_t)nx + 2 * SS_GRID_GHOST;
	g->nx = nx;
	g->ny = ny;
	g->stride = (row + 7) / 8 * 8;
	g->global_nx = nx;
	g->global_ny = ny;
	g->offset_i = 0;
	g->offset_j = 0;
	g->dx = dx;
	g->dy = dy;
	g->origin_x = origin_x;
	g->origin_y = origin_y;
	return SS_OK;
}

void ss_grid_take_rows(struct ss_grid *g, long long first, int rows)
{
	g->offset_j += first;
	g->ny = rows;
}

size_t ss_grid_storage_cells(const struct ss_grid *g)
{
	return (size_t)g->stride * (size_t)(g->ny + 2 * SS_GRID_GHOST);
}

void ss_cell_types_unpack(const uint8_t *types, ptrdiff_t k0, size_t n, uint8_t *out)
{
	for (size_t m = 0; m < n; m++)
		out[m] = (uint8_t)ss_cell_type_get(types, k0 + (ptrdiff_t)m);
}
