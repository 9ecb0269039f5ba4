/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * boundary.c - halo fill for wall, open and periodic sides (see boundary.h).
 *
 * One routine serves both fields: the x sides first (rows 0..ny-1), then the
 * y sides across the full width including the x ghosts.  A slab of a
 * distributed grid (comm.h) takes a y ghost row from the neighbour rank
 * instead, whole: after the x sides, so the corners come along.
 */
#include "sandslide/boundary.h"

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

static const char *const side_kind_names[] = {"wall", "open", "periodic"};
static const char *const side_names[] = {"west", "east", "south", "north"};

int ss_side_kind_parse(const char *name, enum ss_side_kind *kind)
{
	const int k = ss_parse_name(name, side_kind_names, 3);
	if (k >= 0)
		*kind = (enum ss_side_kind)k;
	return k < 0 ? -1 : 0;
}

const char *ss_side_kind_name(enum ss_side_kind kind)
{
	return (unsigned)kind < 3 ? side_kind_names[kind] : "?";
}

const char *ss_side_name(enum ss_side side)
{
	return (unsigned)side < 4 ? side_names[side] : "?";
}

int ss_boundary_check(const struct ss_boundary *b)
{
	for (int s = 0; s < 4; s += 2) {
		int p0 = b->side[s] == SS_SIDE_PERIODIC;
		int p1 = b->side[s + 1] == SS_SIDE_PERIODIC;
		if (p0 != p1)
			return ss_error_input("boundary: %s and %s must both be periodic or neither",
			                      side_names[s], side_names[s + 1]);
	}
	return SS_OK;
}

/* Fill the ghost cell `ghost` from interior cell `wrap` (periodic) or with
 * the side's fixed value. */
#define FILL_SIDE(field, ghost, wrap, kind, wall_value, open_value)          \
	do {                                                                  \
		if ((kind) == SS_SIDE_PERIODIC)                               \
			(field)[ghost] = (field)[wrap];                       \
		else                                                          \
			(field)[ghost] = (kind) == SS_SIDE_WALL ? (wall_value)   \
			                                        : (open_value);  \
	} while (0)

/* The type of ghost cell `ghost` on a side of this kind; `wrap` is the
 * interior cell it copies when the side is periodic. */
static void fill_type(uint8_t *types, ptrdiff_t ghost, ptrdiff_t wrap,
                      enum ss_side_kind kind)
{
	const enum ss_cell_type t = kind == SS_SIDE_PERIODIC ? ss_cell_type_get(types, wrap)
	                          : kind == SS_SIDE_WALL ? SS_CELL_WALL : SS_CELL_OPEN;
	ss_cell_type_set(types, ghost, t);
}

void ss_boundary_neighbours(const struct ss_grid *g, const struct ss_boundary *b,
                            int *south, int *north)
{
	if (ss_grid_is_whole(g)) {
		*south = *north = -1;
		return;
	}
	ss_comm_neighbours(b->side[SS_SOUTH] == SS_SIDE_PERIODIC, south, north);
}

/* The ghost rows -1 and ny from the neighbour ranks: rows 0 and ny - 1 of
 * this slab go to them, whole (row_bytes from byte offsets first and last
 * of field). */
static void exchange_rows(int south, int north, void *field, size_t row_bytes,
                          size_t ghost_south, size_t first, size_t last, size_t ghost_north)
{
	char *f = field;
	ss_comm_exchange(south, north, f + first, f + ghost_south, f + last, f + ghost_north,
	                 row_bytes);
}

void ss_boundary_fill_types(const struct ss_grid *g, const struct ss_boundary *b,
                            uint8_t *cell_types)
{
	const int nx = g->nx, ny = g->ny;
	int south, north;
	ss_boundary_neighbours(g, b, &south, &north);
	for (int j = 0; j < ny; j++) {
		fill_type(cell_types, ss_grid_index(g, -1, j), ss_grid_index(g, nx - 1, j),
		          b->side[SS_WEST]);
		fill_type(cell_types, ss_grid_index(g, nx, j), ss_grid_index(g, 0, j),
		          b->side[SS_EAST]);
	}
	for (int i = -1; i <= nx; i++) {
		if (south < 0)
			fill_type(cell_types, ss_grid_index(g, i, -1), ss_grid_index(g, i, ny - 1),
			          b->side[SS_SOUTH]);
		if (north < 0)
			fill_type(cell_types, ss_grid_index(g, i, ny), ss_grid_index(g, i, 0),
			          b->side[SS_NORTH]);
	}
	/* a row of packed types is stride / 4 whole bytes (stride is a
	 * multiple of 8, grid.h) */
	const size_t row = (size_t)g->stride / 4;
	exchange_rows(south, north, cell_types, row, 0, row, (size_t)ny * row,
	              (size_t)(ny + 1) * row);
}

void ss_boundary_fill_heights(const struct ss_grid *g, const struct ss_boundary *b,
                              double *height)
{
	ss_boundary_fill_field(g, b, height, 0.0, b->open_level);
}

void ss_boundary_fill_field(const struct ss_grid *g, const struct ss_boundary *b,
                            double *field, double wall_value, double open_value)
{
	const int nx = g->nx, ny = g->ny;
	int south, north;
	ss_boundary_neighbours(g, b, &south, &north);
	for (int j = 0; j < ny; j++) {
		FILL_SIDE(field, ss_grid_index(g, -1, j), ss_grid_index(g, nx - 1, j),
		          b->side[SS_WEST], wall_value, open_value);
		FILL_SIDE(field, ss_grid_index(g, nx, j), ss_grid_index(g, 0, j),
		          b->side[SS_EAST], wall_value, open_value);
	}
	for (int i = -1; i <= nx; i++) {
		if (south < 0)
			FILL_SIDE(field, ss_grid_index(g, i, -1), ss_grid_index(g, i, ny - 1),
			          b->side[SS_SOUTH], wall_value, open_value);
		if (north < 0)
			FILL_SIDE(field, ss_grid_index(g, i, ny), ss_grid_index(g, i, 0),
			          b->side[SS_NORTH], wall_value, open_value);
	}
	const size_t row = (size_t)g->stride * sizeof(double);
	exchange_rows(south, north, field, row, 0, row, (size_t)ny * row,
	              (size_t)(ny + 1) * row);
}

void ss_boundary_fill_materials(const struct ss_grid *g, const struct ss_boundary *b,
                                uint16_t *material)
{
	const int nx = g->nx, ny = g->ny;
	int south, north;
	ss_boundary_neighbours(g, b, &south, &north);
	/* periodic: the cell it wraps to; else the cell beside */
	const int wrap_x = b->side[SS_WEST] == SS_SIDE_PERIODIC;
	const int wrap_y = b->side[SS_SOUTH] == SS_SIDE_PERIODIC;
	for (int j = 0; j < ny; j++) {
		material[ss_grid_index(g, -1, j)] = material[ss_grid_index(g, wrap_x ? nx - 1 : 0, j)];
		material[ss_grid_index(g, nx, j)] = material[ss_grid_index(g, wrap_x ? 0 : nx - 1, j)];
	}
	for (int i = -1; i <= nx; i++) {
		if (south < 0)
			material[ss_grid_index(g, i, -1)] =
				material[ss_grid_index(g, i, wrap_y ? ny - 1 : 0)];
		if (north < 0)
			material[ss_grid_index(g, i, ny)] =
				material[ss_grid_index(g, i, wrap_y ? 0 : ny - 1)];
	}
	const size_t row = (size_t)g->stride * sizeof *material;
	exchange_rows(south, north, material, row, 0, row, (size_t)ny * row,
	              (size_t)(ny + 1) * row);
}
