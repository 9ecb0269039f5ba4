/*
 * sweep.h - the finite-volume stencil of SPEC section 2, in two passes over
 * cache-sized tiles (the reference kernel: simple, each face computed once
 * and stored).
 *
 *   pass 1, ss_sweep_fluxes: for every face between two non-wall cells of
 *     which at least one is a flow cell, the flux per unit face length
 *        F = -nu f_sl(s) g_n / s,   s = sqrt(g_n^2 + g_t^2),
 *     with g_n the difference across the face over the spacing and g_t the
 *     mean of the two cells' central differences along the face, in which a
 *     wall neighbour is replaced by the cell itself (mirror ghost: no normal
 *     gradient into a wall).  Every other face carries 0.
 *   pass 2, ss_sweep_update: on flow cells, forward Euler
 *        h += dt (-(F_e - F_w)/dx - (F_n - F_s)/dy + q).
 *
 * Each face and each cell is written by exactly one tile, so the result is
 * the same bits for any thread count and tile size; the reductions are
 * maxima, which do not depend on order.  Pure compute: no I/O, no
 * allocation.  The caller fills the halo first (boundary.h).
 */
#ifndef SANDSLIDE_SWEEP_H
#define SANDSLIDE_SWEEP_H

#include <stdint.h>

#include "sandslide/closure.h"
#include "sandslide/grid.h"

struct ss_tiling {
	int tile_nx, tile_ny;    /* cells per tile */
	int tiles_x, tiles_y;    /* tiles covering the block */
};

#define SS_TILE_NX_DEFAULT 256
#define SS_TILE_NY_DEFAULT 32

/* Cover g with tiles of tile_nx x tile_ny cells (the last ones may be
 * smaller); sizes < 1 mean the defaults. */
void ss_tiling_init(struct ss_tiling *t, const struct ss_grid *g,
                    int tile_nx, int tile_ny);

/*
 * Pass 1.  flux_x at ss_grid_index(g, i, j) is the flux (m^2/s, positive
 * eastward) through the face between cells (i-1, j) and (i, j), i = 0..nx;
 * flux_y at ss_grid_index(g, i, j) the one (positive northward) between
 * (i, j-1) and (i, j), j = 0..ny.  Returns the largest slope s over the
 * faces that can carry flux (0 when there are none).
 */
double ss_sweep_fluxes(const struct ss_grid *g, const struct ss_tiling *t,
                       const struct ss_closure *c,
                       const double *restrict height,
                       const uint8_t *restrict cell_type,
                       double *restrict flux_x, double *restrict flux_y);

/*
 * Pass 2.  Advances flow cells by dt seconds with the fluxes of pass 1 and
 * the source rate (m/s per cell, NULL for none).  Returns max |dh/dt| over
 * flow cells, m/s.
 */
double ss_sweep_update(const struct ss_grid *g, const struct ss_tiling *t,
                       double dt, const double *restrict flux_x,
                       const double *restrict flux_y,
                       const double *restrict source_rate,
                       const uint8_t *restrict cell_type,
                       double *restrict height);

#endif
