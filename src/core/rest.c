/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * rest.c - a stepper's approach to rest: Chebyshev super-steps once the
 * motion is slow (rest.h).
 */
#include "core/rest.h"

#include <math.h>
#include <string.h>

#include "core/chebyshev.h"
#include "core/ledger.h"
#include "core/rkl2.h"
#include "core/stages.h"
#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/stepper.h"

int ss_rest_create(struct ss_rest **out, const struct ss_stepper *st)
{
	*out = NULL;
	struct ss_rest *r = ss_alloc(1, sizeof *r, "the approach to rest");
	if (!r)
		return SS_ERR_FAIL;
	memset(r, 0, sizeof *r);
	*out = r;
	ss_rest_scale(r, st);
	if (st->rkl2) {   /* the same arrays: never in use at once */
		r->y0 = st->rkl2->y0;
		r->d1 = st->rkl2->d1;
		r->d2 = st->rkl2->d2;
		r->m0 = st->rkl2->m0;
		return SS_OK;
	}
	r->own = 1;
	static const char *const names[4] = {
		"the approach to rest: Y_0", "the approach to rest: D_{j-1}",
		"the approach to rest: D_{j-2}", "the approach to rest: M(Y_0)",
	};
	return ss_stages_arrays_create(st, names, &r->y0, &r->d1, &r->d2, &r->m0);
}

void ss_rest_scale(struct ss_rest *r, const struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	const double lambda = st->closure.nu * ss_cfl_bound_lookup(&st->sweeper->cfl_bound,
	                                                           HUGE_VAL);
	/* the rate of a face steeper than the repose angle by the excess:
	 * f_sl' <= Lambda, so its flux is at most nu Lambda excess */
	const double excess = st->rkl2 ? SS_REST_EXCESS_RKL2 : SS_REST_EXCESS;
	r->entry_rate = excess * lambda / fmin(g->dx, g->dy);
	/* forward Euler is stable for dt <= 2 / b: at cfl = 1 its step for
	 * every slope, 1 / (2 nu Lambda (1/dx^2 + 1/dy^2)); cfl < 1 keeps a
	 * margin as it does for forward Euler */
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	r->b = 4.0 * lambda * inv_d2 / st->cfl;
	r->stages = 0;
}

void ss_rest_destroy(struct ss_rest *r)
{
	if (!r)
		return;
	if (r->own) {
		ss_free(r->m0);
		ss_free(r->d2);
		ss_free(r->d1);
		ss_free(r->y0);
	}
	ss_free(r);
}

int ss_rest_begins(struct ss_rest *r, double rate)
{
	if (r->stages == 0 && rate < r->entry_rate)
		r->stages = SS_REST_START_STAGES;
	return r->stages > 0;
}

/* The lower end a of the rates a super-step of s stages damps: b / s^2,
 * where x = 2 s sqrt(a / b) = 2 damps them by 1 / cosh(2) = 0.27 and moves
 * the slower ones over 0.96 s^2 / b (chebyshev.h; a larger x damps more
 * and moves less, and did not come closer to forward Euler's end states). */
static double lower_end(const struct ss_rest *r, int s)
{
	return r->b / ((double)s * s);
}

double ss_rest_length(const struct ss_rest *r)
{
	struct ss_chebyshev ch;
	ss_chebyshev_init(&ch, r->stages, lower_end(r, r->stages), r->b);
	return ch.tau;
}

/*
 * The stages start from the state ss_sweeper_measure measured.  Their
 * outflow is combined with the stage weights as the heights are, O_j = mu
 * O_{j-1} + nu O_{j-2} + tau_mu out(M(Y_{j-1})), so that it is the outflow
 * of the super-step's change (ledger.h).  No source is on.  The ranks
 * agree once a super-step, after the last stage.
 */
double ss_rest_superstep(struct ss_stepper *st, double *tau,
                         const struct ss_advance_options *o, int *stopped)
{
	struct ss_rest *r = st->rest_state;
	const int s = r->stages;
	struct ss_chebyshev ch;
	ss_chebyshev_init(&ch, s, lower_end(r, s), r->b);
	double change = 0.0, start_rate = 0.0, awake = 0.0;
	const long long evaluations = st->evaluations, rest_evaluations = r->evaluations;
	*stopped = 0;
	*tau = 0.0;
	for (int j = 1; j <= s; j++) {
		if (j > 1 && ss_stages_stop(st, o)) {   /* taken back (stages.h) */
			ss_stages_take_back(st, r->y0);
			st->evaluations = evaluations;
			r->evaluations = rest_evaluations;
			*stopped = 1;
			return 0.0;
		}
		const struct ss_chebyshev_stage k = ss_chebyshev_next(&ch, j);
		const struct ss_sweep_stage stage = {
			.first = j == 1, .mu = k.mu, .nu = k.nu, .tau_mu = k.tau_mu, .tau_gamma = 0.0,
			.y0 = r->y0, .d1 = r->d1, .d2 = r->d2, .m0 = r->m0,
		};
		change = ss_sweeper_stage(st, &stage, j == s, j == 1, &awake);
		if (j == 1)   /* D_1 = M(Y_0) / theta */
			start_rate = change / k.tau_mu;
		st->evaluations++;
		r->evaluations++;
		const struct ss_ledger_entry e = {
			.mu = stage.mu, .nu = stage.nu, .tau_mu = stage.tau_mu, .tau_gamma = 0.0,
			.kind = SS_LEDGER_STAGE | (j == 1 ? SS_LEDGER_FIRST : 0) |
			        (j == s ? SS_LEDGER_LAST : 0),
		};
		ss_ledger_add_outflow(st->ledger, &st->grid, &e);
	}
	/* the tile counts are whole numbers: their sum has the same bits for
	 * any rank count */
	double largest[2] = {change, start_rate};   /* max |Y_s - Y_0|, max |M(Y_0)| */
	ss_comm_reduce(largest, 2, &awake, 1);
	change = largest[0];
	ss_sweeper_count_superstep(st->sweeper, awake, s);
	r->steps++;
	*tau = ch.tau;
	if (!isfinite(change))
		return INFINITY;
	/* the next super-step's stages put the rate of the mode that
	 * dominates the change at their lower end a = b / s^2, where it is
	 * damped by 1/cosh 2 and keeps its sign: past the first zero of p_s,
	 * at 2.2 a, it would change sign, and faces pushed below the repose
	 * angle stop there for good (the whole slope of a pile draining
	 * through an open side came to rest 0.4 % below it when the stages
	 * were doubled blindly).  At most twice the stages at a time: the
	 * rate is estimated from the largest change, of one region. */
	const double slow = largest[1] > 0.0 ? ss_chebyshev_slow_rate(&ch, change / largest[1])
	                                      : 0.0;
	double next = slow > 0.0 ? ceil(sqrt(r->b / slow)) : 2.0 * s;
	next = fmin(fmin(next, 2.0 * s), (double)st->rkl2_max_stages);
	r->stages = next > 2.0 ? (int)next : 2;
	return change;
}
