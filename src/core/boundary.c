/*
 * boundary.c - halo fill for wall, open and periodic sides (see boundary.h).
 *
 * One routine serves both fields: the x sides first (rows 0..ny-1), then the
 * y sides across the full width including the x ghosts.
 */
#include "sandslide/boundary.h"

#include <string.h>

#include "sandslide/error.h"

static const char *const side_kind_names[] = {"wall", "open", "periodic"};
static const char *const side_names[] = {"west", "east", "south", "north"};

int ss_side_kind_parse(const char *name, enum ss_side_kind *kind)
{
	for (int k = 0; k < 3; k++) {
		if (strcmp(name, side_kind_names[k]) == 0) {
			*kind = (enum ss_side_kind)k;
			return 0;
		}
	}
	return -1;
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

void ss_boundary_fill_types(const struct ss_grid *g, const struct ss_boundary *b,
                            uint8_t *cell_types)
{
	const int nx = g->nx, ny = g->ny;
	for (int j = 0; j < ny; j++) {
		fill_type(cell_types, ss_grid_index(g, -1, j), ss_grid_index(g, nx - 1, j),
		          b->side[SS_WEST]);
		fill_type(cell_types, ss_grid_index(g, nx, j), ss_grid_index(g, 0, j),
		          b->side[SS_EAST]);
	}
	for (int i = -1; i <= nx; i++) {
		fill_type(cell_types, ss_grid_index(g, i, -1), ss_grid_index(g, i, ny - 1),
		          b->side[SS_SOUTH]);
		fill_type(cell_types, ss_grid_index(g, i, ny), ss_grid_index(g, i, 0),
		          b->side[SS_NORTH]);
	}
}

void ss_boundary_fill_heights(const struct ss_grid *g, const struct ss_boundary *b,
                              double *height)
{
	const int nx = g->nx, ny = g->ny;
	const double level = b->open_level;
	for (int j = 0; j < ny; j++) {
		FILL_SIDE(height, ss_grid_index(g, -1, j), ss_grid_index(g, nx - 1, j),
		          b->side[SS_WEST], 0.0, level);
		FILL_SIDE(height, ss_grid_index(g, nx, j), ss_grid_index(g, 0, j),
		          b->side[SS_EAST], 0.0, level);
	}
	for (int i = -1; i <= nx; i++) {
		FILL_SIDE(height, ss_grid_index(g, i, -1), ss_grid_index(g, i, ny - 1),
		          b->side[SS_SOUTH], 0.0, level);
		FILL_SIDE(height, ss_grid_index(g, i, ny), ss_grid_index(g, i, 0),
		          b->side[SS_NORTH], 0.0, level);
	}
}
