/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_sweep.c - the two sweep kernels and the face function (sweep.h,
 * face.h, stepper.h):
 *
 *   bit identity     the fast in-place sweep over active tiles gives the same
 *                    bits as the reference two-pass sweep: heights, time,
 *                    steps, inflow and outflow, for every closure, with
 *                    interior walls, open regions and sides, two sources
 *                    switching on and off, several tile sizes (not dividing
 *                    the grid) and 1 or 2 threads; periodic sides too
 *   active tiles     a steep pile in a corner slides, spreads and stops:
 *                    the fast kernel skips tiles (active_fraction < 1), keeps
 *                    the reference's bits at every stop, conserves volume
 *   subcritical      the fast sweep leaves a subcritical state bit for bit
 *                    unchanged and falls asleep after its first step
 *   max slope        ss_sweep_max_slope is exactly the slope ss_sweep_fluxes
 *                    returns (and the fast sweep's first measure)
 *   paths            on every instruction-set path the processor runs (cpu.h;
 *                    the others are skipped with a note): a row of faces
 *                    gives the bits of single faces, the face accuracy
 *                    checks below hold, the fast sweep gives the reference
 *                    sweep's bits; the generic and AVX2 paths give the same
 *                    bits, the AVX-512 path other bits in some faces
 *   face function    ss_face_fluxes against nu * ss_closure_face_flux: within
 *                    K eps (1 + kappa) relative everywhere (kappa the
 *                    cancellation factor of e = b - 1, see bound_scale; this
 *                    is also the bound near the threshold), 1e-14 where
 *                    e > 0.1 and kappa <= 8, 5e-14 where e > 0.1; +0 where
 *                    g_n^2 + g_t^2 <= tan^2 a_cr; ss_face_rsqrt against
 *                    1/sqrt over 1e-300 .. 1e300; a row of faces gives the
 *                    bits of single faces
 *
 * About 16 s on 2 idle cores (the identity cases, the active-tile case and
 * the three paths' sweeps, 3-5 s each); the seed is fixed
 * (SANDSLIDE_TEST_SEED overrides it).  The path main() starts on is the
 * default one, or the one SANDSLIDE_CPU forces.
 * SANDSLIDE_TEST_SCALE in (0, 1] (tests/scale.h; 0.5 under `make SANITIZE=1
 * test` and `make race`) shrinks the box of the active-tile case, with
 * every check kept.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "scale.h"
#include "core/face.h"
#include "core/ledger.h"
#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/cpu.h"
#include "sandslide/diagnostics.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

#define REPOSE 35.0

static uint64_t seed = 20240612;

/* ---- helpers ------------------------------------------------------------ */

static int same_bits(double a, double b)
{
	return memcmp(&a, &b, sizeof a) == 0;
}

struct closure_case {
	enum ss_closure_kind kind;
	double gamma;
	const char *name;
	double nu;    /* m^2/s for the random states: about 100-200 steps */
};

static const struct closure_case closures[] = {
	{SS_CLOSURE_COULOMB, 1.0, "coulomb", 0.05},
	{SS_CLOSURE_BINGHAM, 1.0, "bingham", 0.05},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 0.5, "herschel-bulkley 0.5 (e^3)", 0.1},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 2.0, "herschel-bulkley 2 (e sqrt e)", 0.05},
	{SS_CLOSURE_HERSCHEL_BULKLEY, 0.3, "herschel-bulkley 0.3 (pow)", 0.2},
	{SS_CLOSURE_CASSON, 1.0, "casson", 0.1},
};
#define N_CLOSURES ((int)(sizeof closures / sizeof *closures))

/* A complete set-up: grid, closure, sides, cells, initial heights, sources. */
struct scenario {
	const char *name;
	int nx, ny;
	double dx, dy, nu;
	struct closure_case cl;
	struct ss_boundary sides;
	double *h0;          /* nx * ny, row-major from the south */
	uint8_t *type;       /* nx * ny */
	double *bedrock;     /* nx * ny, or NULL */
	int sources;
	uint8_t *mask[2];
	double rate[2], start[2], stop[2];
	int materials;       /* > 0: ss_stepper_set_materials with these */
	struct ss_closure material[3];
	uint16_t *material_of_cell;   /* nx * ny */
};

static void scenario_alloc(struct scenario *sc, int nx, int ny)
{
	memset(sc, 0, sizeof *sc);
	sc->nx = nx;
	sc->ny = ny;
	sc->h0 = calloc((size_t)nx * ny, sizeof *sc->h0);
	sc->type = calloc((size_t)nx * ny, 1);
	for (int k = 0; k < 2; k++)
		sc->mask[k] = calloc((size_t)nx * ny, 1);
}

static void scenario_free(struct scenario *sc)
{
	free(sc->h0);
	free(sc->type);
	free(sc->bedrock);
	free(sc->material_of_cell);
	for (int k = 0; k < 2; k++)
		free(sc->mask[k]);
}

/* Fill a random rectangle of at most w x h cells of a[nx * ny] with v. */
static void random_rect(struct rng *r, int nx, int ny, int w, int h, uint8_t *a,
                        uint8_t v)
{
	const int rw = 1 + rng_int(r, w < nx ? w : nx), rh = 1 + rng_int(r, h < ny ? h : ny);
	const int i0 = rng_int(r, nx - rw + 1), j0 = rng_int(r, ny - rh + 1);
	for (int j = j0; j < j0 + rh; j++)
		for (int i = i0; i < i0 + rw; i++)
			a[(size_t)j * nx + i] = v;
}

/* Build a stepper for sc with the given kernel, tile size and threads. */
static int build(struct ss_stepper *st, const struct scenario *sc, enum ss_kernel kernel,
                 int tile_nx, int tile_ny, int threads)
{
	struct ss_grid g;
	struct ss_closure c;
	int err = ss_grid_init(&g, sc->nx, sc->ny, sc->dx, sc->dy, 0.0, 0.0);
	CHECK(err == 0, "%s: grid %d x %d refused", sc->name, sc->nx, sc->ny);
	if (err)
		return err;
	err = ss_closure_init(&c, sc->cl.kind, REPOSE, sc->cl.gamma, sc->nu);
	CHECK(err == 0, "%s: closure %s refused", sc->name, sc->cl.name);
	if (err)
		return err;
	ss_parallel_set_threads(threads);   /* the fast sweep sizes its buffers now */
	err = ss_stepper_init(st, &g, &c, &sc->sides, 0.9, tile_nx, tile_ny);
	CHECK(err == 0, "%s: stepper init failed", sc->name);
	if (err)
		return err;
	st->kernel = kernel;
	for (int j = 0; j < sc->ny; j++) {
		for (int i = 0; i < sc->nx; i++) {
			const ptrdiff_t k = ss_grid_index(&st->grid, i, j);
			st->height[k] = sc->h0[(size_t)j * sc->nx + i];
			ss_cell_type_set(st->cell_types, k, sc->type[(size_t)j * sc->nx + i]);
		}
	}
	if (sc->materials &&
	    (err = ss_stepper_set_materials(st, sc->material, sc->materials,
	                                    sc->material_of_cell))) {
		CHECK(0, "%s: materials refused", sc->name);
		ss_stepper_release(st);
		return err;
	}
	if (sc->bedrock && (err = ss_stepper_set_bedrock(st, sc->bedrock))) {
		CHECK(0, "%s: bedrock refused", sc->name);
		ss_stepper_release(st);
		return err;
	}
	for (int s = 0; s < sc->sources; s++) {
		err = ss_stepper_add_source(st, sc->mask[s], sc->rate[s], sc->start[s], sc->stop[s]);
		CHECK(err == 0, "%s: source %d refused", sc->name, s);
		if (err) {
			ss_stepper_release(st);
			return err;
		}
	}
	err = ss_stepper_prepare(st);
	CHECK(err == 0, "%s: ss_stepper_prepare refused the initial state", sc->name);
	if (err)
		ss_stepper_release(st);
	return err;
}

/* Advance to t with no steady stop; checks that t was reached. */
static int advance_to(struct ss_stepper *st, double t, const char *what)
{
	const struct ss_advance_options o = {.steady_tol = 0.0};
	const enum ss_advance_end end = ss_stepper_advance(st, t, &o);
	CHECK(end == SS_ADVANCE_REACHED && st->time == t,
	      "%s: advance to t = %g s ended with %d at t = %.17g s", what, t, (int)end,
	      st->time);
	return end == SS_ADVANCE_REACHED;
}

/* Compare two steppers on the same grid bit for bit: interior heights (every
 * cell, flow, wall and open), time, steps, inflow, outflow.  Names the first
 * differing cell.  Returns 1 when identical. */
static int compare_states(const struct ss_stepper *a, const struct ss_stepper *b,
                          const char *what)
{
	const struct ss_grid *g = &a->grid;
	int first_i = -1, first_j = -1;
	long differing = 0;
	for (int j = 0; j < g->ny; j++) {
		const double *ra = a->height + ss_grid_index(g, 0, j);
		const double *rb = b->height + ss_grid_index(g, 0, j);
		if (memcmp(ra, rb, (size_t)g->nx * sizeof *ra) == 0)
			continue;
		for (int i = 0; i < g->nx; i++) {
			if (!same_bits(ra[i], rb[i])) {
				if (first_i < 0) {
					first_i = i;
					first_j = j;
				}
				differing++;
			}
		}
	}
	int ok = differing == 0;
	CHECK(differing == 0,
	      "%s: %ld cells differ between the kernels; first (%d, %d): fast %.17g, "
	      "reference %.17g", what, differing, first_i, first_j,
	      first_i >= 0 ? a->height[ss_grid_index(g, first_i, first_j)] : 0.0,
	      first_i >= 0 ? b->height[ss_grid_index(g, first_i, first_j)] : 0.0);
	CHECK(same_bits(a->time, b->time) && a->steps == b->steps,
	      "%s: time %.17g s after %lld steps (fast) vs %.17g s after %lld steps "
	      "(reference)", what, a->time, a->steps, b->time, b->steps);
	const double in_a = ss_stepper_inflow(a), in_b = ss_stepper_inflow(b);
	const double out_a = ss_stepper_outflow(a), out_b = ss_stepper_outflow(b);
	CHECK(same_bits(in_a, in_b),
	      "%s: inflow %.17g (fast) vs %.17g (reference) m^3", what, in_a, in_b);
	CHECK(same_bits(out_a, out_b),
	      "%s: outflow %.17g (fast) vs %.17g (reference) m^3", what, out_a, out_b);
	ok &= same_bits(a->time, b->time) && a->steps == b->steps &&
	      same_bits(in_a, in_b) && same_bits(out_a, out_b);
	return ok;
}

/* ---- 1. bit identity fast vs reference ------------------------------------ */

struct tile_case {
	int nx, ny;
};

static const struct tile_case tile_cases[] = {{7, 5}, {16, 8}, {64, 64}, {0, 0}, {1, 3}};
#define N_TILES ((int)(sizeof tile_cases / sizeof *tile_cases))

/*
 * Random scenario on a 97 x 61 grid (dx 1 cm, dy 1.2 cm): heights random
 * noise of amplitude 4 tan(a_cr) dx, everywhere (patchy = 0) or in a few
 * rectangles on a gentle subcritical ramp (patchy = 1, so tiles fall asleep
 * and are woken); three wall blocks, two open blocks, two sources on random
 * rectangles (one stopping at 0.5 T, one starting at 0.3 T).
 */
static void random_scenario(struct scenario *sc, struct rng *r, struct closure_case cl,
                            struct ss_boundary sides, int patchy, double T)
{
	const int nx = 97, ny = 61;
	scenario_alloc(sc, nx, ny);
	sc->cl = cl;
	sc->dx = 0.01;
	sc->dy = 0.012;
	sc->nu = cl.nu;
	sc->sides = sides;
	const double tc = tan(REPOSE * M_PI / 180.0), amp = 4.0 * tc * sc->dx;
	uint8_t *noisy = calloc((size_t)nx * ny, 1);
	if (patchy) {
		for (int k = 0; k < 3; k++)
			random_rect(r, nx, ny, 30, 25, noisy, 1);
	} else {
		memset(noisy, 1, (size_t)nx * ny);
	}
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			sc->h0[(size_t)j * nx + i] = noisy[(size_t)j * nx + i]
				? amp * rng_uniform(r)
				: 0.3 * tc * sc->dx * i + 0.2 * tc * sc->dy * j;
	free(noisy);
	for (int k = 0; k < 3; k++)
		random_rect(r, nx, ny, 12, 9, sc->type, SS_CELL_WALL);
	for (int k = 0; k < 2; k++)
		random_rect(r, nx, ny, 6, 6, sc->type, SS_CELL_OPEN);
	sc->sources = 2;
	for (int k = 0; k < 2; k++)
		random_rect(r, nx, ny, 25, 20, sc->mask[k], 1);
	/* a step may raise a cell by cfl tan(a_cr) min(dx, dy): 2-3 ms at these
	 * rates, comparable to the CFL step */
	sc->rate[0] = 2.0;
	sc->start[0] = 0.0;
	sc->stop[0] = 0.5 * T;
	sc->rate[1] = 1.0;
	sc->start[1] = 0.3 * T;
	sc->stop[1] = INFINITY;
}

static long long identity_steps;   /* reference steps, summed, for the report */

/* Run sc to T with the reference kernel, then with the fast kernel for the
 * tile sizes tile_cases[tiles[0..n_tiles)] and 1 and 2 threads; compare bit
 * for bit. */
static double identity_case(const struct scenario *sc, double T, const int *tiles,
                            int n_tiles)
{
	double af_min = 1.0;
	struct ss_stepper ref;
	char what[240];
	if (build(&ref, sc, SS_KERNEL_REFERENCE, 16, 8, 2))
		return af_min;
	snprintf(what, sizeof what, "%s reference", sc->name);
	advance_to(&ref, T, what);
	CHECK(ref.steps >= 60, "%s: test set-up: only %lld steps to T = %g s", sc->name,
	      ref.steps, T);
	identity_steps += ref.steps;
	CHECK(ref.ledger->open_face_count == 0 || ss_stepper_outflow(&ref) != 0.0,
	      "%s: test set-up: no outflow through %zu open faces", sc->name,
	      ref.ledger->open_face_count);
	CHECK(sc->sources == 0 || ss_stepper_inflow(&ref) > 0.0, "%s: test set-up: no inflow",
	      sc->name);
	for (int m = 0; m < n_tiles; m++) {
		const struct tile_case tc = tile_cases[tiles[m]];
		for (int threads = 1; threads <= 2; threads++) {
			struct ss_stepper fast;
			if (build(&fast, sc, SS_KERNEL_FAST, tc.nx, tc.ny, threads))
				continue;
			snprintf(what, sizeof what, "%s, fast kernel tiles %dx%d, %d thread%s",
			         sc->name, fast.sweeper->tiling.tile_nx, fast.sweeper->tiling.tile_ny, threads,
			         threads > 1 ? "s" : "");
			advance_to(&fast, T, what);
			compare_states(&fast, &ref, what);
			struct ss_diagnostics d;
			ss_stepper_diagnostics(&fast, &d);
			af_min = fmin(af_min, d.active_fraction);
			ss_stepper_release(&fast);
		}
	}
	ss_stepper_release(&ref);
	ss_parallel_set_threads(2);
	return af_min;
}

static struct ss_boundary sides4(enum ss_side_kind w, enum ss_side_kind e,
                                 enum ss_side_kind s, enum ss_side_kind n, double level)
{
	struct ss_boundary b = {{w, e, s, n}, level};
	return b;
}

static void test_identity(void)
{
	const double T = 0.12;
	const enum ss_side_kind W = SS_SIDE_WALL, O = SS_SIDE_OPEN;
	const struct ss_boundary side_sets[3] = {
		sides4(O, W, W, O, 0.002),   /* open west and north */
		sides4(W, W, W, W, 0.0),     /* closed box */
		sides4(W, O, O, W, -0.001),  /* open east and south, below the sand */
	};
	for (int c = 0; c < N_CLOSURES; c++) {
		for (int patchy = 0; patchy <= 1; patchy++) {
			struct rng r = {seed * 31u + (uint64_t)(2 * c + patchy)};
			struct scenario sc;
			char name[160];
			random_scenario(&sc, &r, closures[c], side_sets[(c + patchy) % 3], patchy, T);
			snprintf(name, sizeof name, "%s, %s noise, sides %d", closures[c].name,
			         patchy ? "patchy" : "full", (c + patchy) % 3);
			sc.name = name;
			static const int all[N_TILES] = {0, 1, 2, 3, 4};
			identity_case(&sc, T, all, N_TILES);
			scenario_free(&sc);
		}
	}
	printf("  bit identity: %d closures x 2 states x %d tile sizes x 1, 2 threads, "
	       "%lld reference steps in all\n", N_CLOSURES, N_TILES, identity_steps);
}

/* Periodic sides: both periodic, and x periodic with open y sides. */
static void test_identity_periodic(void)
{
	const double T = 0.12;
	const enum ss_side_kind P = SS_SIDE_PERIODIC, O = SS_SIDE_OPEN;
	const long long before = identity_steps;
	for (int c = 0; c < N_CLOSURES; c += 1) {
		for (int variant = 0; variant < 2; variant++) {
			struct rng r = {seed * 77u + (uint64_t)(2 * c + variant)};
			struct scenario sc;
			char name[160];
			const struct ss_boundary b = variant == 0 ? sides4(P, P, P, P, 0.0)
			                                          : sides4(P, P, O, O, 0.001);
			random_scenario(&sc, &r, closures[c], b, c % 2, T);
			snprintf(name, sizeof name, "%s, %s, %s noise", closures[c].name,
			         variant == 0 ? "periodic x and y" : "periodic x, open y",
			         c % 2 ? "patchy" : "full");
			sc.name = name;
			/* tiles 7x5, 16x8 and the default (one tile wide: it wraps
			 * onto itself) */
			static const int some[3] = {0, 1, 3};
			identity_case(&sc, T, some, 3);
			scenario_free(&sc);
		}
	}
	printf("  bit identity, periodic sides: %d closures x 2 side sets, %lld reference "
	       "steps\n", N_CLOSURES, identity_steps - before);
}

/* Periodic seams: a steep pile (8 tan a_cr) on a flat floor whose foot
 * stays 3 cells clear of the west and south edges of a periodic grid.  The
 * flat tiles across the seams fall asleep after the first step; the sand
 * spreading over the seams (and the corner) must wake them: the tile plan
 * wraps round, diagonally too. */
static void test_identity_periodic_pile(void)
{
	const int nx = 61, ny = 43;
	struct scenario sc;
	scenario_alloc(&sc, nx, ny);
	sc.name = "periodic pile at the seams";
	sc.cl = closures[0];
	sc.dx = sc.dy = 0.01;
	sc.nu = 0.01;
	sc.sides = sides4(SS_SIDE_PERIODIC, SS_SIDE_PERIODIC, SS_SIDE_PERIODIC,
	                  SS_SIDE_PERIODIC, 0.0);
	const double tc = tan(REPOSE * M_PI / 180.0);
	const double ci = 13.0, cj = 13.0, R = 10.0;   /* cells */
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const double rr = hypot(i + 0.5 - ci, j + 0.5 - cj);
			sc.h0[(size_t)j * nx + i] = fmax(0.0, 8.0 * tc * (R - rr) * sc.dx);
		}
	}
	const double T = 1.5;
	static const int some[4] = {0, 1, 4, 3};
	const double af = identity_case(&sc, T, some, 4);
	CHECK(af < 0.8, "periodic pile: test set-up: the fast kernel swept %.3g of the "
	      "tiles: the pile does not leave tiles asleep", af);
	/* the sand must have crossed both seams */
	struct ss_stepper st;
	if (build(&st, &sc, SS_KERNEL_FAST, 7, 5, 2) == 0) {
		advance_to(&st, T, "periodic pile");
		const double east = st.height[ss_grid_index(&st.grid, nx - 1, 13)];
		const double north = st.height[ss_grid_index(&st.grid, 13, ny - 1)];
		const double corner = st.height[ss_grid_index(&st.grid, nx - 1, ny - 1)];
		CHECK(east > 0.0 && north > 0.0 && corner > 0.0,
		      "periodic pile: test set-up: sand did not cross the seams (east %g, "
		      "north %g, corner %g m)", east, north, corner);
		printf("  periodic pile at the seams: identical bits, smallest active_fraction "
		       "%.3f, sand across the seams: east %.3g, north %.3g, corner %.3g m\n",
		       af, east, north, corner);
		ss_stepper_release(&st);
	}
	scenario_free(&sc);
}

/* Bedrock: the random scenarios with a bedrock under each flow cell at a
 * random depth, a third of the cells bare (bedrock = surface), so that the
 * face limits of face.h bind.  Both kernels must still agree bit for bit. */
static void test_identity_bedrock(void)
{
	const double T = 0.12;
	const enum ss_side_kind W = SS_SIDE_WALL, O = SS_SIDE_OPEN, P = SS_SIDE_PERIODIC;
	const struct ss_boundary side_sets[3] = {
		sides4(O, W, W, O, 0.002), sides4(P, P, O, O, -0.001), sides4(P, P, P, P, 0.0),
	};
	const long long before = identity_steps;
	for (int c = 0; c < N_CLOSURES; c += 2) {
		struct rng r = {seed * 53u + (uint64_t)c};
		struct scenario sc;
		char name[160];
		random_scenario(&sc, &r, closures[c], side_sets[c / 2 % 3], 0, T);
		sc.bedrock = malloc((size_t)sc.nx * sc.ny * sizeof *sc.bedrock);
		const double thick = 0.5 * tan(REPOSE * M_PI / 180.0) * sc.dx;
		for (size_t k = 0; k < (size_t)sc.nx * sc.ny; k++)
			sc.bedrock[k] = sc.h0[k] - (rng_int(&r, 3) == 0 ? 0.0 : thick * rng_uniform(&r));
		snprintf(name, sizeof name, "%s, bedrock, sides %d", closures[c].name, c / 2 % 3);
		sc.name = name;
		static const int some[3] = {0, 1, 3};
		identity_case(&sc, T, some, 3);
		/* the limits must bind (else this tests nothing) and keep every
		 * flow cell on or above its bedrock */
		struct ss_stepper with, without;
		if (build(&with, &sc, SS_KERNEL_FAST, 16, 8, 2) == 0) {
			advance_to(&with, T, name);
			double *bedrock = sc.bedrock;
			sc.bedrock = NULL;
			if (build(&without, &sc, SS_KERNEL_FAST, 16, 8, 2) == 0) {
				advance_to(&without, T, name);
				double worst = 0.0;
				long differ = 0;
				for (int j = 0; j < sc.ny; j++) {
					for (int i = 0; i < sc.nx; i++) {
						const ptrdiff_t k = ss_grid_index(&with.grid, i, j);
						if (ss_cell_type_get(with.cell_types, k) != SS_CELL_FLOW)
							continue;
						worst = fmin(worst, with.height[k] - with.bedrock[k]);
						differ += with.height[k] != without.height[k];
					}
				}
				CHECK(worst >= -1e-15, "%s: a cell ends %.3g m below its bedrock", name,
				      -worst);
				CHECK(differ > 0, "%s: test set-up: the bedrock changed no height", name);
				ss_stepper_release(&without);
			}
			sc.bedrock = bedrock;
			ss_stepper_release(&with);
		}
		scenario_free(&sc);
	}
	printf("  bit identity with bedrock: 3 closures, %lld reference steps\n",
	       identity_steps - before);
}

/* ---- 2. active tiles: a pile slides, spreads and stops -------------------- */

/* Materials (doc/model.md#materials) in random rectangles: angles 25,
 * REPOSE and 40 deg with different nu; the fast kernel gives the
 * reference's bits, and each face the rule of the larger angle of its two
 * cells.  Also Coulomb beside Bingham (faces of two forms in one row).
 * One material, or three equal ones, give the bits of a run without
 * materials. */
static void test_identity_materials(void)
{
	const double T = 0.12;
	const struct ss_boundary sides[2] = {sides4(SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL,
	                                            SS_SIDE_OPEN, 0.002),
	                                     sides4(SS_SIDE_PERIODIC, SS_SIDE_PERIODIC,
	                                            SS_SIDE_WALL, SS_SIDE_WALL, 0.0)};
	static const int some[3] = {0, 1, 3};
	for (int c = 0; c <= N_CLOSURES; c++) {
		struct rng r = {seed * 37u + (uint64_t)c};
		struct scenario sc;
		char name[160];
		/* c == N_CLOSURES: coulomb and bingham side by side */
		const struct closure_case cl = closures[c < N_CLOSURES ? c : 0];
		random_scenario(&sc, &r, cl, sides[c % 2], c % 2, T);
		sc.materials = 3;
		const double angles[3] = {25.0, REPOSE, 40.0};
		for (int m = 0; m < 3; m++) {
			const struct closure_case mc = c < N_CLOSURES || m != 1 ? cl : closures[1];
			ss_closure_init(&sc.material[m], mc.kind, angles[m], mc.gamma,
			                cl.nu * (1.0 + 0.5 * m));
		}
		sc.material_of_cell = calloc((size_t)sc.nx * sc.ny, sizeof *sc.material_of_cell);
		uint8_t *mask = calloc((size_t)sc.nx * sc.ny, 1);
		for (int m = 1; m < 3; m++) {
			memset(mask, 0, (size_t)sc.nx * sc.ny);
			for (int k = 0; k < 3; k++)
				random_rect(&r, sc.nx, sc.ny, 40, 30, mask, 1);
			for (size_t q = 0; q < (size_t)sc.nx * sc.ny; q++)
				if (mask[q])
					sc.material_of_cell[q] = (uint16_t)(m == 1 ? 2 : 1);
		}
		free(mask);
		snprintf(name, sizeof name, "%s, three materials%s", cl.name,
		         c < N_CLOSURES ? "" : " (coulomb and bingham)");
		sc.name = name;
		identity_case(&sc, T, some, 3);

		/* one material, then three equal ones: the run without */
		struct ss_stepper plain, one;
		sc.name = "materials test: one material";
		sc.materials = 0;
		if (build(&plain, &sc, SS_KERNEL_FAST, 16, 8, 2) == 0) {
			advance_to(&plain, T, sc.name);
			for (int variant = 0; variant < 2; variant++) {
				ss_closure_init(&sc.material[0], cl.kind, REPOSE, cl.gamma, cl.nu);
				sc.material[1] = sc.material[2] = sc.material[0];
				sc.materials = variant == 0 ? 1 : 3;
				if (variant == 0)
					memset(sc.material_of_cell, 0,
					       (size_t)sc.nx * sc.ny * sizeof *sc.material_of_cell);
				if (build(&one, &sc, SS_KERNEL_FAST, 16, 8, 2) == 0) {
					CHECK(one.material == NULL, "%s: %d equal materials kept a field of "
					      "materials", cl.name, sc.materials);
					advance_to(&one, T, sc.name);
					compare_states(&one, &plain, variant == 0 ? "one material"
					                                          : "three equal materials");
					ss_stepper_release(&one);
				}
			}
			ss_stepper_release(&plain);
		}
		sc.materials = 0;
		scenario_free(&sc);
	}
	printf("  bit identity with materials: %d closures and coulomb beside bingham, "
	       "three tile sizes x 1, 2 threads; one or equal materials as none\n",
	       N_CLOSURES);
}

static void test_active_tiles(void)
{
	/* 200 x 150 cells; SANDSLIDE_TEST_SCALE (scale.h) shrinks the box
	 * round the same pile */
	const int nx = test_scaled(200, 40), ny = test_scaled(150, 40);
	struct scenario sc;
	scenario_alloc(&sc, nx, ny);
	sc.name = "corner pile";
	sc.cl = closures[0];
	sc.dx = sc.dy = 0.01;
	sc.nu = 0.05;
	sc.sides = sides4(SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, 0.0);
	/* the cone is cut by the west and south walls */
	const double tc = tan(REPOSE * M_PI / 180.0), R = 0.12;
	const double cx = 0.10, cy = 0.10;   /* cone centre, m */
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const double rr = hypot((i + 0.5) * sc.dx - cx, (j + 0.5) * sc.dy - cy);
			sc.h0[(size_t)j * nx + i] = fmax(0.0, 1.5 * tc * (R - rr));
		}
	}
	struct ss_stepper fast, ref;
	if (build(&fast, &sc, SS_KERNEL_FAST, 16, 8, 2)) {
		scenario_free(&sc);
		return;
	}
	if (build(&ref, &sc, SS_KERNEL_REFERENCE, 16, 8, 2)) {
		ss_stepper_release(&fast);
		scenario_free(&sc);
		return;
	}
	struct ss_diagnostics d0;
	ss_stepper_diagnostics(&fast, &d0);
	const struct ss_advance_options o = {.steady_tol = 1e-9};
	const double t_cap = 40.0;
	double t = 0.0, dt_stop = 0.02;
	double af_min = 1.0, af_max = 0.0, af_while_sliding_min = 1.0;
	int stops = 0, steady = 0, all_same = 1;
	char line[2048] = "";
	size_t used = 0;
	while (t < t_cap && !steady) {
		t = fmin(t + dt_stop, t_cap);
		dt_stop *= 1.6;
		const enum ss_advance_end ef = ss_stepper_advance(&fast, t, &o);
		const enum ss_advance_end er = ss_stepper_advance(&ref, t, &o);
		char what[120];
		snprintf(what, sizeof what, "corner pile, stop %d at t = %.4g s", stops, t);
		CHECK(ef == er, "%s: the fast kernel ended with %d, the reference with %d",
		      what, (int)ef, (int)er);
		CHECK(ef == SS_ADVANCE_REACHED || ef == SS_ADVANCE_STEADY,
		      "%s: advance ended with %d", what, (int)ef);
		all_same &= compare_states(&fast, &ref, what);
		struct ss_diagnostics d;
		const double rate = fast.rate_max;
		ss_stepper_diagnostics(&fast, &d);
		if (d.active_fraction < af_min)
			af_min = d.active_fraction;
		if (d.active_fraction > af_max)
			af_max = d.active_fraction;
		if (rate > 1e-6 && d.active_fraction < af_while_sliding_min)
			af_while_sliding_min = d.active_fraction;
		CHECK(rate <= 1e-6 || d.active_fraction > 0.0,
		      "%s: max |dh/dt| %g m/s but active_fraction %g", what, rate,
		      d.active_fraction);
		if (used < sizeof line - 40)
			used += (size_t)snprintf(line + used, sizeof line - used, " %.3g@%.3gs",
			                         d.active_fraction, fast.time);
		steady = ef == SS_ADVANCE_STEADY;
		stops++;
		if (ef != SS_ADVANCE_REACHED && ef != SS_ADVANCE_STEADY)
			break;
	}
	struct ss_diagnostics d1;
	ss_stepper_diagnostics(&fast, &d1);
	CHECK(d1.active_fraction == 0.0, "corner pile: active_fraction %g right after the "
	      "last diagnostics, with no substep between: the counters were not reset",
	      d1.active_fraction);
	CHECK(steady, "corner pile: not steady (max |dh/dt| %g m/s) by t = %g s",
	      fast.rate_max, fast.time);
	CHECK(af_min < 0.5, "corner pile: active_fraction never fell below 0.5 (min %g): "
	      "the fast kernel does not skip quiet tiles", af_min);
	CHECK(af_while_sliding_min > 0.0 && af_max > 0.0,
	      "corner pile: active_fraction 0 while sliding");
	CHECK(af_while_sliding_min < 1.0, "corner pile: every tile swept at every stop "
	      "while sliding (min active_fraction %g)", af_while_sliding_min);
	CHECK_REL(d1.volume, d0.volume, 1e-12, "corner pile: volume in a closed box changed");
	CHECK(d1.inflow == 0.0 && d1.outflow == 0.0, "corner pile: inflow %g, outflow %g "
	      "in a closed box", d1.inflow, d1.outflow);
	CHECK(d1.max_slope_deg < REPOSE + 1.0 && d1.max_slope_deg > REPOSE - 5.0,
	      "corner pile: final steepest face %g deg, not near the repose angle",
	      d1.max_slope_deg);
	printf("  active tiles: %d stops to t = %.4g s (%s), %lld steps, volume %.17g -> "
	       "%.17g m^3, steepest face %.3f deg, identical bits: %s\n"
	       "    active_fraction@t:%s\n", stops, fast.time, steady ? "steady" : "not steady",
	       fast.steps, d0.volume, d1.volume, d1.max_slope_deg, all_same ? "yes" : "NO",
	       line);
	ss_stepper_release(&fast);
	ss_stepper_release(&ref);
	scenario_free(&sc);
}

/* ---- 3. subcritical states ------------------------------------------------ */

static void test_subcritical(void)
{
	const int nx = 83, ny = 47;
	struct scenario sc;
	scenario_alloc(&sc, nx, ny);
	sc.name = "subcritical";
	sc.cl = closures[5];
	sc.dx = 0.02;
	sc.dy = 0.015;
	sc.nu = 0.01;
	const double level = 0.2;
	sc.sides = sides4(SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_OPEN, level);
	struct rng r = {seed + 3};
	for (int k = 0; k < 3; k++)
		random_rect(&r, nx, ny, 10, 8, sc.type, SS_CELL_WALL);
	for (int k = 0; k < 2; k++)
		random_rect(&r, nx, ny, 5, 5, sc.type, SS_CELL_OPEN);
	const double ph1 = 6.28 * rng_uniform(&r), ph2 = 6.28 * rng_uniform(&r);
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			sc.h0[(size_t)j * nx + i] = sin(0.11 * i + ph1) * cos(0.17 * j + ph2) +
			                            0.3 * (rng_uniform(&r) - 0.5);
	/* heights relative to the open level: scale so that the steepest face
	 * (open cells and open sides at their level) is 0.95 tan a_cr */
	struct ss_stepper st;
	double *h_unit = malloc((size_t)nx * ny * sizeof *h_unit);
	memcpy(h_unit, sc.h0, (size_t)nx * ny * sizeof *h_unit);
	sc.sides.open_level = 0.0;
	if (build(&st, &sc, SS_KERNEL_FAST, 16, 8, 2))
		goto out;
	ss_boundary_fill_heights(&st.grid, &st.boundary, st.height);
	const double s_unit = ss_sweep_max_slope(&st.grid, st.height, st.cell_types);
	ss_stepper_release(&st);
	const double tc = tan(REPOSE * M_PI / 180.0);
	for (size_t k = 0; k < (size_t)nx * ny; k++)
		sc.h0[k] = level + h_unit[k] * (0.95 * tc / s_unit);
	sc.sides.open_level = level;
	if (build(&st, &sc, SS_KERNEL_FAST, 16, 8, 2))
		goto out;
	const struct ss_grid *g = &st.grid;
	const size_t storage = ss_grid_storage_cells(g);
	double *before = malloc(storage * sizeof *before);
	ss_boundary_fill_heights(g, &st.boundary, st.height);
	memcpy(before, st.height, storage * sizeof *before);
	const double s0 = ss_sweep_max_slope(g, st.height, st.cell_types);
	CHECK(s0 < tc && s0 > 0.9 * tc, "subcritical: test set-up: steepest face %g, "
	      "tan a_cr %g", s0, tc);

	/* the kernel itself, with a large forced dt */
	const double tiles = (double)st.sweeper->fast.tiles;
	const double awake0 = ss_sweep_fast_awake(&st.sweeper->fast);
	CHECK(awake0 == tiles, "subcritical: %g of %g tiles awake after prepare", awake0, tiles);
	for (int step = 0; step < 3; step++) {
		ss_boundary_fill_heights(g, &st.boundary, st.height);
		const double s = ss_sweep_fast_begin(&st.sweeper->fast, g, st.height, st.cell_types);
		CHECK(s <= tc, "subcritical: step %d: the fast sweep measures slope %g > tan "
		      "a_cr %g", step, s, tc);
		const double rate = ss_sweep_fast_step(&st.sweeper->fast, g, &st.sweeper->face_rule, 1e3, NULL, NULL,
		                                       st.cell_types, st.height, st.ledger->open_flux);
		CHECK(rate == 0.0, "subcritical: step %d: max |dh/dt| %g", step, rate);
		CHECK(memcmp(before, st.height, storage * sizeof *before) == 0,
		      "subcritical: step %d with dt = 1000 s changed the heights", step);
		int flux_zero = 1;
		for (size_t m = 0; m < st.ledger->open_face_count; m++)
			flux_zero &= st.ledger->open_flux[m] == 0.0;
		CHECK(flux_zero, "subcritical: step %d: an open face carries flux", step);
		const double awake = ss_sweep_fast_awake(&st.sweeper->fast);
		CHECK(awake == 0.0, "subcritical: %g of %g tiles still awake after step %d",
		      awake, tiles, step);
	}

	/* and through the stepper: no substep, time jumps, nothing changes */
	{
		ss_stepper_heights_changed(&st);
		advance_to(&st, 50.0, "subcritical stepper");
		CHECK(st.steps == 0, "subcritical: the stepper took %lld substeps", st.steps);
		struct ss_diagnostics d;
		ss_stepper_diagnostics(&st, &d);
		CHECK(d.active_fraction == 0.0, "subcritical: active_fraction %g",
		      d.active_fraction);
		ss_boundary_fill_heights(g, &st.boundary, st.height);
		CHECK(memcmp(before, st.height, storage * sizeof *before) == 0,
		      "subcritical: the stepper changed the heights");
	}
	printf("  subcritical: steepest face %.4f deg, %g tiles asleep after one sweep, "
	       "heights unchanged\n", atan(s0) * 180.0 / M_PI, tiles);
	free(before);
	ss_stepper_release(&st);
out:
	free(h_unit);
	scenario_free(&sc);
}

/* ---- 4. ss_sweep_max_slope against ss_sweep_fluxes ------------------------ */

static void test_max_slope(void)
{
	struct rng r = {seed + 4};
	const enum ss_side_kind kinds[3] = {SS_SIDE_WALL, SS_SIDE_OPEN, SS_SIDE_PERIODIC};
	int cases = 0, mismatches = 0, fast_mismatches = 0;
	double worst_rel = 0.0;
	for (int rep = 0; rep < 40; rep++) {
		const int nx = 5 + rng_int(&r, 60), ny = 3 + rng_int(&r, 50);
		struct scenario sc;
		scenario_alloc(&sc, nx, ny);
		sc.name = "max slope";
		sc.cl = closures[rng_int(&r, N_CLOSURES)];
		sc.dx = 0.005 + 0.02 * rng_uniform(&r);
		sc.dy = 0.005 + 0.02 * rng_uniform(&r);
		sc.nu = 0.01;
		const enum ss_side_kind kx = kinds[rng_int(&r, 3)], ky = kinds[rng_int(&r, 3)];
		const enum ss_side_kind w = kx, e = kx == SS_SIDE_PERIODIC ? kx : kinds[rng_int(&r, 2)];
		const enum ss_side_kind s = ky, n = ky == SS_SIDE_PERIODIC ? ky : kinds[rng_int(&r, 2)];
		sc.sides = sides4(w, e, s, n, 0.05 * (rng_uniform(&r) - 0.5));
		/* scattered single walls and opens as well as blocks */
		for (size_t k = 0; k < (size_t)nx * ny; k++) {
			const double u = rng_uniform(&r);
			sc.type[k] = u < 0.08 ? SS_CELL_WALL : u < 0.12 ? SS_CELL_OPEN : SS_CELL_FLOW;
		}
		random_rect(&r, nx, ny, 8, 6, sc.type, SS_CELL_WALL);
		struct ss_stepper ref, fast;
		const int tnx = 1 + rng_int(&r, 20), tny = 1 + rng_int(&r, 20);
		if (build(&ref, &sc, SS_KERNEL_REFERENCE, tnx, tny, 2)) {
			scenario_free(&sc);
			continue;
		}
		if (build(&fast, &sc, SS_KERNEL_FAST, tnx, tny, 1 + rep % 2)) {
			ss_stepper_release(&ref);
			scenario_free(&sc);
			continue;
		}
		const struct ss_grid *g = &ref.grid;
		for (int state = 0; state < 5; state++) {
			/* amplitudes from far below to far above the critical slope */
			const double amp = sc.dx * pow(10.0, -2.0 + state);
			for (int j = 0; j < ny; j++) {
				for (int i = 0; i < nx; i++) {
					const ptrdiff_t k = ss_grid_index(g, i, j);
					const uint8_t t = ref.sweeper->cell_type_bytes[k];
					const double h = t == SS_CELL_FLOW ? amp * (rng_uniform(&r) - 0.5)
					               : t == SS_CELL_OPEN ? sc.sides.open_level : 0.0;
					ref.height[k] = fast.height[k] = h;
				}
			}
			ss_boundary_fill_heights(g, &ref.boundary, ref.height);
			ss_boundary_fill_heights(g, &fast.boundary, fast.height);
			const double m = ss_sweep_max_slope(g, ref.height, ref.cell_types);
			const double f = ss_sweep_fluxes(g, &ref.sweeper->tiling, &ref.sweeper->face_rule, ref.height,
			                                 ref.sweeper->cell_type_bytes, ref.sweeper->flux_x, ref.sweeper->flux_y);
			ss_sweep_fast_wake_all(&fast.sweeper->fast, g, fast.height, fast.cell_types);
			const double b = ss_sweep_fast_begin(&fast.sweeper->fast, g, fast.height, fast.cell_types);
			cases++;
			if (!same_bits(m, f)) {
				mismatches++;
				worst_rel = fmax(worst_rel, fabs(m - f) / fmax(m, f));
			}
			fast_mismatches += !same_bits(b, f);
			CHECK(same_bits(m, f), "grid %d x %d, sides %d %d %d %d, tiles %dx%d, "
			      "amplitude %g: ss_sweep_max_slope %.17g, ss_sweep_fluxes %.17g",
			      nx, ny, (int)w, (int)e, (int)s, (int)n, tnx, tny, amp, m, f);
			CHECK(same_bits(b, f), "grid %d x %d, sides %d %d %d %d, tiles %dx%d, "
			      "amplitude %g: the fast sweep's first measure %.17g, "
			      "ss_sweep_fluxes %.17g", nx, ny, (int)w, (int)e, (int)s, (int)n,
			      tnx, tny, amp, b, f);
		}
		/* a NaN height: documented NaN */
		const ptrdiff_t k = ss_grid_index(g, nx / 2, ny / 2);
		if (ref.sweeper->cell_type_bytes[k] == SS_CELL_FLOW) {
			ref.height[k] = NAN;
			const double m = ss_sweep_max_slope(g, ref.height, ref.cell_types);
			CHECK(isnan(m), "ss_sweep_max_slope with a NaN height gave %g, not NaN", m);
		}
		ss_stepper_release(&ref);
		ss_stepper_release(&fast);
		scenario_free(&sc);
	}
	printf("  max slope: %d random states, %d mismatches against ss_sweep_fluxes "
	       "(worst relative %.3g), %d for the fast measure\n", cases, mismatches,
	       worst_rel, fast_mismatches);
}

/* ---- 5. the face function ------------------------------------------------- */

/*
 * The honest error bound of a face flux.  ss_face_fluxes and closure.h
 * evaluate the same formula by different roundings (s = s^2 (1/s) with a
 * reciprocal square root against sqrt, b = s (1/w) / sin a_cr against
 * (s / sqrt(1 + s^2)) / sin a_cr), so b, or s for coulomb, differs by a few
 * ulps, and e = b - 1 (sqrt(b) - 1 for casson, s - tan a_cr for coulomb)
 * cancels.  With F = -nu f(s) g_n / s:
 *
 *   |F - F_closure| <= K eps nu |g_n| / s (f(s) + C(s))
 *
 *   C = s / w                                   coulomb (w = sqrt(1 + s^2))
 *   C = (A + G/b) p (e + K eps b)^(p - 1)       bingham (A 2, G 1, p 2),
 *                                               h-bulkley (A 1 + gamma, G gamma,
 *                                               p 1 + 1/gamma)
 *   C = (1/b)^2 P 3 q (e + K eps q)^2           casson (q = sqrt b, P its polynomial)
 *
 * i.e. the relative error eps K (1 + kappa) with the cancellation factor
 * kappa = p b / e (s / (s - tan a_cr) for coulomb), continued through e = 0
 * by the uncertainty K eps b of e itself.  f C-term / f = kappa.  K is
 * measured (printed) and held to BOUND_K.
 */
#define BOUND_K 8.0

static double bound_scale(const struct ss_closure *c, double g_n, double g_t)
{
	const double eps = DBL_EPSILON;
	const double s = sqrt(g_n * g_n + g_t * g_t), w = sqrt(1.0 + s * s);
	const double b = s / w / c->sin_cr, r = 1.0 / b;
	double C;
	switch (c->kind) {
	case SS_CLOSURE_COULOMB:
		C = s / w;
		break;
	case SS_CLOSURE_CASSON: {
		const double q = sqrt(b), e = fmax(q - 1.0, 0.0) + BOUND_K * eps * q;
		const double P = 10.0 * b * q + 6.0 * b + 3.0 * q + 1.0;
		C = r * r * P * 3.0 * q * e * e;
		break;
	}
	default: {
		const double A = 1.0 + c->gamma, G = c->gamma;
		const double p = c->kind == SS_CLOSURE_BINGHAM ? 2.0 : c->power;
		const double e = fmax(b - 1.0, 0.0) + BOUND_K * eps * b;
		C = (A + G * r) * p * pow(e, p - 1.0);
		break;
	}
	}
	/* f at s or, at the threshold, 0 */
	const double f = s > c->tan_cr ? ss_closure_eval(c, s) : 0.0;
	return c->nu * fabs(g_n) / s * (f + C);
}

/* The closure's distance from the threshold: e = b - 1 (sqrt(b) - 1 for
 * casson, (s - tan a_cr) / tan a_cr for coulomb). */
static double excess(const struct ss_closure *c, double s)
{
	const double b = s / sqrt(1.0 + s * s) / c->sin_cr;
	switch (c->kind) {
	case SS_CLOSURE_COULOMB:
		return (s - c->tan_cr) / c->tan_cr;
	case SS_CLOSURE_CASSON:
		return sqrt(b) - 1.0;
	default:
		return b - 1.0;
	}
}

/* Random (g_n, g_t) with |g| = s in a random direction. */
static void random_gradient(struct rng *r, double s, double *gn, double *gt)
{
	const double th = 2.0 * M_PI * rng_uniform(r);
	*gn = s * cos(th);
	*gt = s * sin(th);
}

static void test_face_formula(void)
{
	struct rng r = {seed + 5};
	const double eps = DBL_EPSILON;
	const double nu = 0.0137;
	printf("  face function against nu * ss_closure_face_flux (K: |dF| / (eps nu |g_n|/s "
	       "(f + C)), see bound_scale):\n");
	for (int ci = 0; ci < N_CLOSURES; ci++) {
		double k_all = 0.0, rel_far_all = 0.0, rel_strict_all = 0.0;
		long over_1e14 = 0, far_all = 0, thr_nonzero = 0, thr_negzero = 0;
		long strict_count = 0;
		for (int ai = 0; ai < 4; ai++) {
			/* at 5 deg faces with sqrt(q) == tan a_cr < q exist */
			const double angle = ai == 0 ? REPOSE : ai == 1 ? 20.0 : ai == 2 ? 60.0 : 5.0;
			struct ss_closure c;
			struct ss_face_rule rule;
			if (ss_closure_init(&c, closures[ci].kind, angle, closures[ci].gamma, nu)) {
				CHECK(0, "closure %s refused", closures[ci].name);
				continue;
			}
			ss_face_rule_init(&rule, &c);
			const double tc = c.tan_cr;
			double worst_k = 0.0, worst_k_s = 0.0, worst_strict = 0.0, worst_strict_s = 0.0;
			double far_rel = 0.0;
			for (int k = 0; k < 30000; k++) {
				/* s in (1.01, 50) tan a_cr, and (1 + 1e-13, 1.01) tan a_cr */
				double s;
				if (k < 15000) {
					s = 1.01 * tc * exp(log(50.0 / 1.01) * rng_uniform(&r));
				} else {
					const double lo = log1p(1e-13), hi = log(1.01);
					s = tc * exp(lo + (hi - lo) * rng_uniform(&r));
				}
				double gn, gt, flux;
				random_gradient(&r, s, &gn, &gt);
				ss_face_fluxes(&rule, 1, &gn, &gt, &flux);
				const double want = nu * ss_closure_face_flux(&c, gn, gt);
				const double ss = sqrt(gn * gn + gt * gt);
				const double diff = fabs(flux - want);
				const double kk = diff > 0.0 ? diff / (eps * bound_scale(&c, gn, gt)) : 0.0;
				if (kk > worst_k || kk != kk) {
					worst_k = kk;
					worst_k_s = ss / tc - 1.0;
				}
				if (excess(&c, ss) > 0.1) {
					const double rel = diff / fabs(want);
					far_all++;
					over_1e14 += rel > 1e-14;
					rel_far_all = fmax(rel_far_all, rel);
					/* 1e-14 holds where the cancellation factor kappa
					 * is at most 8 (8 eps K (1 + kappa) < 1e-14) */
					const double b = ss / sqrt(1.0 + ss * ss) / c.sin_cr;
					const double e = excess(&c, ss);
					const double p = c.kind == SS_CLOSURE_COULOMB ? 1.0
					               : c.kind == SS_CLOSURE_BINGHAM ? 2.0
					               : c.kind == SS_CLOSURE_CASSON ? 3.0 : c.power;
					const double kappa = c.kind == SS_CLOSURE_COULOMB ? ss / (ss - tc)
					                   : c.kind == SS_CLOSURE_CASSON ? p * sqrt(b) / e
					                   : p * b / e;
					far_rel = fmax(far_rel, rel);
					if (kappa <= 8.0) {
						strict_count++;
						if (rel > worst_strict) {
							worst_strict = rel;
							worst_strict_s = ss / tc;
						}
					}
				}
			}
			CHECK(worst_k <= BOUND_K, "%s, a_cr %g deg: |F - F_closure| reaches %.3g eps "
			      "nu |g_n|/s (f + C) at s = (1 + %.3g) tan a_cr (bound %g)",
			      closures[ci].name, angle, worst_k, worst_k_s, BOUND_K);
			CHECK(worst_strict <= 1e-14, "%s, a_cr %g deg: ss_face_fluxes differs from nu * "
			      "ss_closure_face_flux by relative %.3g at s = %.6g tan a_cr (e > 0.1, "
			      "cancellation factor <= 8)", closures[ci].name, angle, worst_strict,
			      worst_strict_s);
			/* e > 0.1 with any kappa (up to 4.3 * 1.74 / 0.1 = 75 for
			 * herschel-bulkley 0.3): K <= 4 measured gives 4.3e-14 */
			CHECK(far_rel <= 5e-14, "%s, a_cr %g deg: ss_face_fluxes differs from nu * "
			      "ss_closure_face_flux by relative %.3g where e > 0.1", closures[ci].name,
			      angle, far_rel);
			k_all = fmax(k_all, worst_k);
			rel_strict_all = fmax(rel_strict_all, worst_strict);

			/* at and below the threshold.  face.h: exactly +0 where
			 * g_n^2 + g_t^2 <= tan^2 a_cr (the rule's rounded square);
			 * closure.h: 0 where sqrt(g_n^2 + g_t^2) <= tan a_cr.  The two
			 * disagree only for s within an ulp of tan a_cr, where the face
			 * function must stay inside the bound. */
			int contract = 0;
			double worst_thr = 0.0;
			for (int k = 0; k < 20000; k++) {
				double s;
				if (k < 8000)
					s = tc * rng_uniform(&r);
				else   /* within a few ulps of tan a_cr, either side */
					s = tc * (1.0 + eps * (rng_int(&r, 9) - 6));
				double gn, gt, flux;
				random_gradient(&r, s, &gn, &gt);
				if (k % 500 == 0) {   /* exactly on an axis */
					gn = k % 1000 ? s : -s;
					gt = 0.0;
				}
				const double q = gn * gn + gt * gt;
				ss_face_fluxes(&rule, 1, &gn, &gt, &flux);
				if (q <= rule.tan_cr2)
					contract += !same_bits(flux, 0.0);
				else if (sqrt(q) <= tc) {
					thr_nonzero += flux != 0.0;
					thr_negzero += flux == 0.0 && signbit(flux);
					worst_thr = fmax(worst_thr, fabs(flux) /
					                 (eps * bound_scale(&c, gn, gt)));
				}
			}
			CHECK(contract == 0, "%s, a_cr %g deg: %d faces with g_n^2 + g_t^2 <= "
			      "tan^2 a_cr got a flux other than +0", closures[ci].name, angle,
			      contract);
			CHECK(worst_thr <= BOUND_K, "%s, a_cr %g deg: a face with sqrt(g_n^2 + "
			      "g_t^2) <= tan a_cr got |F| = %.3g eps nu |g_n|/s (f + C)",
			      closures[ci].name, angle, worst_thr);
			const double zero = 0.0;
			double flux;
			ss_face_fluxes(&rule, 1, &zero, &zero, &flux);
			CHECK(same_bits(flux, 0.0), "%s: flux at s = 0 is %g", closures[ci].name, flux);
		}
		printf("    %-30s K <= %.2f; e > 0.1: worst relative %.2e, above 1e-14 in "
		       "%ld of %ld faces; kappa <= 8: worst %.2e (%ld faces); q = g_n^2 + g_t^2 > "
		       "tan^2 a_cr but sqrt(q) <= tan a_cr: %ld non-zero, %ld -0\n", closures[ci].name,
		       k_all, rel_far_all, over_1e14, far_all, rel_strict_all, strict_count,
		       thr_nonzero, thr_negzero);
	}
}

static void test_face_rsqrt(void)
{
	struct rng r = {seed + 6};
	enum { N = 4000 };
	static double x[N], y[N];
	double worst = 0.0, worst_x = 0.0;
	for (int k = 0; k < N; k++) {
		/* log-uniform over 1e-300 .. 1e300, plus powers of 2 and 1 */
		x[k] = k < 100 ? ldexp(1.0, -990 + 20 * k) : pow(10.0, -300.0 + 600.0 * rng_uniform(&r));
		if (k == N - 1)
			x[k] = 1.0;
	}
	ss_face_rsqrt(N, x, y);
	/* masked tails of every length, at every alignment: the same bits */
	int tails = 0;
	for (int n = 1; n <= 9; n++) {
		double t[9];
		for (int off = 0; off < 8; off++) {
			ss_face_rsqrt(n, x + 200 * n + off, t);
			for (int k = 0; k < n; k++)
				tails += !same_bits(t[k], y[200 * n + off + k]);
		}
	}
	CHECK(tails == 0, "ss_face_rsqrt: %d values of short rows (1..9, offsets 0..7) differ "
	      "from the same values in a long row", tails);
	for (int k = 0; k < N; k++) {
		const double want = 1.0 / sqrt(x[k]);
		const double rel = fabs(y[k] - want) / want;
		if (rel > worst || rel != rel) {
			worst = rel;
			worst_x = x[k];
		}
	}
	CHECK(worst <= 1e-15, "ss_face_rsqrt (%s) differs from 1/sqrt by relative %.3g at "
	      "x = %.17g", ss_face_rsqrt_method(), worst, worst_x);
	/* lane independence of the rsqrt: one at a time */
	int differ = 0;
	for (int k = 0; k < N; k += 7) {
		double one;
		ss_face_rsqrt(1, x + k, &one);
		differ += !same_bits(one, y[k]);
	}
	CHECK(differ == 0, "ss_face_rsqrt: %d values differ between a row call and single "
	      "calls", differ);
	printf("  rsqrt (%s): worst relative error %.3g (%.2f ulp) over 1e-300 .. 1e300\n",
	       ss_face_rsqrt_method(), worst, worst / DBL_EPSILON);
}

/* ---- the instruction-set paths (cpu.h) ---------------------------------- */

static const enum ss_cpu_path all_paths[] = {SS_CPU_GENERIC, SS_CPU_AVX2, SS_CPU_AVX512};
#define N_PATHS ((int)(sizeof all_paths / sizeof *all_paths))

/* Use path p for what follows.  0 when this processor (or build) cannot
 * run it: then prints why `what` is skipped there, which is not a pass. */
static int use_path(enum ss_cpu_path p, const char *what)
{
	if (!ss_cpu_path_supported(p)) {
		CHECK_SKIP("%s on the %s path: this processor (or this build) cannot run it", what,
		           ss_cpu_path_name(p));
		return 0;
	}
	const int err = ss_cpu_select(ss_cpu_path_name(p));
	CHECK(err == 0 && ss_cpu_path() == p, "ss_cpu_select(\"%s\") refused or ignored: "
	      "the path in use is %s", ss_cpu_path_name(p), ss_cpu_path_name(ss_cpu_path()));
	return err == 0 && ss_cpu_path() == p;
}

/* The path in use when main() started: what a test that changes it puts back. */
static enum ss_cpu_path default_path;

static void restore_path(void)
{
	const int err = ss_cpu_select(ss_cpu_path_name(default_path));
	CHECK(err == 0, "ss_cpu_select(\"%s\") refused: cannot restore the default path",
	      ss_cpu_path_name(default_path));
}

/* The faces of test_face_lanes: sub- and supercritical faces mixed, some
 * exactly 0; n + PAD of them (see there). */
static void lane_faces(struct rng *r, const struct ss_closure *c, int n, double *gn,
                       double *gt)
{
	for (int k = 0; k < n; k++) {
		const double s = k % 17 == 0 ? 0.0 : 3.0 * c->tan_cr * rng_uniform(r);
		random_gradient(r, s, &gn[k], &gt[k]);
	}
}

/* A row of n faces gives the same bits as n calls with n = 1, wherever a
 * face sits in the row (vector lanes, masked tails, chunk boundaries): on
 * every path this processor runs. */
static void test_face_lanes(void)
{
	/* rows of up to N faces from offsets up to 4: PAD more inputs than
	 * faces, so that no row reads past them */
	enum { N = 300, PAD = 4 };
	double gn[N + PAD], gt[N + PAD], row[N];
	for (int pi = 0; pi < N_PATHS; pi++) {
		const enum ss_cpu_path path = all_paths[pi];
		if (!use_path(path, "face lanes"))
			continue;
		struct rng r = {seed + 7};
		int differ = 0, total = 0;
		for (int ci = 0; ci < N_CLOSURES; ci++) {
			struct ss_closure c;
			struct ss_face_rule rule;
			const int err = ss_closure_init(&c, closures[ci].kind, REPOSE,
			                                closures[ci].gamma, 0.02);
			CHECK(err == 0, "test set-up: closure %s refused", closures[ci].name);
			if (err)
				continue;
			ss_face_rule_init(&rule, &c);
			lane_faces(&r, &c, N + PAD, gn, gt);
			const int lengths[] = {100, N, 129, 7};
			for (size_t li = 0; li < sizeof lengths / sizeof *lengths; li++) {
				const int n = lengths[li];
				const int off = (int)li * 3 % (PAD + 1);   /* shift the lanes */
				ss_face_fluxes(&rule, n, gn + off, gt + off, row);
				int d = 0;
				for (int k = 0; k < n; k++) {
					double one;
					ss_face_fluxes(&rule, 1, gn + off + k, gt + off + k, &one);
					d += !same_bits(one, row[k]);
					total++;
				}
				CHECK(d == 0, "%s path, %s: a row of %d faces (offset %d) differs from "
				      "single calls in %d faces", ss_cpu_path_name(path),
				      closures[ci].name, n, off, d);
				differ += d;
			}
		}
		printf("  face lanes, %s path: %d faces in rows of 100, 300, 129, 7: %d differ "
		       "from single calls\n", ss_cpu_path_name(path), total, differ);
	}
	restore_path();
}

/*
 * The paths against each other.  Faces: the generic and AVX2 paths give
 * the same bits (both take 1/sqrt); the AVX-512 path (vrsqrt14pd) differs
 * in some faces, so that a forced path is seen to be the one that runs,
 * and passes the accuracy checks of the face function (test_face_rsqrt,
 * test_face_formula, run here on each path main() did not run them on).
 * Sweeps: on each path the fast sweep gives the reference sweep's bits
 * (1 and 2 threads, two tile sizes, every closure), and the generic and
 * AVX2 paths give the same bits.  A path this processor cannot run is
 * skipped with a note.
 */
enum { PATH_FACES = 2000 };

/* Fluxes of PATH_FACES random faces of every closure on the path in use,
 * into out[closure][face]. */
static void path_faces(double out[][PATH_FACES])
{
	static double gn[PATH_FACES], gt[PATH_FACES];
	struct rng r = {seed + 8};
	for (int ci = 0; ci < N_CLOSURES; ci++) {
		struct ss_closure c;
		struct ss_face_rule rule;
		const int err = ss_closure_init(&c, closures[ci].kind, REPOSE, closures[ci].gamma,
		                                0.02);
		CHECK(err == 0, "test set-up: closure %s refused", closures[ci].name);
		lane_faces(&r, &c, PATH_FACES, gn, gt);
		ss_face_rule_init(&rule, &c);
		ss_face_fluxes(&rule, PATH_FACES, gn, gt, out[ci]);
	}
}

/* The heights of sc after T s on the path in use (fast sweep, tiles 16x8,
 * 2 threads), by storage index, in a new array (free it) of *n; NULL if
 * the stepper could not be built. */
static double *path_heights(const struct scenario *sc, double T, size_t *n_out)
{
	struct ss_stepper st;
	if (build(&st, sc, SS_KERNEL_FAST, 16, 8, 2))
		return NULL;
	advance_to(&st, T, sc->name);
	const size_t n = ss_grid_storage_cells(&st.grid);
	double *h = malloc(n * sizeof *h);
	if (h)
		memcpy(h, st.height, n * sizeof *h);
	*n_out = n;
	CHECK(h != NULL, "test set-up: out of memory");
	ss_stepper_release(&st);
	return h;
}

/*
 * The faces of several rules (materials, doc/model.md#materials) on every
 * path: a row whose faces all take rule r gives the bits of the one-rule
 * function with r; a row of mixed rules the bits of single calls, with up
 * to 8 rules (a register permutation on AVX-512) and with 12 (gathers);
 * coulomb beside bingham beside casson in one row too.
 */
static void test_face_mixed(void)
{
	enum { N = 300, PAD = 4 };
	double gn[N + PAD], gt[N + PAD], row[N], plain[N];
	uint16_t rules[N + PAD];
	for (int pi = 0; pi < N_PATHS; pi++) {
		const enum ss_cpu_path path = all_paths[pi];
		if (!use_path(path, "face mixed"))
			continue;
		struct rng r = {seed + 11};
		long total = 0, differ = 0;
		for (int variant = 0; variant < 3; variant++) {
			/* 0: 8 angles of one closure; 1: 12; 2: three closures */
			const int count = variant == 1 ? 12 : 8;
			struct ss_closure c[12];
			for (int m = 0; m < count; m++) {
				const int ci = variant == 2 ? (m % 3 == 0 ? 0 : m % 3 == 1 ? 1 : N_CLOSURES - 1)
				                            : 0;
				ss_closure_init(&c[m], closures[ci].kind, 20.0 + 2.5 * m, closures[ci].gamma,
				                0.02 * (1.0 + 0.1 * m));
			}
			struct ss_face_table table;
			if (ss_face_table_create(&table, c, count)) {
				CHECK(0, "test set-up: face table");
				continue;
			}
			lane_faces(&r, &c[count - 1], N + PAD, gn, gt);
			for (int k = 0; k < N + PAD; k++)
				rules[k] = (uint16_t)rng_int(&r, count);
			for (int off = 0; off <= PAD; off += 3) {
				const int n = off ? 129 : N;
				ss_face_fluxes_mixed(&table, n, rules + off, gn + off, gt + off, row);
				long d = 0;
				for (int k = 0; k < n; k++) {
					double one;
					ss_face_fluxes_mixed(&table, 1, rules + off + k, gn + off + k,
					                     gt + off + k, &one);
					d += !same_bits(one, row[k]);
				}
				CHECK(d == 0, "%s path, %d rules: a mixed row of %d faces differs from single "
				      "calls in %ld faces", ss_cpu_path_name(path), count, n, d);
				total += n;
				differ += d;
			}
			/* every face of rule m: the one-rule function's bits */
			for (int m = 0; m < count; m += 3) {
				uint16_t same[N];
				for (int k = 0; k < N; k++)
					same[k] = (uint16_t)m;
				struct ss_face_rule one;
				ss_face_rule_init(&one, &c[m]);
				ss_face_fluxes_mixed(&table, N, same, gn, gt, row);
				ss_face_fluxes(&one, N, gn, gt, plain);
				long d = 0;
				for (int k = 0; k < N; k++)
					d += !same_bits(row[k], plain[k]);
				CHECK(d == 0, "%s path: rule %d of %d in a table differs from it alone in %ld "
				      "faces", ss_cpu_path_name(path), m, count, d);
				total += N;
				differ += d;
			}
			ss_face_table_release(&table);
		}
		printf("  face rules of a table, %s path: %ld faces, %ld differ\n",
		       ss_cpu_path_name(path), total, differ);
	}
	restore_path();
}

static void test_paths(void)
{
	const double T = 0.12;
	static double faces[N_PATHS][N_CLOSURES][PATH_FACES];
	double *heights[N_PATHS][N_CLOSURES] = {{NULL}};
	int ran[N_PATHS] = {0};
	size_t cells = 0;
	for (int pi = 0; pi < N_PATHS; pi++) {
		const enum ss_cpu_path path = all_paths[pi];
		if (!use_path(path, "the face function and both sweeps"))
			continue;
		ran[pi] = 1;
		path_faces(faces[pi]);
		if (path != default_path) {
			printf("  %s path:\n", ss_cpu_path_name(path));
			test_face_rsqrt();
			test_face_formula();
		}
		const long long before = identity_steps;
		for (int c = 0; c < N_CLOSURES; c++) {
			struct rng r = {seed * 53u + (uint64_t)c};
			struct scenario sc;
			char name[160];
			random_scenario(&sc, &r, closures[c], sides4(SS_SIDE_WALL, SS_SIDE_OPEN,
			                SS_SIDE_WALL, SS_SIDE_WALL, 0.0), c % 2, T);
			snprintf(name, sizeof name, "%s path, %s", ss_cpu_path_name(path),
			         closures[c].name);
			sc.name = name;
			static const int some[2] = {0, 3};   /* 7x5 and the default */
			identity_case(&sc, T, some, 2);
			heights[pi][c] = path_heights(&sc, T, &cells);
			scenario_free(&sc);
		}
		printf("  %s path: the fast sweep gives the reference's bits, %d closures x 2 tile "
		       "sizes x 1, 2 threads, %lld reference steps\n", ss_cpu_path_name(path),
		       N_CLOSURES, identity_steps - before);
	}
	/* across paths: generic (index 0) against avx2 (1) and avx512 (2) */
	for (int pi = 1; pi < N_PATHS && ran[0]; pi++) {
		if (!ran[pi])
			continue;
		long face_differ = 0, cell_differ = 0;
		for (int c = 0; c < N_CLOSURES; c++) {
			for (int k = 0; k < PATH_FACES; k++)
				face_differ += !same_bits(faces[pi][c][k], faces[0][c][k]);
			for (size_t k = 0; heights[pi][c] && heights[0][c] && k < cells; k++)
				cell_differ += !same_bits(heights[pi][c][k], heights[0][c][k]);
		}
		const char *name = ss_cpu_path_name(all_paths[pi]);
		if (all_paths[pi] == SS_CPU_AVX2) {
			CHECK(face_differ == 0, "the avx2 path's face fluxes differ from the generic "
			      "path's in %ld of %d faces: they must be the same bits", face_differ,
			      N_CLOSURES * PATH_FACES);
			CHECK(cell_differ == 0, "the avx2 path's sweeps differ from the generic "
			      "path's in %ld cells after %g s: they must be the same bits",
			      cell_differ, T);
		} else {
			CHECK(face_differ > 0, "the avx512 path gives the generic path's bits in "
			      "all %d faces: is it running 1/sqrt, not vrsqrt14pd?",
			      N_CLOSURES * PATH_FACES);
		}
		printf("  %s against generic: %ld of %d faces and %ld cells (%d closures after "
		       "%g s) differ\n", name, face_differ, N_CLOSURES * PATH_FACES, cell_differ,
		       N_CLOSURES, T);
	}
	for (int pi = 0; pi < N_PATHS; pi++)
		for (int c = 0; c < N_CLOSURES; c++)
			free(heights[pi][c]);
	restore_path();
}

/* Packed cell types (grid.h): every set is read back, no set disturbs
 * another cell, and unpacking from any start matches cell-by-cell reads. */
static void test_packed_types(void)
{
	enum { CELLS = 1037 };
	struct rng r = {seed ^ 0x7e57u};
	uint8_t packed[(CELLS + 3) / 4], expect[CELLS], out[CELLS];
	CHECK(ss_cell_types_bytes(CELLS) == sizeof packed,
	      "ss_cell_types_bytes(%d) = %zu, expected %zu", CELLS,
	      ss_cell_types_bytes(CELLS), sizeof packed);
	memset(packed, 0, sizeof packed);
	memset(expect, SS_CELL_FLOW, sizeof expect);
	int wrong = 0;
	for (int n = 0; n < 20000; n++) {
		const int k = rng_int(&r, CELLS);
		const enum ss_cell_type t = (enum ss_cell_type)rng_int(&r, 3);
		ss_cell_type_set(packed, k, t);
		expect[k] = (uint8_t)t;
		if (n % 97 == 0)
			for (int m = 0; m < CELLS; m++)
				wrong += ss_cell_type_get(packed, m) != expect[m];
	}
	CHECK(wrong == 0, "packed types: %d reads differ from the values set", wrong);
	int unpack_wrong = 0;
	for (int k0 = 0; k0 < 9; k0++) {
		ss_cell_types_unpack(packed, k0, (size_t)(CELLS - k0), out);
		unpack_wrong += memcmp(out, expect + k0, (size_t)(CELLS - k0)) != 0;
	}
	CHECK(unpack_wrong == 0, "ss_cell_types_unpack differs from the values set for "
	      "%d of 9 start cells", unpack_wrong);
}

int main(void)
{
	const char *env = getenv("SANDSLIDE_TEST_SEED");
	if (env && *env)
		seed = strtoull(env, NULL, 10);
	const double t0 = check_now();
	ss_parallel_set_threads(2);
	default_path = ss_cpu_path();
	printf("test_sweep: seed %llu, %s path (rsqrt %s), scale %g\n",
	       (unsigned long long)seed, ss_cpu_path_name(default_path), ss_face_rsqrt_method(),
	       test_scale());
	RUN(test_packed_types);
	{
		const double t_ = check_now();
		RUN(test_face_rsqrt);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_face_lanes);
		RUN(test_face_mixed);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_face_formula);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_paths);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_max_slope);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_subcritical);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_identity);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_identity_periodic);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_identity_periodic_pile);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_identity_bedrock);
		RUN(test_identity_materials);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	{
		const double t_ = check_now();
		RUN(test_active_tiles);
		printf("    (%.2f s)\n", check_now() - t_);
	}
	printf("test_sweep: %.2f s\n", check_now() - t0);
	if (!CHECK_OPENMP)
		CHECK_SKIP("the fast kernel on 2 threads: this build has no OpenMP (OPENMP=0), "
		           "every run is on 1 thread");
	return check_report();
}
