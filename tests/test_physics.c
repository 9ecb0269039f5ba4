/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_physics.c - physical properties of the whole engine (doc/model.md),
 * checked end to end through the stepper:
 *
 *   conservation     volume change = inflow - outflow to round-off, with wall
 *                    blocks, open regions, an open side and two sources
 *   subcritical      a state with every face below tan a_cr never changes
 *   cone             a 50 degree cone relaxes to a 35 degree cone
 *   open table       a block on an open table becomes the pyramid
 *                    tan a_cr * (distance to the edge), error O(dx)
 *   oblique walls    a room drained through an off-centre door never goes
 *                    below the continuum stationary state (mirror ghosts)
 *   symmetry         a symmetric set-up stays symmetric
 *   determinism      the same bits for any thread count and tile size
 *   periodic sides   conservation, and a state depending on y alone stays so
 *
 * Grids are small so the program runs in seconds; the measured figures are
 * printed on stdout for the project's notes.  The random seed can be set
 * with SANDSLIDE_TEST_SEED.  SANDSLIDE_TEST_SCALE in (0, 1] (tests/scale.h;
 * 0.5 under `make SANITIZE=1 test` and `make race`) scales the rooms of the
 * oblique-walls test, most of the run time, with every check kept.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "scale.h"
#include "core/sweep.h"
#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/diagnostics.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

#define DEG (M_PI / 180.0)
#define REPOSE 35.0

static uint64_t seed = 20240611;

/* ---- helpers ------------------------------------------------------------ */

static struct ss_boundary sides(enum ss_side_kind w, enum ss_side_kind e,
                                enum ss_side_kind s, enum ss_side_kind n,
                                double open_level)
{
	struct ss_boundary b = {{w, e, s, n}, open_level};
	return b;
}

/* A stepper on an nx x ny grid with spacings dx, dy, origin 0; returns 0 on
 * success (and counts a failed check otherwise). */
static int setup2(struct ss_stepper *st, int nx, int ny, double dx, double dy,
                  enum ss_closure_kind kind, double gamma, double nu,
                  struct ss_boundary b, int tile_nx, int tile_ny)
{
	struct ss_grid g;
	struct ss_closure c;
	int err = ss_grid_init(&g, nx, ny, dx, dy, 0.0, 0.0);
	CHECK(err == 0, "grid %d x %d, dx %g refused", nx, ny, dx);
	if (err)
		return err;
	err = ss_closure_init(&c, kind, REPOSE, gamma, nu);
	CHECK(err == 0, "closure %s refused", ss_closure_name(kind));
	if (err)
		return err;
	err = ss_stepper_init(st, &g, &c, &b, 0.9, tile_nx, tile_ny);
	CHECK(err == 0, "stepper init failed for %d x %d", nx, ny);
	return err;
}

/* The same with dy = dx. */
static int setup(struct ss_stepper *st, int nx, int ny, double dx,
                 enum ss_closure_kind kind, double gamma, double nu,
                 struct ss_boundary b, int tile_nx, int tile_ny)
{
	return setup2(st, nx, ny, dx, dx, kind, gamma, nu, b, tile_nx, tile_ny);
}

static double *hp(struct ss_stepper *st, int i, int j)
{
	return &st->height[ss_grid_index(&st->grid, i, j)];
}

static void set_type(struct ss_stepper *st, int i, int j, enum ss_cell_type type)
{
	ss_cell_type_set(st->cell_types, ss_grid_index(&st->grid, i, j), type);
}

static enum ss_cell_type type_of(const struct ss_stepper *st, int i, int j)
{
	return ss_cell_type_get(st->cell_types, ss_grid_index(&st->grid, i, j));
}

static int prepare(struct ss_stepper *st)
{
	int err = ss_stepper_prepare(st);
	CHECK(err == 0, "ss_stepper_prepare refused the initial state");
	return err;
}

static struct ss_diagnostics diag(struct ss_stepper *st)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	return d;
}

/* Copy the interior heights (row by row) into out[nx * ny]. */
static void interior(struct ss_stepper *st, double *out)
{
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++)
		memcpy(out + (size_t)j * g->nx, hp(st, 0, j), (size_t)g->nx * sizeof *out);
}

/* Advance to t (no steady stop) and check it got there. */
static void advance_to(struct ss_stepper *st, double t)
{
	const struct ss_advance_options o = {.steady_tol = 0.0};
	enum ss_advance_end end = ss_stepper_advance(st, t, &o);
	CHECK(end == SS_ADVANCE_REACHED && st->time == t,
	      "advance to t = %g s ended with %d at t = %.17g s", t, (int)end, st->time);
}

/* Advance until steady (max |dh/dt| < tol) or t_cap; returns the end. */
static enum ss_advance_end advance_steady(struct ss_stepper *st, double tol, double t_cap)
{
	const struct ss_advance_options o = {.steady_tol = tol};
	return ss_stepper_advance(st, t_cap, &o);
}

/* ---- 1. conservation ------------------------------------------------------ */

static void conservation_case(enum ss_closure_kind kind)
{
	const int nx = 40, ny = 30;
	const double dx = 0.1, nu = 0.01, T = 300.0;
	struct ss_stepper st;
	/* west side open, the others walls; open level 0 */
	if (setup(&st, nx, ny, dx, kind, 1.0, nu,
	          sides(SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, 0.0), 16, 8))
		return;
	struct rng r = {seed ^ (uint64_t)kind};
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			/* a ramp rising eastward plus strong noise: supercritical */
			*hp(&st, i, j) = 0.05 * i * dx + 0.3 * rng_uniform(&r);
			int wall = i >= 15 && i < 22 && j >= 8 && j < 14;  /* block */
			int open = i >= 30 && i < 34 && j >= 20 && j < 24; /* a pit */
			set_type(&st, i, j, wall ? SS_CELL_WALL : open ? SS_CELL_OPEN : SS_CELL_FLOW);
		}
	}
	uint8_t *m1 = calloc((size_t)nx * ny, 1), *m2 = calloc((size_t)nx * ny, 1);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			/* source 1 overlaps the wall block: wall cells are ignored */
			m1[j * nx + i] = i >= 12 && i < 20 && j >= 12 && j < 18;
			m2[j * nx + i] = i >= 30 && i < 38 && j >= 3 && j < 9;
		}
	}
	/* one stopping early, one starting late */
	CHECK(ss_stepper_add_source(&st, m1, 2e-3, 0.0, T / 3.0) == 0, "source 1 refused");
	CHECK(ss_stepper_add_source(&st, m2, 1e-3, T / 2.0, 0.9 * T) == 0, "source 2 refused");
	free(m1);
	free(m2);
	if (prepare(&st))
		goto out;

	const double v0 = diag(&st).volume;
	const double times[] = {T / 12.0, T / 3.0, 0.4 * T, T / 2.0, 0.7 * T, 0.9 * T, T};
	double worst = 0.0;
	for (size_t k = 0; k < sizeof times / sizeof *times; k++) {
		advance_to(&st, times[k]);
		struct ss_diagnostics d = diag(&st);
		const double err = fabs((d.volume - v0) - (d.inflow - d.outflow));
		const double scale = fmax(d.volume, fmax(d.inflow, d.outflow));
		CHECK(err <= 1e-12 * scale,
		      "%s: volume not conserved at t = %g s: dV = %.17g, in - out = %.17g, "
		      "error %.3g > 1e-12 * %.6g", ss_closure_name(kind), times[k],
		      d.volume - v0, d.inflow - d.outflow, err, scale);
		if (err / scale > worst)
			worst = err / scale;
	}
	struct ss_diagnostics d = diag(&st);
	/* the run must exercise what it claims to: both sources and outflow */
	const double in1 = 2e-3 * T / 3.0 * 8 * 6 * dx * dx - 2e-3 * T / 3.0 * 5 * 2 * dx * dx;
	const double in2 = 1e-3 * (0.9 * T - T / 2.0) * 8 * 6 * dx * dx;
	CHECK_REL(d.inflow, in1 + in2, 1e-9,
	          "%s: inflow should be source 1 on its 38 flow cells for T/3 plus "
	          "source 2 on 48 cells from T/2 to 0.9 T", ss_closure_name(kind));
	CHECK(d.outflow > 0.01 * v0, "%s: hardly any outflow (%g of %g m^3): the "
	      "open side and pit are not draining", ss_closure_name(kind), d.outflow, v0);
	printf("  conservation %-8s: V0 %.6f, V %.6f, in %.6f, out %.6f m^3, %.0f steps, "
	       "worst |dV - (in - out)| / max = %.2e (seed %llu)\n",
	       ss_closure_name(kind), v0, d.volume, d.inflow, d.outflow, d.steps, worst,
	       (unsigned long long)seed);
out:
	ss_stepper_release(&st);
}

static void test_conservation(void)
{
	conservation_case(SS_CLOSURE_COULOMB);
	conservation_case(SS_CLOSURE_CASSON);
}

/* ---- 2. subcritical states do not move ------------------------------------ */

/* The largest face slope as doc/model.md#face-flux defines it, computed here
 * independently: faces between two non-wall cells of which one flows, wall
 * neighbours mirrored, open cells and ghosts at their held height.  Only
 * faces whose cells both lie west of column i_limit count. */
static double max_face_slope(struct ss_stepper *st, int i_limit)
{
	const struct ss_grid *g = &st->grid;
	ss_boundary_fill_types(g, &st->boundary, st->cell_types);
	ss_boundary_fill_heights(g, &st->boundary, st->height);
	const double *h = st->height;
	/* one byte per cell, unpacked here by the simplest loop */
	const size_t cells = ss_grid_storage_cells(g);
	uint8_t *t = malloc(cells);
	if (!t)
		return NAN;
	for (size_t k = 0; k < cells; k++)
		t[k] = (uint8_t)ss_cell_type_get(st->cell_types, (ptrdiff_t)k);
	double smax = 0.0;
	for (int axis = 0; axis < 2; axis++) {
		const ptrdiff_t n = axis == 0 ? 1 : g->stride;   /* across */
		const ptrdiff_t a = axis == 0 ? g->stride : 1;   /* along */
		const double dn = axis == 0 ? g->dx : g->dy, da = axis == 0 ? g->dy : g->dx;
		for (int j = 0; j <= g->ny; j++) {
			for (int i = 0; i <= g->nx; i++) {
				if ((axis == 0 && j == g->ny) || (axis == 1 && i == g->nx) ||
				    i >= i_limit)
					continue;
				const ptrdiff_t kb = ss_grid_index(g, i, j), ka = kb - n;
				if (t[ka] == SS_CELL_WALL || t[kb] == SS_CELL_WALL ||
				    (t[ka] != SS_CELL_FLOW && t[kb] != SS_CELL_FLOW))
					continue;
				double gt = 0.0;
				const ptrdiff_t ks[2] = {ka, kb};
				for (int m = 0; m < 2; m++) {
					const ptrdiff_t k = ks[m];
					const double up = t[k + a] == SS_CELL_WALL ? h[k] : h[k + a];
					const double dn_ = t[k - a] == SS_CELL_WALL ? h[k] : h[k - a];
					gt += 0.5 * (up - dn_) / (2.0 * da);
				}
				const double gn = (h[kb] - h[ka]) / dn;
				const double s = sqrt(gn * gn + gt * gt);
				if (s > smax)
					smax = s;
			}
		}
	}
	free(t);
	return smax;
}

static void test_subcritical_unchanged(void)
{
	const int nx = 48, ny = 36;
	const double dx = 0.05, level = 0.3;
	struct ss_stepper st;
	/* open west and east sides held at 0.3 m, walls south and north */
	if (setup(&st, nx, ny, dx, SS_CLOSURE_COULOMB, 1.0, 0.01,
	          sides(SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, level), 16, 8))
		return;
	struct rng r = {seed + 2};
	double *p = malloc((size_t)nx * ny * sizeof *p);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const double x = (i + 0.5) / nx, y = (j + 0.5) / ny;
			p[j * nx + i] = sin(2.0 * M_PI * x) * cos(3.0 * M_PI * y) +
			                0.3 * sin(5.0 * M_PI * (x + y)) + 0.2 * (rng_uniform(&r) - 0.5);
			int wall = (i >= 20 && i < 26 && j >= 10 && j < 15) ||      /* block */
			           (j == 25 && i >= 5 && i < 30);                 /* thin wall */
			int open = i >= 36 && i < 40 && j >= 24 && j < 28;        /* pit */
			set_type(&st, i, j, wall ? SS_CELL_WALL : open ? SS_CELL_OPEN : SS_CELL_FLOW);
		}
	}
	/* heights relative to the open level: every face slope is linear in
	 * the perturbation, so one scale factor sets the steepest to 0.8 tc */
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			*hp(&st, i, j) = type_of(&st, i, j) == SS_CELL_OPEN ? level : p[j * nx + i];
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			*hp(&st, i, j) -= level;
	struct ss_boundary b0 = st.boundary;
	st.boundary.open_level = 0.0;
	const double s_unit = max_face_slope(&st, nx + 1);
	st.boundary = b0;
	const double tc = st.closure.tan_cr, scale = 0.8 * tc / s_unit;
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			if (type_of(&st, i, j) != SS_CELL_WALL)
				*hp(&st, i, j) = level + scale * *hp(&st, i, j);
	free(p);
	if (prepare(&st))
		goto out;
	const double s_test = max_face_slope(&st, nx + 1);
	struct ss_diagnostics d0 = diag(&st);
	CHECK(s_test < 0.81 * tc && s_test > 0.79 * tc,
	      "test set-up: steepest face %g is not 0.8 tan a_cr = %g", s_test, 0.8 * tc);
	CHECK_NEAR(d0.max_slope_deg, atan(s_test) / DEG, 1e-9,
	           "the library's steepest face differs from doc/model.md's face slope "
	           "(mirror ghosts at walls, held height at open cells)");

	double *before = malloc((size_t)nx * ny * sizeof *before);
	double *after = malloc((size_t)nx * ny * sizeof *after);
	interior(&st, before);
	advance_to(&st, 100.0);
	interior(&st, after);
	struct ss_diagnostics d1 = diag(&st);
	CHECK(memcmp(before, after, (size_t)nx * ny * sizeof *before) == 0,
	      "a subcritical state (steepest face %.2f deg < %.0f deg) changed", d0.max_slope_deg,
	      REPOSE);
	CHECK(d1.outflow == 0.0 && d1.inflow == 0.0,
	      "a subcritical state had outflow %g, inflow %g", d1.outflow, d1.inflow);
	CHECK(memcmp(&d1.volume, &d0.volume, sizeof d0.volume) == 0,
	      "volume of a subcritical state changed: %.17g -> %.17g", d0.volume, d1.volume);

	const long long steps = st.steps;
	enum ss_advance_end end = advance_steady(&st, 1e-9, 200.0);
	CHECK(end == SS_ADVANCE_STEADY, "steady mode on a subcritical state ended with %d, "
	      "not SS_ADVANCE_STEADY", (int)end);
	CHECK(st.steps == steps && st.time == 100.0,
	      "steady mode on a subcritical state took %lld steps to t = %g s instead of "
	      "stopping at once", st.steps - steps, st.time);
	interior(&st, after);
	CHECK(memcmp(before, after, (size_t)nx * ny * sizeof *before) == 0,
	      "a subcritical state changed in steady mode");
	printf("  subcritical: steepest face %.4f deg (0.8 tan a_cr), %lld substeps over 100 s, "
	       "heights unchanged\n", d0.max_slope_deg, st.steps);
	ss_stepper_release(&st);

	/* the same surface west of a wall across the grid at column 30, with a
	 * supercritical random state east of it: the sweeps now run, and the
	 * subcritical part must still keep its bits */
	const int cut = 30;
	if (setup(&st, nx, ny, dx, SS_CLOSURE_COULOMB, 1.0, 0.01,
	          sides(SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, level), 16, 8))
		goto out_free;
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const int wall = i == cut || (i >= 20 && i < 26 && j >= 10 && j < 15) ||
			                 (j == 25 && i >= 5 && i < 30);
			const int open = i >= 36 && i < 40 && j >= 24 && j < 28;
			set_type(&st, i, j, wall ? SS_CELL_WALL : open ? SS_CELL_OPEN : SS_CELL_FLOW);
			*hp(&st, i, j) = i < cut ? before[j * nx + i] : level + 0.3 * rng_uniform(&r);
		}
	}
	/* rescale the west part so that its own steepest face is 0.8 tc again */
	const double s_cut = max_face_slope(&st, cut);
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < cut; i++)
			*hp(&st, i, j) = level + (*hp(&st, i, j) - level) * (0.8 * tc / s_cut);
	if (prepare(&st) == 0) {
		const double s_west = max_face_slope(&st, cut);
		CHECK(s_west < tc, "test set-up: the west part has a face at slope %g >= tan "
		      "a_cr", s_west);
		interior(&st, before);
		advance_to(&st, 20.0);
		interior(&st, after);
		int west_same = 1, east_moved = 0;
		for (int j = 0; j < ny; j++) {
			for (int i = 0; i < nx; i++) {
				const size_t k = (size_t)j * nx + i;
				const int same = memcmp(&before[k], &after[k], sizeof *before) == 0;
				if (i < cut)
					west_same &= same;
				else
					east_moved |= !same;
			}
		}
		CHECK(st.steps > 0 && east_moved, "test set-up: the supercritical east part did "
		      "not move (%lld steps)", st.steps);
		CHECK(west_same, "a subcritical region (steepest face %.2f deg) changed while "
		      "the sweeps ran for the sliding region beside it", atan(s_west) / DEG);
		printf("  subcritical beside sliding: west part (steepest face %.4f deg) kept its "
		       "bits over %lld substeps\n", atan(s_west) / DEG, st.steps);
	}
	ss_stepper_release(&st);
out_free:
	free(before);
	free(after);
	return;
out:
	ss_stepper_release(&st);
}

/* ---- 3. cone -------------------------------------------------------------- */

static void test_cone(void)
{
	const int n = 64;
	const double dx = 0.05, nu = 0.01, R = 20 * dx;
	const double c = 0.5 * n * dx;  /* centre of the domain */
	struct ss_stepper st;
	if (setup(&st, n, n, dx, SS_CLOSURE_COULOMB, 1.0, nu,
	          sides(SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, 0.0), 0, 0))
		return;
	const double t50 = tan(50.0 * DEG), tc = st.closure.tan_cr;
	for (int j = 0; j < n; j++)
		for (int i = 0; i < n; i++)
			*hp(&st, i, j) = t50 * fmax(R - hypot(ss_grid_x(&st.grid, i) - c,
			                                      ss_grid_y(&st.grid, j) - c), 0.0);
	if (prepare(&st))
		goto out;
	const double v0 = diag(&st).volume;
	const double t0 = check_now();
	enum ss_advance_end end = advance_steady(&st, 1e-7, 1e5);
	const double secs = check_now() - t0;
	struct ss_diagnostics d = diag(&st);
	CHECK(end == SS_ADVANCE_STEADY, "cone did not reach steady (max |dh/dt| %g m/s) by "
	      "t = %g s", st.rate_max, st.time);
	CHECK_NEAR(d.max_slope_deg, REPOSE, 0.5, "steepest face of the relaxed cone is not "
	           "the repose angle");
	CHECK_REL(d.volume, v0, 1e-12, "cone volume not conserved inside walls");
	CHECK(d.outflow == 0.0, "outflow %g through wall sides", d.outflow);

	/* footprint: cells that hold sand; none may touch the walls */
	long cells = 0, at_wall = 0;
	for (int j = 0; j < n; j++) {
		for (int i = 0; i < n; i++) {
			const int sand = *hp(&st, i, j) > 1e-9;
			cells += sand;
			at_wall += sand && (i == 0 || j == 0 || i == n - 1 || j == n - 1);
		}
	}
	CHECK(at_wall == 0, "test set-up: the relaxed cone reaches the walls (%ld cells)",
	      at_wall);
	const double r_foot = sqrt((double)cells / M_PI) * dx;
	const double r_theory = R * cbrt(t50 / tc);
	/* least squares of h against r on the flank */
	double sr = 0, sh = 0, srr = 0, srh = 0;
	long m = 0;
	for (int j = 0; j < n; j++) {
		for (int i = 0; i < n; i++) {
			const double rr = hypot(ss_grid_x(&st.grid, i) - c, ss_grid_y(&st.grid, j) - c);
			if (rr <= 0.2 * r_foot || rr >= 0.8 * r_foot)
				continue;
			const double h = *hp(&st, i, j);
			sr += rr, sh += h, srr += rr * rr, srh += rr * h;
			m++;
		}
	}
	const double slope = -(m * srh - sr * sh) / (m * srr - sr * sr);
	const double angle = atan(slope) / DEG;
	CHECK_NEAR(angle, REPOSE, 0.5, "fitted flank of the relaxed cone (%ld cells, "
	           "0.2 R < r < 0.8 R, R = %.3f m from the footprint)", m, r_foot);
	CHECK_NEAR(r_foot, r_theory, 2.0 * dx, "footprint radius of the relaxed cone is not "
	           "the one of a 35 degree cone of the same volume");
	printf("  cone: t_steady %.1f s, %lld steps, %.2f s wall; max face slope %.4f deg, "
	       "fitted flank %.4f deg; R footprint %.4f m vs %.4f m for a 35 deg cone of "
	       "equal volume; |dV|/V %.2e\n", st.time, st.steps, secs, d.max_slope_deg,
	       angle, r_foot, r_theory, fabs(d.volume - v0) / v0);
out:
	ss_stepper_release(&st);
}

/* ---- 4. open table -------------------------------------------------------- */

struct table_result {
	double err_max, err_mean, excess_max, excess_half;
	double t, secs;
	long long steps;
};

static struct table_result open_table(int n)
{
	const double L = 1.0, H = 0.5, dx = L / n, nu = 0.01;
	struct table_result res = {NAN, NAN, NAN, NAN, 0, 0, 0};
	struct ss_stepper st;
	if (setup(&st, n, n, dx, SS_CLOSURE_COULOMB, 1.0, nu,
	          sides(SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN, 0.0), 0, 0))
		return res;
	for (int j = 0; j < n; j++)
		for (int i = 0; i < n; i++)
			*hp(&st, i, j) = H;
	if (prepare(&st))
		goto out;
	const double t0 = check_now();
	enum ss_advance_end end = advance_steady(&st, 1e-10, 1e5);
	res.secs = check_now() - t0;
	CHECK(end == SS_ADVANCE_STEADY, "open table %d x %d not steady (max |dh/dt| %g m/s) "
	      "by t = %g s", n, n, st.rate_max, st.time);
	const double tc = st.closure.tan_cr;
	double sum = 0.0;
	res.err_max = 0.0;
	res.excess_max = res.excess_half = -INFINITY;
	int bad_i = -1, bad_j = -1;
	for (int j = 0; j < n; j++) {
		for (int i = 0; i < n; i++) {
			const double x = ss_grid_x(&st.grid, i), y = ss_grid_y(&st.grid, j);
			const double d = fmin(fmin(x, L - x), fmin(y, L - y));
			const double h = *hp(&st, i, j), e = fabs(h - tc * d);
			sum += e;
			if (e > res.err_max)
				res.err_max = e;
			const double excess = h - tc * (d + dx);
			res.excess_half = fmax(res.excess_half, h - tc * (d + 0.5 * dx));
			if (excess > res.excess_max) {
				res.excess_max = excess;
				bad_i = i, bad_j = j;
			}
		}
	}
	res.err_mean = sum / ((double)n * n);
	CHECK(res.excess_max <= 1e-9, "open table %d x %d: cell (%d, %d) is %g m above the "
	      "discrete pyramid tan a_cr (d + dx)", n, n, bad_i, bad_j, res.excess_max);
	/* at rest every face is at most critical, so from the open ghost (0 at
	 * distance dx/2 outside the edge) h <= tan a_cr (d + dx/2); the steady
	 * tolerance 1e-10 m/s leaves ~1e-9 m of sand still above it */
	CHECK(res.excess_half <= 1e-7, "open table %d x %d: a cell is %g m above tan a_cr "
	      "(d + dx/2), the highest surface whose faces are all subcritical", n, n,
	      res.excess_half);
	res.t = st.time;
	res.steps = st.steps;
out:
	ss_stepper_release(&st);
	return res;
}

static void test_open_table(void)
{
	const int n[2] = {20, 40};
	struct table_result r[2];
	for (int k = 0; k < 2; k++) {
		r[k] = open_table(n[k]);
		printf("  open table %dx%d: mean |h - h*| %.6f m, max %.6f m (tc dx/2 = %.6f m); "
		       "max h - tc(d + dx) %.3e m, max h - tc(d + dx/2) %.3e m; t_steady %.1f s, "
		       "%lld steps, %.2f s wall\n", n[k], n[k], r[k].err_mean, r[k].err_max,
		       0.5 * tan(REPOSE * DEG) / n[k], r[k].excess_max, r[k].excess_half,
		       r[k].t, r[k].steps, r[k].secs);
	}
	/* first order: both the mean and the largest error halve with dx */
	const double ratio_mean = r[0].err_mean / r[1].err_mean;
	const double ratio_max = r[0].err_max / r[1].err_max;
	CHECK(ratio_mean >= 1.6 && ratio_mean <= 2.5,
	      "mean error against tan a_cr * distance to the edge does not halve with "
	      "dx: %.4g (%dx%d) / %.4g (%dx%d) = %.3f", r[0].err_mean, n[0], n[0],
	      r[1].err_mean, n[1], n[1], ratio_mean);
	CHECK(ratio_max >= 1.6 && ratio_max <= 2.5,
	      "largest error against tan a_cr * distance to the edge does not halve with "
	      "dx: %.4g (%dx%d) / %.4g (%dx%d) = %.3f", r[0].err_max, n[0], n[0],
	      r[1].err_max, n[1], n[1], ratio_max);
	printf("  open table error ratios %d/%d: mean %.3f, max %.3f\n", n[0], n[1], ratio_mean,
	       ratio_max);
}

/* ---- 5. walls met obliquely ----------------------------------------------- */

/* Distance from (x, y) to the axis-aligned segment [xa, xb] x [ya, yb] (one
 * of the two intervals is a point). */
static double door_distance(double x, double y, double xa, double xb, double ya,
                            double yb)
{
	const double cx = x < xa ? xa : x > xb ? xb : x;
	const double cy = y < ya ? ya : y > yb ? yb : y;
	return hypot(x - cx, y - cy);
}

/* Geodesic distance through flow cells from every cell to the door, by
 * Dijkstra on the 8-neighbour graph (edges dx, dy, sqrt(dx^2 + dy^2)) seeded
 * at the cells touching the door with their distance to it.  Every graph
 * path is a path through the room, so it over-estimates the true geodesic
 * distance (by at most ~8 %), never under. */
static void dijkstra(int nx, int ny, double dx, double dy, const uint8_t *flow,
                     const double *seed_dist, double *dist)
{
	const size_t n = (size_t)nx * ny;
	uint8_t *done = calloc(n, 1);
	for (size_t k = 0; k < n; k++)
		dist[k] = seed_dist[k];
	for (;;) {
		/* O(n^2) selection: the grids are tiny */
		size_t best = n;
		for (size_t k = 0; k < n; k++)
			if (!done[k] && flow[k] && isfinite(dist[k]) &&
			    (best == n || dist[k] < dist[best]))
				best = k;
		if (best == n)
			break;
		done[best] = 1;
		const int i = (int)(best % nx), j = (int)(best / nx);
		for (int dj = -1; dj <= 1; dj++) {
			for (int di = -1; di <= 1; di++) {
				const int a = i + di, b = j + dj;
				if ((!di && !dj) || a < 0 || b < 0 || a >= nx || b >= ny)
					continue;
				const size_t k = (size_t)b * nx + a;
				/* a diagonal step needs both side cells free */
				if (!flow[k] || (di && dj && (!flow[(size_t)j * nx + a] ||
				                               !flow[(size_t)b * nx + i])))
					continue;
				const double dd = dist[best] + hypot(di * dx, dj * dy);
				if (dd < dist[k])
					dist[k] = dd;
			}
		}
	}
	free(done);
}

/*
 * A rx x ry-cell rectangular room inside walls w cells thick.  The door, a
 * gap of door_w cells starting door_at cells from the room's south (west)
 * corner, is cut through the south (door_east = 0) or east wall and filled
 * with open cells at level 0; that side of the grid is open beyond it.  The
 * off-centre door makes the stationary surface, tan a_cr times the distance
 * to the door, meet every wall obliquely.
 */
static void oblique_room(int rx, int ry, int door_east, int door_at, int door_w,
                         double dx, double dy)
{
	const int w = 2, nx = rx + 2 * w, ny = ry + 2 * w;
	const double nu = 0.01;
	const enum ss_side_kind W = SS_SIDE_WALL, O = SS_SIDE_OPEN;
	struct ss_stepper st;
	if (setup2(&st, nx, ny, dx, dy, SS_CLOSURE_COULOMB, 1.0, nu,
	           door_east ? sides(W, O, W, W, 0.0) : sides(W, W, O, W, 0.0), 0, 0))
		return;
	const double tc = st.closure.tan_cr, t50 = tan(50.0 * DEG);
	/* the door segment: the faces between the room and the door cells */
	const int d0 = w + door_at, d1 = d0 + door_w;
	const double xa = door_east ? (nx - w) * dx : d0 * dx;
	const double xb = door_east ? xa : d1 * dx;
	const double ya = door_east ? d0 * dy : w * dy;
	const double yb = door_east ? d1 * dy : ya;
	const size_t cells = (size_t)nx * ny;
	uint8_t *flow = calloc(cells, 1);
	double *seed_dist = malloc(cells * sizeof *seed_dist);
	double *geo = malloc(cells * sizeof *geo);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const int in_room = i >= w && i < nx - w && j >= w && j < ny - w;
			const int along = door_east ? j : i, across = door_east ? nx - 1 - i : j;
			const int in_door = across < w && along >= d0 && along < d1;
			const int by_door = in_room && across == w && along >= d0 && along < d1;
			set_type(&st, i, j, in_room ? SS_CELL_FLOW : in_door ? SS_CELL_OPEN : SS_CELL_WALL);
			flow[(size_t)j * nx + i] = (uint8_t)in_room;
			seed_dist[(size_t)j * nx + i] = by_door ? 0.5 * (door_east ? dx : dy) : INFINITY;
		}
	}
	dijkstra(nx, ny, dx, dy, flow, seed_dist, geo);
	/* the room is convex, so the Euclidean distance to the door is the
	 * geodesic one: the Dijkstra distance must never fall below it */
	double geo_low = INFINITY, geo_high = 0.0;
	for (int j = w; j < ny - w; j++) {
		for (int i = w; i < nx - w; i++) {
			const double d = door_distance(ss_grid_x(&st.grid, i), ss_grid_y(&st.grid, j),
			                               xa, xb, ya, yb);
			const double g = geo[(size_t)j * nx + i];
			geo_low = fmin(geo_low, g - d);
			geo_high = fmax(geo_high, g - d);
			/* well above the continuum stationary state, 50 deg steep */
			*hp(&st, i, j) = t50 * g + 0.2;
		}
	}
	CHECK(geo_low >= -1e-12, "test set-up: Dijkstra distance below the Euclidean one by %g",
	      -geo_low);
	free(flow);
	free(seed_dist);
	free(geo);
	if (prepare(&st))
		goto out;
	const double v0 = diag(&st).volume;
	const double t0 = check_now();
	enum ss_advance_end end = advance_steady(&st, 1e-12, 1e6);
	const double secs = check_now() - t0;
	struct ss_diagnostics d = diag(&st);
	CHECK(end == SS_ADVANCE_STEADY, "room did not reach steady: max |dh/dt| %g m/s at "
	      "t = %g s", st.rate_max, st.time);
	CHECK(st.rate_max <= 1e-12, "room: max |dh/dt| %g m/s is not at round-off", st.rate_max);
	CHECK(fabs((d.volume - v0) + d.outflow) <= 1e-12 * v0,
	      "room: volume lost %.17g m^3 but outflow %.17g m^3", v0 - d.volume, d.outflow);
	CHECK_NEAR(d.max_slope_deg, REPOSE, 1e-3, "room: steepest face at rest is not the "
	           "repose angle");

	double margin = INFINITY, margin_wall = INFINITY, excess = -INFINITY;
	int mi = -1, mj = -1;
	for (int j = w; j < ny - w; j++) {
		for (int i = w; i < nx - w; i++) {
			const double dist = door_distance(ss_grid_x(&st.grid, i),
			                                  ss_grid_y(&st.grid, j), xa, xb, ya, yb);
			const double e = *hp(&st, i, j) - tc * dist;
			if (e < margin) {
				margin = e;
				mi = i, mj = j;
			}
			const int by_wall = i == w || i == nx - w - 1 || j == w || j == ny - w - 1;
			if (by_wall && e < margin_wall)
				margin_wall = e;
			excess = fmax(excess, e);
		}
	}
	CHECK(margin >= -1e-9, "room: cell (%d, %d) drained %g m below the continuum "
	      "stationary state tan a_cr * (distance to the door)", mi, mj, -margin);
	CHECK(excess <= 2.0 * tc * fmax(dx, dy), "room: sand stays %g m above the continuum "
	      "stationary state, more than 2 tan a_cr max(dx, dy) = %g m", excess,
	      2.0 * tc * fmax(dx, dy));
	printf("  oblique walls, %dx%d room, door %s, dx %.3f dy %.3f m: t_steady %.1f s, "
	       "%lld steps, %.2f s wall, last max |dh/dt| %.2e m/s, max face slope %.6f deg\n"
	       "    min h - tc d = %.4e m at (%d, %d) = %.3f tc min(dx, dy); along the walls "
	       "%.4e m; max h - tc d %.4e m; outflow %.4f of %.4f m^3, |dV + out| / V0 "
	       "%.2e; Dijkstra - Euclid in [%.1e, %.4f] m\n",
	       rx, ry, door_east ? "east" : "south", dx, dy, st.time, st.steps, secs,
	       st.rate_max, d.max_slope_deg, margin, mi, mj, margin / (tc * fmin(dx, dy)),
	       margin_wall, excess, d.outflow, v0, fabs(d.volume - v0 + d.outflow) / v0,
	       geo_low, geo_high);
out:
	ss_stepper_release(&st);
}

static void test_oblique_walls(void)
{
	/* SANDSLIDE_TEST_SCALE (scale.h) shrinks the rooms and doors, cells
	 * keeping their size: the door stays off-centre */
	oblique_room(test_scaled(30, 8), test_scaled(24, 8), 0, test_scaled(5, 2),
	             test_scaled(4, 2), 0.05, 0.05);
	oblique_room(test_scaled(24, 8), test_scaled(30, 8), 1, test_scaled(20, 5),
	             test_scaled(3, 2), 0.05, 0.04);
}

/* ---- 6. symmetry ---------------------------------------------------------- */

static void test_symmetry(void)
{
	const int n = 40;
	const double dx = 0.05, nu = 0.01, R = 12 * dx;
	struct ss_stepper st;
	if (setup(&st, n, n, dx, SS_CLOSURE_BINGHAM, 1.0, nu,
	          sides(SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN, SS_SIDE_OPEN, 0.0), 16, 8))
		return;
	const double t55 = tan(55.0 * DEG);
	uint8_t *mask = calloc((size_t)n * n, 1);
	for (int j = 0; j < n; j++) {
		for (int i = 0; i < n; i++) {
			/* offsets from the centre, exactly antisymmetric */
			const double ox = (2 * i - (n - 1)) * 0.5 * dx, oy = (2 * j - (n - 1)) * 0.5 * dx;
			const double r = sqrt(ox * ox + oy * oy);
			*hp(&st, i, j) = t55 * fmax(R - r, 0.0) +
			                 0.05 * (1.0 + cos(M_PI * r / (n * dx)));
			mask[j * n + i] = abs(2 * i - (n - 1)) <= 3 && abs(2 * j - (n - 1)) <= 3;
		}
	}
	CHECK(ss_stepper_add_source(&st, mask, 5e-3, 0.0, 40.0) == 0, "source refused");
	free(mask);
	if (prepare(&st))
		goto out;
	advance_to(&st, 60.0);
	double dev[3] = {0, 0, 0};
	for (int j = 0; j < n; j++) {
		for (int i = 0; i < n; i++) {
			const double h = *hp(&st, i, j);
			dev[0] = fmax(dev[0], fabs(h - *hp(&st, n - 1 - i, j)));
			dev[1] = fmax(dev[1], fabs(h - *hp(&st, i, n - 1 - j)));
			dev[2] = fmax(dev[2], fabs(h - *hp(&st, j, i)));
		}
	}
	struct ss_diagnostics d = diag(&st);
	CHECK(dev[0] <= 1e-12, "x-mirror symmetry broken by %g m", dev[0]);
	CHECK(dev[1] <= 1e-12, "y-mirror symmetry broken by %g m", dev[1]);
	CHECK(dev[2] <= 1e-12, "diagonal (transpose) symmetry broken by %g m", dev[2]);
	CHECK(d.outflow > 0.0 && d.inflow > 0.0, "symmetry run is trivial: inflow %g, "
	      "outflow %g", d.inflow, d.outflow);
	printf("  symmetry (bingham, %lld steps): max |h - mirror| x %.2e, y %.2e, "
	       "transpose %.2e m; max h %.4f m, max slope %.3f deg\n", st.steps, dev[0], dev[1],
	       dev[2], d.max_height, d.max_slope_deg);
out:
	ss_stepper_release(&st);
}

/* ---- 7. determinism ------------------------------------------------------- */

struct det_result {
	double *h;
	double inflow, outflow;
	long long steps;
};

/* Large enough for several tiles per thread; 203 x 131 is not a multiple
 * of any tile size used. */
#define DET_NX 203
#define DET_NY 131

static struct det_result determinism_run(int threads, int tile_nx, int tile_ny)
{
	const int nx = DET_NX, ny = DET_NY;
	const double dx = 0.05;
	struct det_result res = {NULL, 0, 0, 0};
	struct ss_stepper st;
	ss_parallel_set_threads(threads);
	if (setup(&st, nx, ny, dx, SS_CLOSURE_HERSCHEL_BULKLEY, 0.5, 0.01,
	          sides(SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_OPEN, 0.1), tile_nx,
	          tile_ny))
		return res;
	struct rng r = {seed + 7};
	uint8_t *mask = calloc((size_t)nx * ny, 1);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			*hp(&st, i, j) = 0.2 + 0.0025 * i + 0.25 * rng_uniform(&r);
			const int wall = (i - 115) * (i - 115) + (j - 48) * (j - 48) < 256 ||
			                 (i == 38 && j > 18 && j < 113);
			const int open = i >= 153 && i < 169 && j >= 96 && j < 113;
			set_type(&st, i, j, wall ? SS_CELL_WALL : open ? SS_CELL_OPEN : SS_CELL_FLOW);
			mask[j * nx + i] = i >= 57 && i < 85 && j >= 80 && j < 107;
		}
	}
	CHECK(ss_stepper_add_source(&st, mask, 3e-3, 2.0, 25.0) == 0, "source refused");
	free(mask);
	if (prepare(&st) == 0) {
		advance_to(&st, 60.0);
		res.h = malloc((size_t)nx * ny * sizeof *res.h);
		interior(&st, res.h);
		res.inflow = ss_stepper_inflow(&st);
		res.outflow = ss_stepper_outflow(&st);
		res.steps = st.steps;
	}
	ss_stepper_release(&st);
	return res;
}

static void test_determinism(void)
{
	const int nx = DET_NX, ny = DET_NY, threads = ss_parallel_max_threads();
	const struct det_result a = determinism_run(1, 256, 32);
	const struct det_result b = determinism_run(2, 7, 5);
	const struct det_result c = determinism_run(2, 16, 64);
	ss_parallel_set_threads(threads);
	if (!a.h || !b.h || !c.h)
		goto out;
	const size_t bytes = (size_t)nx * ny * sizeof *a.h;
	CHECK(memcmp(a.h, b.h, bytes) == 0, "heights differ: 1 thread tiles 256x32 vs "
	      "2 threads tiles 7x5");
	CHECK(memcmp(a.h, c.h, bytes) == 0, "heights differ: 1 thread tiles 256x32 vs "
	      "2 threads tiles 16x64");
	CHECK(memcmp(&a.inflow, &b.inflow, sizeof a.inflow) == 0 &&
	      memcmp(&a.inflow, &c.inflow, sizeof a.inflow) == 0,
	      "inflow differs: %.17g %.17g %.17g", a.inflow, b.inflow, c.inflow);
	CHECK(memcmp(&a.outflow, &b.outflow, sizeof a.outflow) == 0 &&
	      memcmp(&a.outflow, &c.outflow, sizeof a.outflow) == 0,
	      "outflow differs: %.17g %.17g %.17g", a.outflow, b.outflow, c.outflow);
	CHECK(a.steps == b.steps && a.steps == c.steps, "substep counts differ: %lld %lld %lld",
	      a.steps, b.steps, c.steps);
	CHECK(a.outflow > 0.0 && a.inflow > 0.0, "determinism run is trivial");
	if (!CHECK_OPENMP)
		CHECK_SKIP("1 thread against 2: this build has no OpenMP (OPENMP=0), every run "
		           "is on 1 thread");
	printf("  determinism (herschel-bulkley 0.5, %dx%d cells, %lld steps): in %.17g, "
	       "out %.17g m^3, identical for 1 thread 256x32, 2 threads 7x5 and 16x64\n",
	       nx, ny, a.steps, a.inflow, a.outflow);
out:
	free(a.h);
	free(b.h);
	free(c.h);
}

/* ---- 8. periodic sides ---------------------------------------------------- */

static void periodic_case(int axis)
{
	/* axis 0: x periodic, y walls; axis 1: the transpose */
	const int n_per = 32, n_wall = 24;
	const int nx = axis == 0 ? n_per : n_wall, ny = axis == 0 ? n_wall : n_per;
	const double dx = 0.05;
	const enum ss_side_kind P = SS_SIDE_PERIODIC, W = SS_SIDE_WALL;
	const struct ss_boundary b = axis == 0 ? sides(P, P, W, W, 0.0) : sides(W, W, P, P, 0.0);
	const char *name = axis == 0 ? "x" : "y";
	struct ss_stepper st;

	/* a flat layer with a random supercritical patch away from the seam and
	 * a ridge on the first periodic column (row): volume is conserved, and
	 * the flat cells on the far side of the seam fill only through it */
	if (setup(&st, nx, ny, dx, SS_CLOSURE_COULOMB, 1.0, 0.01, b, 8, 8))
		return;
	struct rng r = {seed + 8 + (uint64_t)axis};
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const int k = axis == 0 ? i : j;
			*hp(&st, i, j) = 0.3 + 0.3 * (k == 0) +
			                 (k >= 8 && k < n_per - 8 ? 0.3 * rng_uniform(&r) : 0.0);
		}
	}
	if (prepare(&st) == 0) {
		const double v0 = diag(&st).volume;
		const double seam0 = axis == 0 ? *hp(&st, nx - 1, 5) : *hp(&st, 5, ny - 1);
		advance_to(&st, 20.0);
		struct ss_diagnostics d = diag(&st);
		const double seam1 = axis == 0 ? *hp(&st, nx - 1, 5) : *hp(&st, 5, ny - 1);
		CHECK_REL(d.volume, v0, 1e-12, "%s-periodic run lost volume", name);
		CHECK(d.outflow == 0.0, "%s-periodic run with wall sides had outflow %g", name,
		      d.outflow);
		CHECK(seam1 > seam0, "%s-periodic: the last cell did not fill from the ridge "
		      "across the seam (%.17g -> %.17g m)", name, seam0, seam1);
		printf("  periodic %s: |dV|/V %.2e over %lld steps\n", name,
		       fabs(d.volume - v0) / v0, st.steps);
	}
	ss_stepper_release(&st);

	/* a state depending only on the wall-bounded coordinate stays so */
	if (setup(&st, nx, ny, dx, SS_CLOSURE_COULOMB, 1.0, 0.01, b, 7, 5))
		return;
	const double t55 = tan(55.0 * DEG);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			const int k = axis == 0 ? j : i;
			*hp(&st, i, j) = t55 * fabs((k + 0.5) * dx - 0.3) + 0.02 * (k % 3);
		}
	}
	if (prepare(&st) == 0) {
		const double h0 = *hp(&st, 0, 0);
		advance_to(&st, 20.0);
		int same = 1;
		for (int j = 0; j < ny; j++)
			for (int i = 0; i < nx; i++)
				same &= memcmp(hp(&st, i, j), axis == 0 ? hp(&st, 0, j) : hp(&st, i, 0),
				               sizeof(double)) == 0;
		CHECK(same, "%s-periodic: a state depending on %s alone grew a dependence on %s",
		      name, axis == 0 ? "y" : "x", name);
		CHECK(*hp(&st, 0, 0) != h0, "%s-periodic: the one-dimensional state did not move",
		      name);
		printf("  periodic %s: 1-D state (%lld steps) stays 1-D bit for bit\n", name,
		       st.steps);
	}
	ss_stepper_release(&st);
}

static void test_periodic(void)
{
	periodic_case(0);
	periodic_case(1);
}

/* ---- main ----------------------------------------------------------------- */

static double timed(void (*fn)(void))
{
	const double t0 = check_now();
	fn();
	return check_now() - t0;
}

#define RUN_TIMED(fn)                                                         \
	do {                                                                  \
		const struct check_mark mark_ = check_begin(#fn);             \
		const double secs_ = timed(fn);                               \
		printf("%s %s (%.2f s)\n", check_end(mark_), #fn, secs_);     \
		fflush(stdout);                                               \
	} while (0)

/* ---- bedrock ------------------------------------------------------------ */

/* Smallest sand thickness h - b over the flow cells, checked after every
 * substep through the progress hook. */
struct thickness_watch {
	double min_thickness;
};

static void watch_thickness(void *context, const struct ss_stepper *st)
{
	struct thickness_watch *w = context;
	const struct ss_grid *g = &st->grid;
	for (int j = 0; j < g->ny; j++) {
		for (int i = 0; i < g->nx; i++) {
			const ptrdiff_t k = ss_grid_index(g, i, j);
			if (ss_cell_type_get(st->cell_types, k) == SS_CELL_FLOW)
				w->min_thickness = fmin(w->min_thickness, st->height[k] - st->bedrock[k]);
		}
	}
}

/* A 5 mm layer on a bedrock inclined at 45 degrees (steeper than the 35
 * degree repose angle), open at the low east end: all of it slides off,
 * leaving the bedrock bare; no cell ever goes below its bedrock, and the
 * volume that left is the volume that was there. */
static void test_bedrock_slide_off(void)
{
	const int nx = 60, ny = 12;
	const double dx = 0.01, slope = 1.0, layer = 0.005;
	const double open_level = -slope * (nx + 0.5) * dx;  /* the plane, one cell out */
	struct ss_stepper st;
	if (setup(&st, nx, ny, dx, SS_CLOSURE_COULOMB, 1.0, 0.05,
	          sides(SS_SIDE_WALL, SS_SIDE_OPEN, SS_SIDE_WALL, SS_SIDE_WALL, open_level),
	          16, 8))
		return;
	double *bedrock = malloc((size_t)nx * ny * sizeof *bedrock);
	for (int j = 0; j < ny; j++) {
		for (int i = 0; i < nx; i++) {
			bedrock[(size_t)j * nx + i] = -slope * (i + 0.5) * dx;
			*hp(&st, i, j) = bedrock[(size_t)j * nx + i] + layer;
		}
	}
	int err = ss_stepper_set_bedrock(&st, bedrock);
	CHECK(err == 0, "bedrock slide-off: bedrock refused");
	if (err || prepare(&st))
		goto out;
	const struct ss_diagnostics d0 = diag(&st);
	const double v0 = d0.volume;
	struct thickness_watch w = {INFINITY};
	const struct ss_advance_options o = {.steady_tol = 1e-9, .progress = watch_thickness,
	                                     .context = &w};
	const enum ss_advance_end end = ss_stepper_advance(&st, 50.0, &o);
	struct ss_diagnostics d = diag(&st);
	double left = 0.0;
	for (int j = 0; j < ny; j++)
		for (int i = 0; i < nx; i++)
			left = fmax(left, *hp(&st, i, j) - bedrock[(size_t)j * nx + i]);
	CHECK(end == SS_ADVANCE_STEADY, "bedrock slide-off: no steady state by t = %g s "
	      "(ended %d, max |dh/dt| %g m/s)", st.time, (int)end, st.rate_max);
	CHECK(w.min_thickness >= -1e-15, "bedrock slide-off: a cell went %.3g m below its "
	      "bedrock", -w.min_thickness);
	CHECK(left < 1e-9, "bedrock slide-off: %.3g m of sand left on the 45 degree "
	      "bedrock (of %g m)", left, layer);
	CHECK_REL(d.outflow + (d.volume - (v0 - layer * nx * ny * dx * dx)),
	          layer * nx * ny * dx * dx, 1e-10,
	          "bedrock slide-off: the outflow is not the sand that was there");
	/* the steepest face in sand: at least the 45 degrees of the rock under
	 * the layer (the open side's step is steeper), none once the rock is
	 * bare (bare rock does not count) */
	CHECK(d0.max_slope_deg >= 45.0 - 1e-9, "bedrock slide-off: steepest face %.6g deg "
	      "under the layer, below the rock's 45", d0.max_slope_deg);
	CHECK(d.max_slope_deg == 0.0, "bedrock slide-off: max_slope_deg %.6g deg on bare "
	      "bedrock: the rock counted, not only the faces in sand", d.max_slope_deg);
	printf("  slide-off: %lld steps to t = %.3g s, thickest remaining %.3g m, thinnest "
	       "ever %.3g m, outflow %.6g of %.6g m^3\n", st.steps, st.time, left,
	       w.min_thickness, d.outflow, layer * nx * ny * dx * dx);
out:
	free(bedrock);
	ss_stepper_release(&st);
}

/* A 50 degree cone of sand on a flat bedrock at 0 with bare bedrock round
 * it: the pile relaxes to the repose angle, spreading over the bare cells,
 * with its volume conserved and no cell below the bedrock. */
static void test_bedrock_flat_pile(void)
{
	const int n = 48;
	const double dx = 0.05, R = 14 * dx, c = 0.5 * n * dx;
	struct ss_stepper st;
	if (setup(&st, n, n, dx, SS_CLOSURE_COULOMB, 1.0, 0.01,
	          sides(SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, 0.0), 0, 0))
		return;
	const double t50 = tan(50.0 * DEG), tc = st.closure.tan_cr;
	double *bedrock = calloc((size_t)n * n, sizeof *bedrock);
	for (int j = 0; j < n; j++)
		for (int i = 0; i < n; i++)
			*hp(&st, i, j) = t50 * fmax(R - hypot(ss_grid_x(&st.grid, i) - c,
			                                      ss_grid_y(&st.grid, j) - c), 0.0);
	int err = ss_stepper_set_bedrock(&st, bedrock);
	CHECK(err == 0, "bedrock pile: bedrock refused");
	if (err || prepare(&st))
		goto out;
	const double v0 = diag(&st).volume;
	struct thickness_watch w = {INFINITY};
	const struct ss_advance_options o = {.steady_tol = 1e-10, .progress = watch_thickness,
	                                     .context = &w};
	const enum ss_advance_end end = ss_stepper_advance(&st, 1e5, &o);
	struct ss_diagnostics d = diag(&st);
	const double s_max = max_face_slope(&st, n + 1);
	CHECK(end == SS_ADVANCE_STEADY, "bedrock pile: no steady state by t = %g s", st.time);
	CHECK(s_max <= tc + 1e-6, "bedrock pile: steepest face %.9g above tan a_cr %.9g at "
	      "steady state", s_max, tc);
	CHECK(s_max >= tc - 0.02, "bedrock pile: steepest face %.6g: the pile is not at the "
	      "repose angle (%.6g)", s_max, tc);
	CHECK_REL(d.volume, v0, 1e-12, "bedrock pile: volume not conserved");
	CHECK(w.min_thickness >= -1e-15, "bedrock pile: a cell went %.3g m below the "
	      "bedrock", -w.min_thickness);
	printf("  flat bedrock pile: steady at t = %.3g s, steepest face %.4f deg, thinnest "
	       "%.3g m\n", st.time, atan(s_max) / DEG, w.min_thickness);
out:
	free(bedrock);
	ss_stepper_release(&st);
}

/* A bedrock above the surface or not finite is refused (the messages,
 * which name the cell, go to stderr). */
static void test_bedrock_refused(void)
{
	struct ss_stepper st;
	if (setup(&st, 8, 6, 0.1, SS_CLOSURE_COULOMB, 1.0, 0.01,
	          sides(SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, SS_SIDE_WALL, 0.0), 0, 0))
		return;
	double bedrock[48] = {0};
	bedrock[2 * 8 + 5] = 0.25;   /* cell (5, 2), above the zero surface */
	int err = ss_stepper_set_bedrock(&st, bedrock);
	CHECK(err == 0, "bedrock refused before the surface is known");
	err = ss_stepper_prepare(&st);
	CHECK(err == SS_ERR_INPUT, "a bedrock above the surface gave %d, not SS_ERR_INPUT",
	      err);
	bedrock[2 * 8 + 5] = NAN;
	err = ss_stepper_set_bedrock(&st, bedrock);
	CHECK(err == SS_ERR_INPUT, "a NaN bedrock gave %d, not SS_ERR_INPUT", err);
	ss_stepper_release(&st);
}

int main(void)
{
	const char *s = getenv("SANDSLIDE_TEST_SEED");
	if (s && *s)
		seed = strtoull(s, NULL, 0);
	printf("test_physics: seed %llu, %d threads, scale %g\n", (unsigned long long)seed,
	       ss_parallel_max_threads(), test_scale());
	const double t0 = check_now();
	RUN_TIMED(test_conservation);
	RUN_TIMED(test_subcritical_unchanged);
	RUN_TIMED(test_cone);
	RUN_TIMED(test_open_table);
	RUN_TIMED(test_oblique_walls);
	RUN_TIMED(test_symmetry);
	RUN_TIMED(test_determinism);
	RUN_TIMED(test_periodic);
	RUN_TIMED(test_bedrock_slide_off);
	RUN_TIMED(test_bedrock_flat_pile);
	RUN_TIMED(test_bedrock_refused);
	printf("total %.2f s\n", check_now() - t0);
	return check_report();
}
