/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * rkl2.c - RKL2 coefficients from their closed formulas, and a stepper's
 * super-steps with them: the stages, the error estimate, the accuracy rule
 * (rkl2.h, stepper.h).
 */
#include "core/rkl2.h"

#include <math.h>
#include <string.h>

#include "core/ledger.h"
#include "core/stages.h"
#include "core/sources.h"
#include "core/sweep.h"
#include "core/sweeper.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"
#include "sandslide/stepper.h"

/* b_j of the recurrence: 1/3 for j <= 2, else (j^2 + j - 2) / (2 j (j + 1)) */
static double b_of(int j)
{
	if (j <= 2)
		return 1.0 / 3.0;
	const double jj = j;
	return (jj * jj + jj - 2.0) / (2.0 * jj * (jj + 1.0));
}

struct ss_rkl2_stage ss_rkl2_stage(int s, int j)
{
	const double ss = s;
	const double w1 = 4.0 / (ss * ss + ss - 2.0);
	struct ss_rkl2_stage c = {0.0, 0.0, w1 / 3.0, 0.0};
	if (j < 2)
		return c;
	const double jj = j;
	c.mu = (2.0 * jj - 1.0) / jj * b_of(j) / b_of(j - 1);
	c.nu = -(jj - 1.0) / jj * b_of(j) / b_of(j - 2);
	c.mu_tilde = w1 * c.mu;
	c.gamma_tilde = -(1.0 - b_of(j - 1)) * c.mu_tilde;
	return c;
}

double ss_rkl2_stable_ratio(int s)
{
	const double ss = s;
	return (ss * ss + ss - 2.0) / 4.0;
}

int ss_rkl2_stages_for(double ratio)
{
	if (!(ratio > 1.0))
		return 2;
	/* the positive root of s^2 + s - 2 - 4 ratio = 0, rounded up; then
	 * checked both ways against the ratio itself, since the root is
	 * rounded */
	int s = (int)ceil(0.5 * (-1.0 + sqrt(9.0 + 16.0 * ratio)));
	if (s < 2)
		s = 2;
	while (s > 2 && ss_rkl2_stable_ratio(s - 1) >= ratio)
		s--;
	while (ss_rkl2_stable_ratio(s) < ratio)
		s++;
	return s;
}

/* The first super-steps are at most START_STAGES stages long, and the
 * limit grows from there by at most 2x a super-step (control): a run
 * starts with no measure of how fast its state changes. */
#define START_STAGES 4

int ss_rkl2_create(struct ss_rkl2 **out, const struct ss_stepper *st)
{
	*out = NULL;
	if (st->bedrock)
		return ss_error_input("the rkl2 integrator cannot be used with a bedrock: its "
		                      "stages cannot keep the sand above the rock; use euler");
	if (st->rkl2_max_stages < 2 || !(st->rkl2_tol > 0.0))
		SS_BUG("rkl2_max_stages %d, rkl2_tol %g: set them before ss_stepper_prepare, "
		       "in the model options' range (model_options.h)", st->rkl2_max_stages,
		       st->rkl2_tol);
	struct ss_rkl2 *r = ss_alloc(1, sizeof *r, "RKL2 state");
	if (!r)
		return SS_ERR_FAIL;
	memset(r, 0, sizeof *r);
	*out = r;
	static const char *const names[4] = {"RKL2 Y_0", "RKL2 D_{j-1}", "RKL2 D_{j-2}",
	                                     "RKL2 M(Y_0)"};
	if (ss_stages_arrays_create(st, names, &r->y0, &r->d1, &r->d2, &r->m0))
		return SS_ERR_FAIL;
	ss_rkl2_scale(r, st);
	return SS_OK;
}

void ss_rkl2_scale(struct ss_rkl2 *r, const struct ss_stepper *st)
{
	const struct ss_grid *g = &st->grid;
	/* forward Euler's step for every slope the closure has (stepper.h) */
	const double inv_d2 = 1.0 / (g->dx * g->dx) + 1.0 / (g->dy * g->dy);
	r->dt_all = st->cfl / (2.0 * st->closure.nu *
	                       ss_cfl_bound_lookup(&st->sweeper->cfl_bound, HUGE_VAL) * inv_d2);
	r->tau_stages = r->dt_all * ss_rkl2_stable_ratio(st->rkl2_max_stages);
	r->tol = st->rkl2_tol * st->closure.tan_cr * fmin(g->dx, g->dy);
	r->tol_pouring = st->rkl2_pouring_tol > 0.0
		? st->rkl2_pouring_tol * st->closure.tan_cr * fmin(g->dx, g->dy) : r->tol;
	r->tau_limit = r->dt_all * ss_rkl2_stable_ratio(START_STAGES);
}

void ss_rkl2_destroy(struct ss_rkl2 *r)
{
	if (!r)
		return;
	ss_free(r->m0);
	ss_free(r->d2);
	ss_free(r->d1);
	ss_free(r->y0);
	ss_free(r);
}

/*
 * The accuracy rule (stepper.h) after a super-step of tau with error
 * estimate est: the limit becomes tau 0.9 sqrt(tol / est), at most twice
 * the limit it had; a limit above the stage cap is none.  tol is the
 * pouring one when a source of the case poured in the super-step
 * (doc/model.md#accuracy-rule).
 */
static void control(struct ss_rkl2 *r, double tau, double estimate, int pouring)
{
	const double tol = pouring ? r->tol_pouring : r->tol;
	const double factor = estimate > 0.0 ? fmin(0.9 * sqrt(tol / estimate), 2.0) : 2.0;
	const double limit = isfinite(r->tau_limit) ? r->tau_limit : r->tau_stages;
	r->tau_limit = fmin(tau * factor, 2.0 * limit);
	if (r->tau_limit >= r->tau_stages)
		r->tau_limit = INFINITY;
}

/*
 * The stages start from the state ss_sweeper_measure measured.  The
 * outflow of the stages is combined with the stage weights, O_j = mu
 * O_{j-1} + nu O_{j-2} + tau (mu~ out(M(Y_{j-1})) + gamma~ out(M(Y_0))), as
 * the heights are, so that it is the outflow of the super-step's change
 * (ledger.h; on several ranks perhaps later, from the batch); the source is
 * constant over it, so the inflow is tau times its rate.  The ranks agree
 * once a super-step, after the estimate (the stages need nothing summed
 * over them but the outflow).
 */
double ss_rkl2_superstep(struct ss_stepper *st, double tau,
                         const struct ss_advance_options *o, int *stopped)
{
	struct ss_rkl2 *r = st->rkl2;
	int s = ss_rkl2_stages_for(tau / r->dt_all);
	s = s < st->rkl2_max_stages ? s : st->rkl2_max_stages;
	double change = 0.0, awake = 0.0, estimate = 0.0;
	const long long evaluations = st->evaluations;
	*stopped = 0;
	for (int j = 1; j <= s; j++) {
		if (j > 1 && ss_stages_stop(st, o)) {   /* taken back (stages.h) */
			ss_stages_take_back(st, r->y0);
			st->evaluations = evaluations;
			*stopped = 1;
			return 0.0;
		}
		const struct ss_rkl2_stage k = ss_rkl2_stage(s, j);
		const struct ss_sweep_stage stage = {
			.first = j == 1, .mu = k.mu, .nu = k.nu,
			.tau_mu = tau * k.mu_tilde, .tau_gamma = tau * k.gamma_tilde,
			.y0 = r->y0, .d1 = r->d1, .d2 = r->d2, .m0 = r->m0,
		};
		change = ss_sweeper_stage(st, &stage, j == s, j == 1, &awake);
		st->evaluations++;
		const struct ss_ledger_entry e = {
			.mu = stage.mu, .nu = stage.nu, .tau_mu = stage.tau_mu,
			.tau_gamma = stage.tau_gamma,
			.kind = SS_LEDGER_STAGE | (j == 1 ? SS_LEDGER_FIRST : 0) |
			        (j == s ? SS_LEDGER_LAST : 0),
		};
		ss_ledger_add_outflow(st->ledger, &st->grid, &e);
	}
	ss_ledger_add_inflow(st->ledger, tau * st->sources->volume_rate);
	/* the error estimate: one more evaluation, at Y_s, that writes nothing;
	 * the next super-step's first stage evaluates there again, but the
	 * estimate is then known before the next super-step is sized, and a
	 * restart from Y_s needs nothing a snapshot does not hold */
	const struct ss_sweep_stage est = {
		.estimate_only = 1, .estimate_tau = tau, .estimate = &estimate,
		.y0 = r->y0, .d1 = r->d1, .d2 = r->d2, .m0 = r->m0,
	};
	ss_sweeper_stage(st, &est, 0, 0, &awake);
	st->evaluations++;
	/* the tile counts are whole numbers: their sum has the same bits for
	 * any rank count */
	double max[2] = {change, estimate};
	ss_comm_reduce(max, 2, &awake, 1);
	ss_sweeper_count_superstep(st->sweeper, awake, s + 1);
	/* a case's source, not the BMI's rate field (doc/model.md) */
	control(r, tau, max[1], st->sources->on != 0);
	r->last_stages = s;
	return isfinite(max[0]) ? max[0] : INFINITY;
}
