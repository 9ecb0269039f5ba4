/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * grid.h - a rectangular block of cells with a halo ring.
 *
 * Cells (i, j), i = 0..nx-1 west to east, j = 0..ny-1 south to north, are
 * stored row-major with a ghost ring of width SS_GRID_GHOST and a row stride
 * (in elements) that is at least nx + 2 ghost; the stride, never nx, is used
 * for indexing.  A block knows where it sits in the global grid
 * (offset_i, offset_j), so a distributed-memory decomposition gives each rank
 * one block and reuses every kernel unchanged: only the halo fill differs.
 */
#ifndef SANDSLIDE_GRID_H
#define SANDSLIDE_GRID_H

#include <stddef.h>
#include <stdint.h>

#define SS_GRID_GHOST 1

/* Cell types (the uint8 cell_type variable of doc/output.md#variables). */
enum ss_cell_type {
	SS_CELL_FLOW = 0,  /* sand evolves */
	SS_CELL_WALL = 1,  /* solid: no sand, no flux through its faces */
	SS_CELL_OPEN = 2,  /* held at a fixed level; inflow counts as outflow */
};

struct ss_grid {
	int nx, ny;             /* cells of this block, without halo */
	ptrdiff_t stride;       /* elements between rows, >= nx + 2 ghost */
	long long global_nx;    /* cells of the whole grid */
	long long global_ny;
	long long offset_i;     /* global index of this block's cell (0, 0) */
	long long offset_j;
	double dx, dy;          /* cell size, m */
	double origin_x;        /* lower-left corner of the global grid, m */
	double origin_y;
};

/* A single-block grid of nx x ny cells; the stride is padded to a multiple
 * of 8 elements (64 B) so every row starts aligned.  Returns SS_ERR_INPUT for
 * non-positive sizes or spacings. */
int ss_grid_init(struct ss_grid *g, int nx, int ny, double dx, double dy,
                 double origin_x, double origin_y);

/* Keep rows first .. first + rows - 1 of the whole grid g (a rank's slab,
 * stepper.h): ny and offset_j change, the global size does not. */
void ss_grid_take_rows(struct ss_grid *g, long long first, int rows);

/* Whether this block holds the whole grid (one rank). */
static inline int ss_grid_is_whole(const struct ss_grid *g)
{
	return g->nx == g->global_nx && g->ny == g->global_ny;
}

/* Elements of one field including the halo: stride * (ny + 2 ghost). */
size_t ss_grid_storage_cells(const struct ss_grid *g);

/* Index of cell (i, j); i, j may be -1 or n (the halo). */
static inline ptrdiff_t ss_grid_index(const struct ss_grid *g, int i, int j)
{
	return (ptrdiff_t)(j + SS_GRID_GHOST) * g->stride + (i + SS_GRID_GHOST);
}

/*
 * Cell types are stored packed, four cells to a byte (2 bits each, in
 * storage order: cell k in bits 2 (k mod 4) of byte k / 4), so that a cell
 * costs 8 B of height plus a quarter byte of type (the memory budget of
 * doc/performance.md#memory).  Writers are single-threaded (set-up); two threads must
 * never set cells of the same byte.
 */
static inline size_t ss_cell_types_bytes(size_t cells)
{
	return (cells + 3) / 4;
}

static inline enum ss_cell_type ss_cell_type_get(const uint8_t *types, ptrdiff_t k)
{
	return (enum ss_cell_type)(types[k >> 2] >> (2 * (k & 3)) & 3);
}

static inline void ss_cell_type_set(uint8_t *types, ptrdiff_t k, enum ss_cell_type type)
{
	const unsigned shift = 2 * (unsigned)(k & 3);
	types[k >> 2] = (uint8_t)((types[k >> 2] & ~(3u << shift)) | ((unsigned)type << shift));
}

/* One byte per cell for cells k0 .. k0 + n - 1 of packed types, into out. */
void ss_cell_types_unpack(const uint8_t *types, ptrdiff_t k0, size_t n, uint8_t *out);

/* Cell-centre coordinates, m. */
static inline double ss_grid_x(const struct ss_grid *g, int i)
{
	return g->origin_x + ((double)(g->offset_i + i) + 0.5) * g->dx;
}
static inline double ss_grid_y(const struct ss_grid *g, int j)
{
	return g->origin_y + ((double)(g->offset_j + j) + 0.5) * g->dy;
}

#endif
