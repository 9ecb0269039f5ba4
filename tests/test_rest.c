/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_rest.c - the approach to rest (src/core/rest.h): Chebyshev
 * super-steps once a run that asked to come to rest moves slowly.
 *
 *   a 50 degree cone on a closed floor, and a pile by an open side (sand
 *   leaves): forward Euler with the approach against forward Euler alone
 *   to the same steady rule: both steady, no face steeper than the rule
 *   allows, the volume kept to round-off (and the outflow booked), the end
 *   state no farther from Euler's, in mean and at most, than the Coulomb
 *   and Bingham end states are from each other (the paper's point: the
 *   rest state depends little on the law, so the path may not matter
 *   more), in fewer evaluations; after RKL2 as well;
 *   the same bits for 1 and 2 threads, two tile sizes and both kernels;
 *   a restart from the state after a super-step of the approach gives
 *   the bits of the run that was never stopped;
 *   a stop between the stages of a super-step takes it back: the state,
 *   time and counts are those before it, and going on from there gives
 *   the bits of the run that was never stopped.
 */
#include "check.h"

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "core/rest.h"
#include "sandslide/model_options.h"
#include "sandslide/parallel.h"
#include "sandslide/stepper.h"

#define N 40
#define DX 0.05
#define REPOSE 35.0
#define TOL 1e-9          /* m/s: the steady rule's rate */

enum shape { CONE, OPEN_PILE };

struct run {
	double *h;             /* interior heights at the end */
	double volume0, volume, outflow, slope_deg, time;
	long long steps, evaluations, rest_steps, rest_evaluations;
	int steady;
};

/* A stepper on an N x N grid of DX: a 50 degree cone in the middle of a
 * walled floor, or a 50 degree ramp against the west wall with the east
 * side open (the sand that reaches it leaves). */
static enum ss_closure_kind closure = SS_CLOSURE_COULOMB;

static int make(struct ss_stepper *st, enum shape shape, enum ss_integrator in,
                enum ss_rest_mode rest, enum ss_kernel kernel, int tile_nx, int tile_ny)
{
	struct ss_grid g;
	struct ss_closure c;
	const enum ss_side_kind W = SS_SIDE_WALL, O = SS_SIDE_OPEN;
	const struct ss_boundary b = {{W, shape == OPEN_PILE ? O : W, W, W}, 0.0};
	if (ss_grid_init(&g, N, N, DX, DX, 0.0, 0.0) || ss_closure_init(&c, closure, REPOSE, 1.0,
	                                                                0.1) ||
	    ss_stepper_init(st, &g, &c, &b, 0.9, tile_nx, tile_ny))
		return -1;
	struct ss_model_options m;
	ss_model_options_init(&m);
	st->integrator = in;
	st->rest = rest;
	st->kernel = kernel;
	st->rkl2_max_stages = m.rkl2_max_stages;
	st->rkl2_tol = m.rkl2_tol;
	const double t50 = tan(50.0 * M_PI / 180.0);
	for (int j = 0; j < N; j++)
		for (int i = 0; i < N; i++) {
			const double x = ss_grid_x(&st->grid, i), y = ss_grid_y(&st->grid, j);
			const double r = hypot(x - N * DX / 2, y - N * DX / 2);
			st->height[ss_grid_index(&st->grid, i, j)] =
				shape == CONE ? t50 * fmax(0.6 - r, 0.0) : t50 * fmax(1.8 - x, 0.0) + 0.01;
		}
	return ss_stepper_prepare(st);
}

static double volume(struct ss_stepper *st)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	return d.volume;
}

static double *interior(const struct ss_stepper *st)
{
	double *h = malloc(sizeof(double) * N * N);
	if (!h)
		exit(2);
	for (int j = 0; j < N; j++)
		memcpy(h + (size_t)j * N, st->height + ss_grid_index(&st->grid, 0, j),
		       N * sizeof(double));
	return h;
}

static const struct ss_advance_options steady_options = {.steady_tol = TOL};

/* From the state st is in, until steady (or t = 1e6 s), into r. */
static void finish(struct ss_stepper *st, struct run *r)
{
	r->steady = ss_stepper_advance(st, 1e6, &steady_options) == SS_ADVANCE_STEADY;
	struct ss_diagnostics d;
	ss_stepper_diagnostics(st, &d);
	r->volume = d.volume;
	r->outflow = d.outflow;
	r->slope_deg = d.max_slope_deg;
	r->time = st->time;
	r->steps = st->steps;
	r->evaluations = st->evaluations;
	ss_stepper_rest_counts(st, &r->rest_steps, &r->rest_evaluations);
	r->h = interior(st);
}

static struct run relax(enum shape shape, enum ss_integrator in, enum ss_rest_mode rest,
                        enum ss_kernel kernel, int tile_nx, int tile_ny)
{
	struct run r;
	memset(&r, 0, sizeof r);
	struct ss_stepper st;
	if (make(&st, shape, in, rest, kernel, tile_nx, tile_ny) == 0) {
		r.volume0 = volume(&st);
		finish(&st, &r);
	}
	ss_stepper_release(&st);
	return r;
}

static double max_diff(const struct run *a, const struct run *b)
{
	double m = 0.0;
	for (int k = 0; k < N * N; k++)
		m = fmax(m, fabs(a->h[k] - b->h[k]));
	return m;
}

static double mean_diff(const struct run *a, const struct run *b)
{
	double m = 0.0;
	for (int k = 0; k < N * N; k++)
		m += fabs(a->h[k] - b->h[k]);
	return m / (N * N);
}

static int same_run(const struct run *a, const struct run *b)
{
	return a->h && b->h && !memcmp(a->h, b->h, sizeof(double) * N * N) &&
	       a->steps == b->steps && a->evaluations == b->evaluations && a->time == b->time &&
	       a->outflow == b->outflow;
}

static void release(struct run *r)
{
	free(r->h);
	r->h = NULL;
}

static const char *const shape_name[] = {"cone", "pile by an open side"};

static void comes_to_rest_as_euler_does(void)
{
	const double tc = tan(REPOSE * M_PI / 180.0);
	for (int s = CONE; s <= OPEN_PILE; s++) {
		struct run e = relax(s, SS_INTEGRATOR_EULER, SS_REST_OFF, SS_KERNEL_FAST, 0, 0);
		closure = SS_CLOSURE_BINGHAM;
		struct run law = relax(s, SS_INTEGRATOR_EULER, SS_REST_OFF, SS_KERNEL_FAST, 0, 0);
		closure = SS_CLOSURE_COULOMB;
		const double law_max = e.h && law.h ? max_diff(&e, &law) : 0.0;
		const double law_mean = e.h && law.h ? mean_diff(&e, &law) : 0.0;
		for (int in = SS_INTEGRATOR_EULER; in <= SS_INTEGRATOR_RKL2; in++) {
			struct run r = relax(s, in, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0);
			const char *name = ss_integrator_name(in);
			if (!e.h || !r.h) {
				CHECK(0, "%s: set-up failed", shape_name[s]);
				release(&r);
				continue;
			}
			CHECK(e.steady && r.steady, "%s: not steady by 1e6 s (euler alone %d, %s with "
			      "the approach %d)", shape_name[s], e.steady, name, r.steady);
			CHECK(r.rest_steps > 0 && r.rest_evaluations > 0,
			      "test set-up: %s, %s: the approach to rest did not begin", shape_name[s],
			      name);
			CHECK(atan(tan(r.slope_deg * M_PI / 180.0)) <= atan(tc + 1e-6) * 180.0 / M_PI,
			      "%s, %s: a face at %.9f deg, steeper than the rule allows", shape_name[s],
			      name, r.slope_deg);
			CHECK(fabs(r.volume + r.outflow - r.volume0) <= 1e-12 * r.volume0,
			      "%s, %s: volume %.17g + outflow %.17g is not the initial %.17g m^3",
			      shape_name[s], name, r.volume, r.outflow, r.volume0);
			CHECK(s != OPEN_PILE || r.outflow > 0.0, "test set-up: no sand left the pile");
			const double d = max_diff(&e, &r), dm = mean_diff(&e, &r);
			CHECK(d <= law_max && dm <= law_mean, "%s, %s: ends %.3g m at most and %.3g m "
			      "in mean from forward Euler's end state, farther than the Bingham end "
			      "state (%.3g m, %.3g m)", shape_name[s], name, d, dm, law_max, law_mean);
			CHECK(r.evaluations < e.evaluations, "%s, %s: %lld evaluations with the "
			      "approach, not fewer than forward Euler's %lld", shape_name[s], name,
			      r.evaluations, e.evaluations);
			printf("  %s: euler alone %lld evaluations; %s with the approach %lld (%lld "
			       "in %lld super-steps to rest), %.2g tan(a) dx from euler's at most, "
			       "%.2g in mean (bingham's: %.2g, %.2g)\n", shape_name[s], e.evaluations,
			       name, r.evaluations, r.rest_evaluations, r.rest_steps, d / (tc * DX),
			       dm / (tc * DX), law_max / (tc * DX), law_mean / (tc * DX));
			release(&r);
		}
		release(&e);
		release(&law);
	}
}

/* The same bits for any thread count, tile size and kernel. */
static void the_same_bits_everywhere(void)
{
	ss_parallel_set_threads(1);
	struct run a = relax(OPEN_PILE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0);
	ss_parallel_set_threads(2);
	struct run b = relax(OPEN_PILE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0);
	struct run c = relax(OPEN_PILE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 8, 4);
	struct run d = relax(OPEN_PILE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV,
	                     SS_KERNEL_REFERENCE, 0, 0);
	CHECK(a.rest_steps > 0, "test set-up: the approach to rest did not begin");
	CHECK(same_run(&a, &b), "1 and 2 threads give other bits");
	CHECK(same_run(&b, &c), "tiles of 8 x 4 give other bits than the default tiles");
	CHECK(same_run(&b, &d), "the reference kernel gives other bits than the fast one");
	release(&a);
	release(&b);
	release(&c);
	release(&d);
}

/* One step at a time until the approach has taken n super-steps (fewer
 * if the run ends first): the super-steps it took. */
static long long into_the_approach(struct ss_stepper *st, long long n)
{
	struct ss_advance_options o = steady_options;
	o.max_steps = 1;
	long long rest_steps = 0, rest_evaluations = 0;
	while (rest_steps < n && ss_stepper_advance(st, 1e6, &o) == SS_ADVANCE_STEPS)
		ss_stepper_rest_counts(st, &rest_steps, &rest_evaluations);
	return rest_steps;
}

/* The state after `steps` steps, saved as a snapshot saves it, put in a
 * fresh stepper, taken on to steady: the bits of the run never stopped. */
static void a_restart_in_the_approach_gives_the_same_bits(void)
{
	struct run whole = relax(CONE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0);
	struct ss_stepper st, fresh;
	if (make(&st, CONE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0)) {
		CHECK(0, "set-up failed");
		release(&whole);
		return;
	}
	const long long rest_steps = into_the_approach(&st, 2);
	CHECK(rest_steps == 2, "test set-up: the approach took %lld super-steps, not 2",
	      rest_steps);
	struct ss_restart_state s;
	ss_stepper_restart_state(&st, &s);
	double *h = interior(&st);
	const double t = st.time;
	ss_stepper_release(&st);
	if (make(&fresh, CONE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0) == 0) {
		ss_stepper_restore(&fresh, t, h, NULL, &s);
		struct run r;
		memset(&r, 0, sizeof r);
		finish(&fresh, &r);
		CHECK(same_run(&whole, &r), "a restart after 2 super-steps of the approach gives "
		      "other bits than the run never stopped");
		release(&r);
	}
	ss_stepper_release(&fresh);
	free(h);
	release(&whole);
}

/* A stop asked for after the `after`-th progress report (a stage). */
static volatile sig_atomic_t stop_flag;
static long long reports, stop_after;
static void stop_later(void *context, const struct ss_stepper *st)
{
	(void)context;
	(void)st;
	if (++reports == stop_after)
		stop_flag = 1;
}

static void a_stop_between_stages_takes_the_super_step_back(void)
{
	struct run whole = relax(CONE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0);
	struct ss_stepper st;
	if (make(&st, CONE, SS_INTEGRATOR_EULER, SS_REST_CHEBYSHEV, SS_KERNEL_FAST, 0, 0)) {
		CHECK(0, "set-up failed");
		release(&whole);
		return;
	}
	CHECK(into_the_approach(&st, 1) == 1, "test set-up: the approach did not begin");
	double *before = interior(&st);
	const double t = st.time;
	const long long steps = st.steps, evaluations = st.evaluations;
	/* stopped after the third stage of the next super-step */
	struct ss_advance_options stop = steady_options;
	stop.progress = stop_later;
	stop.stop = &stop_flag;
	reports = 0;
	stop_after = 3;
	stop_flag = 0;
	const enum ss_advance_end end = ss_stepper_advance(&st, 1e6, &stop);
	CHECK(end == SS_ADVANCE_INTERRUPTED, "a stop in a super-step ended with %d", (int)end);
	double *after = interior(&st);
	CHECK(!memcmp(before, after, sizeof(double) * N * N) && st.time == t &&
	      st.steps == steps && st.evaluations == evaluations,
	      "a super-step stopped after its third stage is not taken back: t %.17g (was "
	      "%.17g), steps %lld (%lld), evaluations %lld (%lld)", st.time, t, st.steps, steps,
	      st.evaluations, evaluations);
	struct run r;
	memset(&r, 0, sizeof r);
	finish(&st, &r);
	CHECK(same_run(&whole, &r), "going on after a stop in a super-step gives other bits "
	      "than the run never stopped");
	release(&r);
	free(before);
	free(after);
	ss_stepper_release(&st);
	release(&whole);
}

int main(void)
{
	ss_parallel_set_threads(2);
	RUN(comes_to_rest_as_euler_does);
	RUN(the_same_bits_everywhere);
	RUN(a_restart_in_the_approach_gives_the_same_bits);
	RUN(a_stop_between_stages_takes_the_super_step_back);
	return check_report();
}
