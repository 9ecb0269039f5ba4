/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * boundary.h - the halo ring of a block: the four sides of the grid are
 * wall, open or periodic (doc/model.md#cell-types-and-sides).
 *
 *   wall      ghost cells are walls: no flux, mirror ghost for gradients
 *   open      ghost cells are open cells held at open_level (Dirichlet)
 *   periodic  ghost cells copy type and height of the opposite edge
 *
 * Types are filled once, heights before every sweep.  A distributed run
 * would replace the periodic copies and the block-internal sides by halo
 * exchanges; the kernels do not change.
 */
#ifndef SANDSLIDE_BOUNDARY_H
#define SANDSLIDE_BOUNDARY_H

#include <stdint.h>

#include "sandslide/grid.h"

enum ss_side_kind {
	SS_SIDE_WALL,
	SS_SIDE_OPEN,
	SS_SIDE_PERIODIC,
};

enum ss_side { SS_WEST, SS_EAST, SS_SOUTH, SS_NORTH };

struct ss_boundary {
	enum ss_side_kind side[4];  /* indexed by enum ss_side */
	double open_level;          /* height held on open cells and ghosts, m */
};

/* Parse "wall", "open" or "periodic"; returns 0, or -1 if unknown. */
int ss_side_kind_parse(const char *name, enum ss_side_kind *kind);
/* "wall", "open" or "periodic". */
const char *ss_side_kind_name(enum ss_side_kind kind);
/* "west", "east", "south" or "north". */
const char *ss_side_name(enum ss_side side);

/* SS_ERR_INPUT unless opposite sides are both periodic or both not. */
int ss_boundary_check(const struct ss_boundary *b);

/* Ghost cell types (packed, grid.h).  The x sides are filled for rows 0..ny-1, then the y
 * sides for the whole width, so a corner takes the y side's rule (periodic
 * in both directions copies the diagonal corner). */
void ss_boundary_fill_types(const struct ss_grid *g, const struct ss_boundary *b,
                            uint8_t *cell_types);

/* Ghost heights, in the same order: 0 behind a wall, open_level beyond an
 * open side. */
void ss_boundary_fill_heights(const struct ss_grid *g, const struct ss_boundary *b,
                              double *height);

/* The same for any field with the values it takes behind a wall and
 * beyond an open side (the bedrock: -infinity for both, no sand lies
 * outside the grid). */
void ss_boundary_fill_field(const struct ss_grid *g, const struct ss_boundary *b,
                            double *field, double wall_value, double open_value);

/* The same for each cell's material (stepper.h): a ghost beyond a wall or
 * an open side takes the material of the cell beside it. */
void ss_boundary_fill_materials(const struct ss_grid *g, const struct ss_boundary *b,
                                uint16_t *material);

/* For a slab of a distributed grid (grid.h, comm.h) both fills take the
 * ghost rows that face a neighbour rank from it, whole, after the x sides
 * (collective: every rank calls them together).  Those neighbours, or -1
 * where the side's own rule applies (always for a whole grid). */
void ss_boundary_neighbours(const struct ss_grid *g, const struct ss_boundary *b,
                            int *south, int *north);

#endif
