/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * bench.c - `sandslide bench` (see bench.h): the figures go to the caller's
 * callbacks as each case ends, so a long benchmark shows its rows as it
 * goes.
 */
#include "sandslide/bench.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "core/ledger.h"
#include "core/rkl2.h"
#include "core/sources.h"
#include "core/sweeper.h"
#include "cuda/cuda.h"
#include "sandslide/boundary.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

#define REPOSE_DEG 35.0
#define SPACING_M 0.01
#define NU_M2_PER_S 0.1
#define PATCH_CELLS 512
#define ROOM_NX 480             /* the room's grid, whatever --nx, --ny: */
#define ROOM_NY 320             /*   the video of doc/rendering.md */
#define ROOM_STAGES 32          /* stages of the room's super-steps */
#define ROOM_RATE_M_PER_S 1e-3  /* cases/door.ini's source */

static const char *const surface_names[] = {"supercritical", "subcritical", "patch", "room"};

const char *ss_bench_surface_name(enum ss_bench_surface s)
{
	return surface_names[s];
}

static int compare_doubles(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static double median(double *v, int n)
{
	qsort(v, (size_t)n, sizeof *v, compare_doubles);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* A small deterministic hash in [-1, 1) for surface roughness. */
static double noise(long long i, long long j)
{
	unsigned long long z = (unsigned long long)(i * 0x9E3779B97F4A7C15LL ^ j * 0xC2B2AE3D27D4EB4FLL);
	z ^= z >> 33;
	z *= 0xFF51AFD7ED558CCDULL;
	z ^= z >> 33;
	return (double)(z >> 11) / 4503599627370496.0 - 1.0;
}

/*
 * Read+write bandwidth of one array of n doubles with the current thread
 * count (the access pattern of an in-place sweep), bytes/s, median of 5.
 */
static double bandwidth_probe(double *a, size_t n)
{
	double rates[5];
	#pragma omp parallel for schedule(static)
	for (size_t k = 0; k < n; k++)
		a[k] = 1.0;
	for (int r = 0; r < 5; r++) {
		const double t0 = ss_parallel_wall_seconds();
		#pragma omp parallel for schedule(static)
		for (size_t k = 0; k < n; k++)
			a[k] = a[k] * 0.999999 + 1e-9;
		rates[r] = 16.0 * (double)n / (ss_parallel_wall_seconds() - t0);
	}
	return median(rates, 5);
}

static void set_surface(struct ss_stepper *st, enum ss_bench_surface surface)
{
	const struct ss_grid *g = &st->grid;
	const double tc = st->closure.tan_cr;
	const int px0 = (g->nx - PATCH_CELLS) / 2, py0 = (g->ny - PATCH_CELLS) / 2;
	#pragma omp parallel for schedule(static)
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const double x = i * g->dx, y = j * g->dy;
			double h = 0.0;
			switch (surface) {
			case SS_BENCH_SUPERCRITICAL:
				/* both gradient components tan a_cr: s = 1.41 tan a_cr */
				h = tc * (x + y) + 1e-3 * g->dx * noise(i, j);
				break;
			case SS_BENCH_SUBCRITICAL:
				h = 0.3 * tc * (x + y) + 1e-3 * g->dx * noise(i, j);
				break;
			case SS_BENCH_PATCH:
				if (i >= px0 && i < px0 + PATCH_CELLS && j >= py0 && j < py0 + PATCH_CELLS)
					h = 1.5 * tc * (i - px0) * g->dx;
				break;
			case SS_BENCH_ROOM:
				/* a heap against the west wall, steeper than the angle */
				if (i < g->nx / 3)
					h = 1.5 * tc * (g->nx / 3 - i) * g->dx;
				break;
			case SS_BENCH_SURFACES:
				break;
			}
			st->height[ss_grid_index(g, i, j)] = h;
		}
	}
}

/*
 * `angles` repose angles from REPOSE_DEG - 5 to REPOSE_DEG + 5 degrees
 * (doc/model.md#materials) in diagonal stripes 16 cells wide, so that rows
 * of faces mix them: the cost of a field of materials.  The supercritical
 * surface (s = 1.41 tan 35 deg) slides on every face at all of them.
 */
static int set_angles(struct ss_stepper *st, int angles)
{
	const struct ss_grid *g = &st->grid;
	struct ss_closure c[64];
	for (int m = 0; m < angles; m++) {
		const double a = REPOSE_DEG - 5.0 + 10.0 * m / (angles - 1);
		int err = ss_closure_init(&c[m], st->closure.kind, a, st->closure.gamma,
		                          st->closure.nu);
		if (err)
			return err;
	}
	uint16_t *material = ss_alloc((size_t)g->nx * (size_t)g->ny, sizeof *material,
	                              "bench materials");
	if (!material)
		return SS_ERR_FAIL;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			material[(size_t)j * g->nx + i] = (uint16_t)(((i + j) / 16) % angles);
	int err = ss_stepper_set_materials(st, c, angles, material);
	ss_free(material);
	return err;
}

/*
 * The room of cases/door.ini, its coordinates stretched over the grid (x
 * from 0 to 1.5, y from -0.5 to 0.5): the room x < 0.5 with side walls
 * 0.05 deep, the wall x = 0.5 to 0.55 with a door |y| <= 0.1, the source
 * on the room; the west side is a wall (run_case), the others open.
 */
static int set_room(struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const size_t n = (size_t)g->nx * (size_t)g->ny;
	uint8_t *room = ss_alloc(n, 1, "bench room mask");
	if (!room)
		return SS_ERR_FAIL;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const double x = (i + 0.5) * 1.5 / g->nx, y = (j + 0.5) / g->ny - 0.5;
			const int wall = (x < 0.55 && fabs(y) > 0.45) ||
			                 (x >= 0.5 && x < 0.55 && fabs(y) > 0.1);
			if (wall)
				ss_cell_type_set(st->cell_types, ss_grid_index(g, i, j), SS_CELL_WALL);
			room[(size_t)j * g->nx + i] = !wall && x < 0.5;
		}
	}
	const int err = ss_stepper_add_source(st, room, ROOM_RATE_M_PER_S, 0.0, INFINITY);
	ss_free(room);
	return err;
}

/* One RKL2 super-step of ROOM_STAGES stages from the state as it is, with
 * the source on: ROOM_STAGES + 1 stencil evaluations.  A height that is
 * not finite sets *nonfinite. */
static void bench_superstep(struct ss_stepper *st, int *nonfinite)
{
	static const struct ss_advance_options none;
	int stopped;
	ss_sweeper_measure(st);
	const double change = ss_rkl2_superstep(st, st->rkl2->dt_all *
	                                        ss_rkl2_stable_ratio(ROOM_STAGES), &none, &stopped);
	st->sweeper->tile_slots += st->sweeper->tiles_all;
	*nonfinite |= !isfinite(change);
}

/*
 * The stepper's substep without its events: a subcritical state, which
 * ss_stepper_advance would not sweep at all, is swept here (and its tiles
 * skipped).  lambda_idle stands in for a CFL rate of 0.
 */
static void bench_step(struct ss_stepper *st, double lambda_idle)
{
	const struct ss_grid *g = &st->grid;
	struct ss_sweeper *w = st->sweeper;
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double s_max = ss_sweep_fast_begin(&w->fast, g, st->height, st->cell_types);
	double lambda = st->closure.nu * ss_cfl_bound_lookup(&w->cfl_bound, s_max);
	lambda = lambda > 0.0 ? lambda : lambda_idle;
	w->tile_sweeps += ss_sweep_fast_awake(&w->fast);
	w->tile_slots += w->fast.tiles;
	ss_sweep_fast_step(&w->fast, g, &w->face_rule, st->cfl / (2.0 * lambda * inv_d2),
	                   NULL, NULL, st->cell_types, st->height, st->ledger->open_flux);
}

/* A step of the case: a substep, or the room's super-step. */
static void bench_one(struct ss_stepper *st, int room, double lambda_idle, int *nonfinite)
{
	if (room)
		bench_superstep(st, nonfinite);
	else
		bench_step(st, lambda_idle);
}

struct case_result {
	double median, min, max;     /* cell-updates/s */
	double active_fraction;      /* tiles swept / tiles, timed steps */
	double plain_fraction;       /* tiles without cell-type work */
	int tile_ny;                 /* rows per tile */
	long long steps;             /* timed steps per repeat */
};

/* Steps per timing: about 0.3 s worth, from one step taking `one` s. */
static long long steps_for(double one)
{
	const long long steps = (long long)ceil(0.3 / fmax(one, 1e-6));
	return steps < 1 ? 1 : steps > 2000 ? 2000 : steps;
}

/* The median, min and max of rates[0 .. repeats - 1] into res. */
static void rate_summary(double *rates, int repeats, struct case_result *res)
{
	res->min = res->max = rates[0];
	for (int r = 1; r < repeats; r++) {
		res->min = fmin(res->min, rates[r]);
		res->max = fmax(res->max, rates[r]);
	}
	res->median = median(rates, repeats);
}

/* The device's loop set up from the prepared stepper: its heights (halo
 * filled), cell types a byte each, one rule, the CFL table and its
 * thresholds (closure.h). */
static int gpu_create(const struct ss_bench_options *o, struct ss_stepper *st,
                      double lambda_idle, struct ss_cuda_euler **e)
{
	const struct ss_grid *g = &st->grid;
	const size_t n = ss_grid_storage_cells(g);
	uint8_t *types = ss_alloc(n, 1, "cell types");
	double *bound = ss_alloc(SS_CFL_TABLE_SIZE, sizeof *bound, "CFL table thresholds");
	int err = types && bound ? SS_OK : SS_ERR_FAIL;
	if (!err) {
		ss_cell_types_unpack(st->cell_types, 0, n, types);
		ss_cfl_bound_thresholds(bound);
		ss_boundary_fill_heights(g, &st->boundary, st->height);
		struct ss_cuda_euler_setup s = {
			.device = o->device.index, .nx = g->nx, .ny = g->ny, .stride = g->stride,
			.dx = g->dx, .dy = g->dy, .open_level = st->boundary.open_level,
			.rule = ss_face_point_rule(&st->sweeper->face_rule), .cfl = st->cfl,
			.lambda_idle = lambda_idle, .lambda = st->sweeper->cfl_bound.lambda_max,
			.bound = bound, .table_size = SS_CFL_TABLE_SIZE, .height = st->height,
			.type = types,
		};
		for (int k = 0; k < 4; k++)
			s.side[k] = (int)st->boundary.side[k];
		err = ss_cuda_euler_create(e, &s);
	}
	ss_free(types);
	ss_free(bound);
	return err;
}

/* A case on the GPU: the steps queued and timed to their end (the wall
 * clock around them and the wait). */
static int run_case_gpu(const struct ss_bench_options *o, struct ss_stepper *st,
                        enum ss_bench_surface surface, const struct ss_bench_closure *bc,
                        double lambda_idle, struct case_result *res)
{
	struct ss_cuda_euler *e = NULL;
	int nonfinite = 0;
	int err = gpu_create(o, st, lambda_idle, &e);
	/* warm-up (the graph's capture), then one step timed */
	if (!err && !(err = ss_cuda_euler_steps(e, 1)))
		err = ss_cuda_euler_finish(e, &nonfinite);
	long long steps = o->steps;
	if (!err && steps <= 0) {
		const double t0 = ss_parallel_wall_seconds();
		if (!(err = ss_cuda_euler_steps(e, 16)) && !(err = ss_cuda_euler_finish(e, &nonfinite)))
			steps = steps_for((ss_parallel_wall_seconds() - t0) / 16.0);
	}
	double rates[64];
	const int repeats = o->repeats < 64 ? o->repeats : 64;
	const double cells = (double)st->grid.nx * st->grid.ny;
	for (int r = 0; r < repeats && !err; r++) {
		const double t0 = ss_parallel_wall_seconds();
		if (!(err = ss_cuda_euler_steps(e, steps)))
			err = ss_cuda_euler_finish(e, &nonfinite);
		rates[r] = cells * (double)steps / (ss_parallel_wall_seconds() - t0);
	}
	ss_cuda_euler_destroy(e);
	if (err)
		return err;
	if (nonfinite)
		return ss_error_fail("bench %s %s on the GPU: a height became NaN or infinite",
		                     surface_names[surface], bc->label);
	res->active_fraction = 1.0;
	res->plain_fraction = 1.0;
	res->tile_ny = 0;
	res->steps = steps;
	rate_summary(rates, repeats, res);
	return SS_OK;
}

static int run_case(const struct ss_bench_options *o, enum ss_bench_surface surface,
                    const struct ss_bench_closure *bc, struct case_result *res)
{
	struct ss_grid g;
	struct ss_closure c;
	struct ss_boundary b;
	struct ss_stepper st;
	const enum ss_side_kind side = surface == SS_BENCH_SUPERCRITICAL ? SS_SIDE_PERIODIC
	                                                                 : SS_SIDE_WALL;
	const int room = surface == SS_BENCH_ROOM;
	memset(&b, 0, sizeof b);
	for (int k = 0; k < 4; k++)
		b.side[k] = room ? (k == SS_WEST ? SS_SIDE_WALL : SS_SIDE_OPEN) : side;
	int err = ss_grid_init(&g, room ? ROOM_NX : o->nx, room ? ROOM_NY : o->ny, SPACING_M,
	                       SPACING_M, 0.0, 0.0);
	if (!err)
		err = ss_closure_init(&c, bc->kind, REPOSE_DEG, bc->gamma, NU_M2_PER_S);
	if (!err)
		err = ss_stepper_init(&st, &g, &c, &b, 0.9, o->tile[0], o->tile[1]);
	if (err)
		return err;
	set_surface(&st, surface);
	if (room) {
		/* RKL2 with no accuracy limit: every super-step ROOM_STAGES long */
		st.integrator = SS_INTEGRATOR_RKL2;
		st.rkl2_max_stages = ROOM_STAGES;
		st.rkl2_tol = INFINITY;
		err = set_room(&st);
	}
	if (!err && o->angles > 1)
		err = set_angles(&st, o->angles);
	if (err || (err = ss_stepper_prepare(&st))) {
		ss_stepper_release(&st);
		return err;
	}
	if (room && ss_sources_update(st.sources, &st.grid, 0.0))
		ss_sweeper_mark_sources(&st);

	struct ss_sweeper *w = st.sweeper;
	const double lambda_idle = st.closure.nu * ss_cfl_bound_lookup(&w->cfl_bound, 2.0 * c.tan_cr);
	if (o->device.kind == SS_DEVICE_CUDA) {
		err = run_case_gpu(o, &st, surface, bc, lambda_idle, res);
		ss_stepper_release(&st);
		return err;
	}
	/* a step: a substep, or for the room a super-step of ROOM_STAGES + 1
	 * evaluations, which the rate counts */
	const int per_step = room ? ROOM_STAGES + 1 : 1;
	int nonfinite = 0;
	bench_one(&st, room, lambda_idle, &nonfinite);   /* warm-up: every tile */
	long long steps = o->steps;
	if (steps <= 0) {
		/* enough steps for about 0.3 s per timing */
		const double t0 = ss_parallel_wall_seconds();
		bench_one(&st, room, lambda_idle, &nonfinite);
		steps = steps_for(ss_parallel_wall_seconds() - t0);
	}
	double rates[64];
	const int repeats = o->repeats < 64 ? o->repeats : 64;
	const double cells = (double)g.nx * g.ny;
	w->tile_sweeps = w->tile_slots = 0.0;
	for (int r = 0; r < repeats; r++) {
		const double t0 = ss_parallel_wall_seconds();
		for (long long k = 0; k < steps; k++)
			bench_one(&st, room, lambda_idle, &nonfinite);
		rates[r] = cells * (double)(steps * per_step) / (ss_parallel_wall_seconds() - t0);
	}
	if (w->fast.nonfinite || nonfinite) {
		ss_stepper_release(&st);
		return ss_error_fail("bench %s %s: a height became NaN or infinite",
		                     surface_names[surface], bc->label);
	}
	double plain = 0.0;
	for (int k = 0; k < w->fast.tiles; k++)
		plain += w->fast.plain[k];
	res->active_fraction = w->tile_slots > 0.0 ? w->tile_sweeps / w->tile_slots : 0.0;
	res->plain_fraction = plain / w->fast.tiles;
	res->tile_ny = w->tiling.tile_ny;
	res->steps = steps;
	rate_summary(rates, repeats, res);
	ss_stepper_release(&st);
	return SS_OK;
}

/* Bytes per cell update that the fast sweep's design moves: the height read
 * and written once (16 B), the two ring rows of each tile row saved and read
 * back (32 B per tile_ny cells of a column), the packed type (a quarter
 * byte, grid.h) on tiles with walls or open cells near them; an RKL2 stage
 * (the room) also reads and writes D_{j-1} and D_{j-2} and reads Y_0 and
 * M(Y_0) (48 B, rkl2.h). */
static double bytes_per_cell(enum ss_bench_surface surface, int tile_ny, double plain_fraction,
                             int angles)
{
	/* with materials, each cell's number (2 B) read where its row is */
	return 16.0 + 32.0 / tile_ny + 0.25 * (1.0 - plain_fraction) +
	       (surface == SS_BENCH_ROOM ? 48.0 : 0.0) + (angles > 1 ? 2.0 : 0.0);
}

/* The grid and memory the options ask for, checked. */
static int check_size(const struct ss_bench_options *o)
{
	if (o->nx < PATCH_CELLS + 2 || o->ny < PATCH_CELLS + 2)
		if (o->surfaces[SS_BENCH_PATCH])
			return ss_error_input("--nx %d --ny %d: the patch surface (a %d x %d ramp "
			                      "inside walls) needs at least %d x %d cells", o->nx,
			                      o->ny, PATCH_CELLS, PATCH_CELLS, PATCH_CELLS + 2,
			                      PATCH_CELLS + 2);
	const double need = (double)o->nx * (double)o->ny * 2.0 * sizeof(double);
	const double have = ss_memory_available_bytes();
	if (have > 0.0 && need > have) {
		char nb[32], hb[32];
		return ss_error_input("--nx %d --ny %d needs %s of memory; %s is available",
		                      o->nx, o->ny, ss_format_bytes(need, nb),
		                      ss_format_bytes(have, hb));
	}
	return SS_OK;
}

/* The bandwidth probe for each thread count, on an array of the grid's size
 * but at least 256 MiB, far above the last-level cache. */
static int probe_bandwidth(const struct ss_bench_options *o, size_t *probe_n,
                           double bandwidth[SS_BENCH_MAX_CASES])
{
	const size_t n = (size_t)o->nx * (size_t)o->ny;
	*probe_n = n > ((size_t)1 << 25) ? n : (size_t)1 << 25;
	double *probe = ss_alloc(*probe_n, sizeof(double), "bandwidth probe array");
	if (!probe)
		return SS_ERR_FAIL;
	for (int t = 0; t < o->thread_count; t++) {
		ss_parallel_set_threads(o->threads[t]);
		bandwidth[t] = bandwidth_probe(probe, *probe_n);
	}
	ss_free(probe);
	return SS_OK;
}

/* The GPU's side of the header: its name, a copy's bandwidth, and the
 * surfaces it leaves out. */
static int gpu_header(const struct ss_bench_options *o, const char *name, const char *what,
                      char *device, size_t device_size, size_t *probe_n, double *bandwidth,
                      int *surfaces)
{
	int err = SS_OK;
	if (o->angles > 1)
		err = ss_error_input("--angles %d with %s: materials do not run on the GPU yet "
		                     "(doc/gpu.md#what-runs-on-the-gpu)", o->angles, what);
	char description[160];
	if (!err)
		err = ss_cuda_device_describe(o->device.index, description, sizeof description);
	if (err)
		return err;
	snprintf(device, device_size, "%s: %s", name, description);
	const size_t n = (size_t)o->nx * (size_t)o->ny;
	*probe_n = n > ((size_t)1 << 25) ? n : (size_t)1 << 25;
	surfaces[SS_BENCH_ROOM] = 0;
	return ss_cuda_copy_bandwidth(o->device.index, *probe_n * sizeof(double), bandwidth);
}

int ss_bench_run(const struct ss_bench_options *o)
{
	struct ss_tiling tiling;
	struct ss_grid g;
	double bandwidth[SS_BENCH_MAX_CASES];
	size_t probe_n;
	int surfaces[SS_BENCH_SURFACES];
	char device[192];
	const int gpu = o->device.kind == SS_DEVICE_CUDA;
	memcpy(surfaces, o->surfaces, sizeof surfaces);
	char name[16], what[32];
	snprintf(what, sizeof what, "--device %s", ss_device_format(&o->device, name, sizeof name));
	int err = ss_device_check(&o->device, what);
	if (!err)
		err = check_size(o);
	if (err)
		return err;
	if (ss_grid_init(&g, o->nx, o->ny, SPACING_M, SPACING_M, 0.0, 0.0))
		return SS_ERR_INPUT;
	ss_tiling_init(&tiling, &g, o->tile[0], o->tile[1]);
	if ((err = gpu ? gpu_header(o, name, what, device, sizeof device, &probe_n, bandwidth,
	                            surfaces)
	               : probe_bandwidth(o, &probe_n, bandwidth)))
		return err;
	/* on a GPU one case per surface and closure: its threads are its own */
	static const int no_threads[1] = {0};
	const int thread_count = gpu ? 1 : o->thread_count;
	const int *threads = gpu ? no_threads : o->threads;
	const struct ss_bench_header h = {
		.nx = o->nx, .ny = o->ny, .tile_nx = tiling.tile_nx, .tile_ny = tiling.tile_ny,
		.repeats = o->repeats, .rsqrt = gpu ? "1/sqrt (IEEE, CUDA)" : ss_face_rsqrt_method(),
		.probe_doubles = probe_n, .thread_count = thread_count, .threads = threads,
		.bandwidth = bandwidth, .angles = o->angles, .device = gpu ? device : NULL,
		.note = gpu && o->surfaces[SS_BENCH_ROOM]
		        ? "the room (RKL2 with a source) is not on the GPU yet: left out" : NULL,
	};
	if (o->on_header)
		o->on_header(o->context, &h);
	for (int s = 0; s < SS_BENCH_SURFACES; s++) {
		for (int c = 0; c < o->closure_count && surfaces[s]; c++) {
			for (int t = 0; t < thread_count; t++) {
				struct case_result r = {0};
				if (!gpu)
					ss_parallel_set_threads(threads[t]);
				if ((err = run_case(o, (enum ss_bench_surface)s, &o->closures[c], &r)))
					return err;
				const double bytes = gpu ? ss_cuda_euler_bytes_per_update()
				                         : bytes_per_cell((enum ss_bench_surface)s, r.tile_ny,
				                                          r.plain_fraction, o->angles);
				const struct ss_bench_result res = {
					.surface = (enum ss_bench_surface)s, .closure = o->closures[c].label,
					.threads = threads[t], .median = r.median, .min = r.min,
					.max = r.max, .steps = r.steps, .active_fraction = r.active_fraction,
					.bytes_per_cell = bytes, .roofline = bandwidth[t] / bytes,
				};
				if (o->on_result)
					o->on_result(o->context, &res);
			}
		}
	}
	return SS_OK;
}

/* ---- the options (bench.h) ------------------------------------------- */

static void add_closure(struct ss_bench_options *o, enum ss_closure_kind kind, double gamma)
{
	struct ss_bench_closure *c = &o->closures[o->closure_count++];
	c->kind = kind;
	c->gamma = gamma;
	if (kind == SS_CLOSURE_HERSCHEL_BULKLEY)
		snprintf(c->label, sizeof c->label, "herschel-bulkley(%g)", gamma);
	else
		snprintf(c->label, sizeof c->label, "%s", ss_closure_name(kind));
}

/* NAME|all: herschel-bulkley stands for gamma 0.5 and 2. */
static int parse_closures(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	enum ss_closure_kind kind = SS_CLOSURE_COULOMB;
	const int all = !strcmp(word, "all");
	if (!all && ss_closure_parse(word, &kind))
		return -1;
	o->closure_count = 0;
	for (int k = SS_CLOSURE_COULOMB; k <= SS_CLOSURE_CASSON; k++) {
		if (!all && k != (int)kind)
			continue;
		if (k == SS_CLOSURE_HERSCHEL_BULKLEY) {
			add_closure(o, SS_CLOSURE_HERSCHEL_BULKLEY, 0.5);
			add_closure(o, SS_CLOSURE_HERSCHEL_BULKLEY, 2.0);
		} else {
			add_closure(o, (enum ss_closure_kind)k, 1.0);
		}
	}
	return 0;
}

static int parse_surfaces(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	int matched = 0, on[SS_BENCH_SURFACES];
	for (int s = 0; s < SS_BENCH_SURFACES; s++) {
		on[s] = !strcmp(word, "all") || !strcmp(word, surface_names[s]);
		matched |= on[s];
	}
	if (matched)
		memcpy(o->surfaces, on, sizeof on);
	return matched ? 0 : -1;
}

/* 1,2: at most SS_BENCH_MAX_CASES counts. */
static int parse_threads(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	int threads[SS_BENCH_MAX_CASES], n = 0;
	for (const char *p = word; *p;) {
		char buf[16];
		const size_t len = strcspn(p, ",");
		if (len == 0 || len >= sizeof buf || n == SS_BENCH_MAX_CASES)
			return -1;
		memcpy(buf, p, len);
		buf[len] = '\0';
		if (ss_parse_int(buf, 1, 4096, &threads[n++]))
			return -1;
		p += len + (p[len] == ',');
	}
	if (n == 0)
		return -1;
	memcpy(o->threads, threads, (size_t)n * sizeof *threads);
	o->thread_count = n;
	return 0;
}

static int parse_tile(const char *value, void *field)
{
	return ss_parse_tile(value, field);
}

static int parse_device(const char *value, void *field)
{
	return ss_device_parse(value, field);
}

#define AT(m) offsetof(struct ss_bench_options, m)
#define CELLS(n, m, h)                                                                 \
	{.name = n, .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(m),          \
	 .default_value = "8192", .lo = 1, .hi = 1 << 20,                              \
	 .expected = "a cell count from 1 to 1048576", .help = h}

static const struct ss_option options[] = {
	CELLS("nx", nx, "cells along x"),
	CELLS("ny", ny, "cells along y"),
	{.name = "closure", .value_name = "NAME|all", .kind = SS_OPTION_WORD, .offset = 0,
	 .default_value = "all", .parse = parse_closures, .expected = "all, " SS_CLOSURE_NAMES,
	 .help = "coulomb, bingham, herschel-bulkley (gamma 0.5 and 2),\n"
	         "casson, or all"},
	{.name = "threads", .value_name = "LIST", .kind = SS_OPTION_WORD, .offset = 0,
	 .default_value = "1,2", .parse = parse_threads,
	 .expected = "a list such as 1,2 (at most 8 entries from 1 to 4096)",
	 .help = "thread counts, comma-separated"},
	{.name = "surface", .value_name = "NAME|all", .kind = SS_OPTION_WORD, .offset = 0,
	 .default_value = "all", .parse = parse_surfaces,
	 .expected = "all, supercritical, subcritical, patch or room",
	 .help = "supercritical (every face slides), subcritical (none\n"
	         "does), patch (a 512 x 512 ramp on a flat floor), room\n"
	         "(cases/door.ini at 480 x 320 whatever --nx, --ny;\n"
	         "RKL2 super-steps of 32 stages), all"},
	{.name = "repeats", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(repeats),
	 .default_value = "5", .lo = 1, .hi = 64, .expected = "1 to 64",
	 .help = "timings per case; median, min and max"},
	{.name = "steps", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(steps), .lo = 1,
	 .hi = 1000000, .expected = "1 to 1000000",
	 .help = "steps per timing (default: about 0.3 s worth)"},
	{.name = "tile", .value_name = "NXxNY", .kind = SS_OPTION_WORD, .offset = AT(tile),
	 .parse = parse_tile, .expected = "NXxNY, e.g. 256x64",
	 .help = "tile size of the sweep (default 256x128)"},
	{.name = "device", .value_name = "cpu|cuda[:N]", .kind = SS_OPTION_WORD,
	 .offset = AT(device), .parse = parse_device, .default_value = "cpu",
	 .expected = "cpu, cuda or cuda:N (N from 0 to 63)",
	 .help = "the CPU, or GPU N of a build with CUDA: forward\n"
	         "Euler on the device, --threads not used (doc/gpu.md)"},
	{.name = "angles", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(angles),
	 .default_value = "1", .lo = 1, .hi = 64, .expected = "1 to 64",
	 .help = "repose angles from 30 to 40 deg in stripes 16 cells\n"
	         "wide (materials, doc/model.md#materials); 1: 35 deg"},
};

const struct ss_option_table ss_bench_option_table = {
	.command = "bench", .options = options, .count = sizeof options / sizeof *options,
};

void ss_bench_options_init(struct ss_bench_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_bench_option_table, o);
}
