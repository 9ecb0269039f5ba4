/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sweep.h - the finite-volume stencil of doc/model.md#discretisation, in two passes over
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
#ifndef SANDSLIDE_CORE_SWEEP_H
#define SANDSLIDE_CORE_SWEEP_H

#include <stdint.h>

#include "sandslide/closure.h"
#include "core/face.h"
#include "sandslide/grid.h"

struct ss_tiling {
	int tile_nx, tile_ny;    /* cells per tile */
	int tiles_x, tiles_y;    /* tiles covering the block */
};

/* The cells [i0, i1) x [j0, j1) of tile (tx, ty); the last tiles of a row
 * or column may be smaller. */
struct ss_tile_span {
	int i0, i1, j0, j1;
};

static inline struct ss_tile_span ss_tiling_span(const struct ss_tiling *t,
                                                 const struct ss_grid *g,
                                                 int tx, int ty)
{
	struct ss_tile_span s;
	s.i0 = tx * t->tile_nx;
	s.j0 = ty * t->tile_ny;
	s.i1 = s.i0 + t->tile_nx < g->nx ? s.i0 + t->tile_nx : g->nx;
	s.j1 = s.j0 + t->tile_ny < g->ny ? s.j0 + t->tile_ny : g->ny;
	return s;
}

#define SS_TILE_NX_DEFAULT 256
#define SS_TILE_NY_DEFAULT 128

/* Cover g with tiles of tile_nx x tile_ny cells (the last ones may be
 * smaller); sizes < 1 mean the defaults: 256 x 128, or on a small grid about
 * a quarter of its width (a multiple of 8, at least 32) by an eighth of its
 * height (at least 8). */
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
                       const struct ss_face_rule *rule,
                       const double *restrict height,
                       const uint8_t *restrict cell_type,
                       double *restrict flux_x, double *restrict flux_y);

/*
 * Between the passes, with a non-erodible bedrock (m, with halo; -infinity
 * where there is none): each flux limited by the thickness of the cell it
 * leaves (ss_face_limit, face.h) for a step of dt seconds.
 */
void ss_sweep_limit(const struct ss_grid *g, const struct ss_tiling *t, double dt,
                    const double *restrict height, const double *restrict bedrock,
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

/*
 * One stage of an RKL2 super-step (rkl2.h) as both kernels apply it to the
 * flow cells, in place of pass 2's forward Euler.  With M the rate of pass 2
 * (flux divergence plus source) at the heights Y_{j-1} of this stage, the
 * stage is carried as its increment D_j = Y_j - Y_0 (doc/model.md#rkl2-super-steps):
 *
 *   D_j = mu D_{j-1} + nu D_{j-2} + tau mu~ M(Y_{j-1}) + tau gamma~ M(Y_0)
 *   Y_j = Y_0 + D_j
 *
 * Why the increments: the heights are O(m) and the increments of a
 * super-step O(mm), and the recursion amplifies what each stage rounds
 * (its homogeneous part grows like the stage count).  Rounded at the
 * heights' scale, as Y_j = Y_0 + mu (Y_{j-1} - Y_0) + ... was, the volume
 * drifted by 3e-11 of itself over a door run at 256 stages; rounded at the
 * increments' scale, Y_j is rounded once per stage and not fed back.
 *
 * The first stage stores Y_0 and M(Y_0) (mu = nu = gamma~ = 0, D_0 = 0);
 * every stage moves D_{j-1} into d2, which held D_{j-2}.  Cells that are
 * not flow cells keep their height.  After the last stage, one more
 * evaluation (estimate_only: no height is written) estimates the
 * super-step's error from its start Y^n and M(Y^n) (y0, m0) and its change
 * D_s = Y^{n+1} - Y^n, as RKC and SUNDIALS' LSRKStep do for RKL2:
 *
 *   est = max |0.4 tau (M(Y^n) + M(Y^{n+1})) - 0.8 D_s|
 *
 * (0 for a state the trapezoidal rule would also reach; a stiff mode that
 * RKL2 damps only by its a_s ~ 1/2 where it should vanish gives ~ tau M).
 */
/* The error estimate of one cell (the same expression in both kernels). */
static inline double ss_sweep_stage_estimate(double tau, double change, double m_old,
                                             double m)
{
	return fabs(0.4 * tau * (m_old + m) - 0.8 * change);
}

struct ss_sweep_stage {
	int first;                /* stage 1: y0 <- Y_0; d1, d2 <- 0; m0 <- M(Y_0) */
	int estimate_only;        /* after the last stage: est only, no write */
	double estimate_tau;      /* estimate_only: the super-step's length, s */
	double *estimate;         /* estimate_only: out, the largest est, m */
	double mu, nu;            /* weights of D_{j-1}, D_{j-2} */
	double tau_mu, tau_gamma; /* tau mu~_j, tau gamma~_j, s */
	double *y0;               /* Y_0, m, by storage index */
	double *d1;               /* D_{j-1} in, D_j out, m */
	double *d2;               /* D_{j-2} in, D_{j-1} out, m */
	double *m0;               /* M(Y_0), m/s */
};

/* D_j of one cell: the one expression both kernels evaluate, so that they
 * give the same bits.  A cell with D_{j-1} = D_{j-2} = 0 and M = M_0 = 0
 * keeps its height exactly (Y_0 + 0). */
static inline double ss_sweep_stage_weigh(double mu, double nu, double tau_mu,
                                          double tau_gamma, double d1, double d2, double m,
                                          double m0)
{
	return (mu * d1 + nu * d2) + (tau_mu * m + tau_gamma * m0);
}

static inline double ss_sweep_stage_delta(const struct ss_sweep_stage *s, double d1,
                                          double d2, double m, double m0)
{
	return ss_sweep_stage_weigh(s->mu, s->nu, s->tau_mu, s->tau_gamma, d1, d2, m, m0);
}

/*
 * Pass 2 of an RKL2 stage with the fluxes of pass 1 and the source rate
 * (NULL: none).  Returns max |D_j| over flow cells, m (INFINITY on
 * NaN).
 */
double ss_sweep_stage_update(const struct ss_grid *g, const struct ss_tiling *t,
                             const struct ss_sweep_stage *stage,
                             const double *restrict flux_x,
                             const double *restrict flux_y,
                             const double *restrict source_rate,
                             const uint8_t *restrict cell_type,
                             double *restrict height);

/*
 * The largest slope s over the faces that can carry flux (as pass 1 returns
 * it), without computing fluxes; NaN if a height is NaN.  For diagnostics
 * and to start the fast sweep's running measure.  The fast sweep's
 * functions, from here on, read the packed cell types of grid.h; the
 * reference passes above read one byte per cell.
 */
double ss_sweep_max_slope(const struct ss_grid *g, const double *restrict height,
                          const uint8_t *restrict cell_types);

/*
 * The same over the faces whose stencil (both cells and their neighbours
 * along the face) lies in sand: every flow cell of it more than `bare` m
 * above the bedrock (m, with halo, as the stepper keeps it).  Bare rock may
 * stay steeper than the repose angle for ever, and so may a face next to a
 * rock cliff, whose step enters the tangential difference.
 */
double ss_sweep_max_sand_slope(const struct ss_grid *g, const double *restrict height,
                               const uint8_t *restrict cell_types,
                               const double *restrict bedrock, double bare);

/*
 * One face between cells a and b = a + normal (storage indices; `along`
 * the neighbour offset along it, the spacings' inverses): its s^2 into
 * *s2 (0 where it cannot carry flux) and, returned, its sliding flux over
 * nu at closure c, f(s) |g_n| / s (0 where s is 0 or NaN).  The kernel's
 * expressions (a wall neighbour mirrored), for single faces: the steady
 * measure with materials and hysteresis's states.
 */
double ss_sweep_face_sliding(const double *h, const uint8_t *t, ptrdiff_t a, ptrdiff_t normal,
                             ptrdiff_t along, double inv_spacing, double inv_2along,
                             const struct ss_closure *c, double *s2);

/*
 * Several materials (doc/model.md#materials): the largest over the faces
 * that carry flux (with a bedrock, those whose stencil lies in sand, as
 * above) of f_d(s) |g_n| / s / f_tol_d, the sliding flux across the face
 * over nu, d its material (ss_face_material), f_tol_d the Coulomb flux of a face
 * steeper than d's angle by slope_tol: the steady rule of stepper.h holds
 * where it is at most 1.  NaN if a slope is.  A face beside a steeper
 * material may stay steeper than its own angle along itself (g_t) while
 * nothing crosses it.
 */
double ss_sweep_material_excess(const struct ss_grid *g, const double *restrict height,
                                const uint8_t *restrict cell_types,
                                const uint16_t *restrict material,
                                const struct ss_closure *materials,
                                const double *restrict bedrock, double bare,
                                double slope_tol);

/*
 * The fast sweep (sweep_fast.c): one in-place pass per step over the tiles
 * that can move, with the same face function and update as the reference.
 *
 * Tiles are processed a tile row at a time by one thread, west to east, row
 * by row, from three old rows held in a small buffer; the old values of the
 * neighbouring tile rows' edge rows are saved before the pass (ring_south,
 * ring_north), the old east column of a tile is carried to the next one.
 * So the heights are the only grid-sized array: 8 B per cell plus a
 * quarter byte of packed type plus 2 rows per tile row.
 *
 * The time step needs the largest face slope of the current state before
 * the pass.  It is measured without another pass over the grid: a tile
 * measures its interior faces of the new state one row behind its update,
 * while the rows are in cache; faces whose stencil reaches into another tile
 * are measured when the ring rows are saved at the start of the next step.
 *
 * Active tiles: a tile with no face above the critical slope and no source
 * does not change; it is swept again only when a neighbour changes the cells
 * it sees (its ring) or a source on it starts.  Skipping it changes no bit.
 */
/* A face between an interior flow cell and an open cell. */
struct ss_open_face {
	ptrdiff_t index;        /* index into flux_x or flux_y */
	int8_t axis;            /* 0: flux_x, 1: flux_y */
	int8_t sign;            /* +1 if positive flux leaves the flow cell */
};


struct ss_sweep_fast {
	struct ss_tiling tiling;
	int tiles;
	uint8_t *sweep;          /* per tile: sweep it in the coming step */
	uint8_t *sweep_next;
	uint8_t *moving;         /* per tile: the last sweep saw a face above
	                            the critical slope, or a source */
	uint8_t *edges_changed;  /* per tile: SS_EDGE_* bits of the last sweep */
	uint8_t *plain;          /* per tile: it and its ring are all flow cells */
	uint8_t *has_source;     /* per tile: a source is on over it */
	uint8_t *superstep_swept;  /* per tile: swept in an earlier stage of
	                              this RKL2 super-step */
	uint8_t *moving_superstep; /* per tile: moved or changed in a stage */
	uint8_t *edges_superstep;  /* per tile: SS_EDGE_* changed in a stage */
	uint8_t *swept_last;       /* per tile: swept in the last super-step, so
	                              its y0 and m0 are that super-step's */
	int *row_list;           /* tile rows with a tile to sweep */
	double *ring_south;      /* per tile row: old row j0 - 1, index i + 1 */
	double *ring_north;      /* per tile row: old row j1 */
	double *scratch;         /* per thread: row buffers */
	size_t scratch_doubles;  /* per thread */
	int threads;
	int periodic_x, periodic_y;   /* periodic_y: within this block (one rank) */
	uint8_t *edges_out_south;  /* per tile of the first (last) tile row: */
	uint8_t *edges_out_north;  /*   SS_EDGE_* bits the last plan took from
	                              it, for the rank beside (0: not swept) */
	/* faces to open cells, grouped by tile, in row order (ledger.h) */
	struct ss_open_face_slot *open_slots;
	size_t *open_first;      /* per tile + 1: slots of tile t are
	                            [open_first[t], open_first[t + 1]) */
	double s2_interior;      /* max s^2 of faces measured after the last pass */
	int nonfinite;           /* a NaN slope or rate was seen */
};

enum { SS_EDGE_WEST = 1, SS_EDGE_EAST = 2, SS_EDGE_SOUTH = 4, SS_EDGE_NORTH = 8 };

/* A face between a flow cell and an open cell, as the fast sweep finds it:
 * row j, buffer position x of the face in the tile's row (see sweep_fast.c)
 * and which faces of the row it belongs to. */
struct ss_open_face_slot {
	size_t face;             /* index in the ledger's open-face list */
	int j;                   /* cell row */
	int x;                   /* x-face: i - i0 + 0..1; y-face: i - i0 + 1 */
	int which;               /* 0 x-face, 1 y-face south, 2 y-face north */
};

/* Allocate for grid g covered by `tiling`, `threads` OpenMP threads; the
 * cell types must be final (halo included).  The fast sweep writes the flux
 * of open_faces[m] to open_flux[m].  Every tile starts awake. */
int ss_sweep_fast_init(struct ss_sweep_fast *f, const struct ss_grid *g,
                       const struct ss_tiling *tiling, int threads,
                       int periodic_x, int periodic_y,
                       const uint8_t *cell_types,
                       const struct ss_open_face *open_faces,
                       size_t open_face_count);
void ss_sweep_fast_release(struct ss_sweep_fast *f);

/* Wake every tile and measure the state from scratch (after heights were
 * changed from outside). */
void ss_sweep_fast_wake_all(struct ss_sweep_fast *f, const struct ss_grid *g,
                            const double *height, const uint8_t *cell_types);

/* Mark the tiles holding a cell with a non-zero source rate (NULL: none). */
void ss_sweep_fast_mark_sources(struct ss_sweep_fast *f, const struct ss_grid *g,
                                const double *source_rate);

/* Start of a step: save the ring rows of the tiles to sweep and measure the
 * faces their interior measure could not see.  Returns the largest face
 * slope of the current state that can matter for the time step (exact when
 * it is above the critical slope); sets f->nonfinite on NaN. */
double ss_sweep_fast_begin(struct ss_sweep_fast *f, const struct ss_grid *g,
                           const double *height, const uint8_t *cell_types);

/* Start of an RKL2 stage after the first: only the ring rows of the tiles
 * to sweep.  A stage's length is fixed by its super-step, so it needs no
 * slope; a NaN shows in the stage's own change (ss_sweep_fast_stage). */
void ss_sweep_fast_save_rings(struct ss_sweep_fast *f, const struct ss_grid *g,
                              const double *height);

/* The step: advance the tiles to sweep by dt, in place, with the fluxes
 * limited by the bedrock as ss_sweep_limit does (bedrock NULL: none).
 * Returns max |dh/dt| over the flow cells (INFINITY on NaN); open_flux gets
 * the fluxes of the faces to open cells.  Then plans which tiles the next step sweeps. */
double ss_sweep_fast_step(struct ss_sweep_fast *f, const struct ss_grid *g,
                          const struct ss_face_rule *rule, double dt,
                          const double *restrict source_rate,
                          const double *restrict bedrock,
                          const uint8_t *restrict cell_types,
                          double *restrict height, double *restrict open_flux);

/* Stage j of an RKL2 super-step (ss_sweep_stage) over the tiles that can
 * change in it, in place, with the fluxes of the step above (no bedrock:
 * RKL2 is not used with one).  A tile swept in one stage is swept in every
 * later stage of the super-step; `last` (j = s) plans the next super-step's
 * first stage.  Returns max |D_j| over the flow cells swept, m
 * (INFINITY on NaN); open_flux gets the fluxes of M(Y_{j-1}). */
double ss_sweep_fast_stage(struct ss_sweep_fast *f, const struct ss_grid *g,
                           const struct ss_face_rule *rule,
                           const struct ss_sweep_stage *stage, int last,
                           const double *restrict source_rate,
                           const uint8_t *restrict cell_types,
                           double *restrict height, double *restrict open_flux);

/* Tiles in the grid and tiles the coming step sweeps. */
double ss_sweep_fast_awake(const struct ss_sweep_fast *f);

/*
 * Tiles across a rank edge (comm.h).  A sweep's plan wakes the neighbours
 * of every changed tile edge; at a slab's first and last tile rows those
 * neighbours live on the rank beside.  ss_sweep_fast_step and
 * ss_sweep_fast_stage (not estimate-only) leave, in f->edges_out_south
 * and f->edges_out_north (tiles_x bytes each), the changed-edge bits of the
 * first and last tile rows that their plan used; the stepper sends them to
 * the ranks beside and hands the rows it receives (the last tile row of the
 * rank south, the first of the rank north; NULL: none) to
 * ss_sweep_fast_wake_across, which wakes the tiles here that those edges
 * face, by the rule of the plan.
 */
void ss_sweep_fast_wake_across(struct ss_sweep_fast *f, const uint8_t *from_south,
                               const uint8_t *from_north);

#endif
