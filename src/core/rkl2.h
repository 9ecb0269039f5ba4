/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * rkl2.h - the coefficients of second-order Runge-Kutta-Legendre
 * super-time-stepping (RKL2; [Meyer2014]: Meyer, Balsara & Aslam,
 * J. Comput. Phys. 257, 2014, section 3; the recurrence PLUTO, Idefix,
 * Athena++ and SUNDIALS LSRKStep use), and a stepper's super-steps with
 * them (the second half).
 *
 * An s-stage super-step of length tau for dY/dt = M(Y), in delta form:
 *
 *   Y_1 = Y_0 + mu~_1 tau M(Y_0)
 *   Y_j = Y_0 + mu_j (Y_{j-1} - Y_0) + nu_j (Y_{j-2} - Y_0)
 *             + tau (mu~_j M(Y_{j-1}) + gamma~_j M(Y_0)),   j = 2 .. s
 *
 * with w_1 = 4 / (s^2 + s - 2), b_0 = b_1 = b_2 = 1/3,
 * b_j = (j^2 + j - 2) / (2 j (j + 1)), a_j = 1 - b_j, mu~_1 = w_1 / 3 and
 *
 *   mu_j = (2j - 1)/j  b_j / b_{j-1},     nu_j = -(j - 1)/j  b_j / b_{j-2},
 *   mu~_j = w_1 mu_j,                      gamma~_j = -a_{j-1} mu~_j.
 *
 * The delta form equals the usual mu Y_{j-1} + nu Y_{j-2} + (1 - mu - nu) Y_0
 * (the weights sum to 1) but a cell whose every M is exactly 0 keeps its
 * bits.  The kernels carry the increments D_j = Y_j - Y_0 themselves
 * (sweep.h), so the recursion rounds at the scale of tau M, not of the
 * heights, and its round-off is not fed back through Y_{j-1} and Y_{j-2}.
 *
 * Stability: the amplification of a mode with forward-Euler number z =
 * tau lambda is R_s(z) = a_s + b_s P_s(1 + w_1 z) (P_s Legendre), which
 * stays in [2 / (s (s + 1)), 1] for tau <= dt_fe (s^2 + s - 2) / 4, dt_fe
 * the largest stable forward-Euler step: positive, so no mode changes sign
 * and a slope relaxing towards the repose angle is not pushed through it
 * at linear order.  The method is second order in tau for any s >= 2.
 */
#ifndef SANDSLIDE_CORE_RKL2_H
#define SANDSLIDE_CORE_RKL2_H

#include <math.h>

struct ss_rkl2_stage {
	double mu;          /* weight of Y_{j-1} - Y_0 (0 for j = 1) */
	double nu;          /* weight of Y_{j-2} - Y_0 (0 for j = 1) */
	double mu_tilde;    /* weight of tau M(Y_{j-1}) */
	double gamma_tilde; /* weight of tau M(Y_0) (0 for j = 1) */
};

/* The coefficients of stage j (1 .. s) of an s-stage super-step, s >= 2. */
struct ss_rkl2_stage ss_rkl2_stage(int s, int j);

/* The longest stable super-step of s stages, in units of the largest stable
 * forward-Euler step: (s^2 + s - 2) / 4. */
double ss_rkl2_stable_ratio(int s);

/* The fewest stages s >= 2 whose super-step may be `ratio` largest stable
 * forward-Euler steps long: the smallest s with (s^2 + s - 2)/4 >= ratio. */
int ss_rkl2_stages_for(double ratio);

/*
 * A stepper's RKL2 (stepper.h's rules, doc/model.md#rkl2-super-steps): the
 * arrays a super-step carries, the super-step and the accuracy rule that
 * sizes the next.  The arrays, as after a super-step in which nothing
 * moved until the first: Y_0 = the heights, D = 0 and M(Y_0) = 0
 * everywhere (the fast sweep relies on it for the tiles it skips).
 */
struct ss_stepper;
struct ss_advance_options;

struct ss_rkl2 {
	double *y0;             /* Y_0, m, with halo (ss_grid_index) */
	double *d1, *d2;        /* D_{j-1}, D_{j-2} = Y - Y_0, m (sweep.h) */
	double *m0;             /* M(Y_0), m/s */
	double dt_all;          /* forward Euler's step for every slope the
	                         * closure has: the unit of super-steps, s */
	double tau_stages;      /* the longest super-step the stage cap
	                         * (rkl2_max_stages) allows, s */
	double tol;             /* the error tolerance, m */
	double tol_pouring;     /*   while a source of the case pours, m */
	double tau_limit;       /* the accuracy rule's longest next super-step,
	                         * s (INFINITY: no limit); restart state */
	int last_stages;        /* s of the last super-step */
};

/* For st's grid, heights and settings (ss_stepper_prepare): SS_ERR_INPUT
 * with a bedrock, SS_ERR_FAIL when an allocation fails; SS_BUG when
 * rkl2_max_stages or rkl2_tol is out of the model options' range (the
 * caller sets them: stepper.h). */
int ss_rkl2_create(struct ss_rkl2 **out, const struct ss_stepper *st);
void ss_rkl2_destroy(struct ss_rkl2 *r);

/* The step sizes and tolerances from st's CFL table and closure, and the
 * accuracy rule's limit as at the start: at create, and again when the
 * materials change (ss_stepper_change_materials). */
void ss_rkl2_scale(struct ss_rkl2 *r, const struct ss_stepper *st);

/* The longest super-step the rules allow now, s. */
static inline double ss_rkl2_longest(const struct ss_rkl2 *r)
{
	return fmin(r->tau_stages, r->tau_limit);
}

/*
 * One super-step of st of tau seconds (at most ss_rkl2_longest), in as few
 * stages as its length needs (at most rkl2_max_stages), from the state the
 * stepper measured; then the accuracy rule sets the next limit.  Counts
 * the evaluations and books the inflow and outflow (ledger.h).  Returns
 * max |Y_s - Y_0| (as max |D_s|), m, INFINITY on NaN.  Between its stages
 * the caller's progress and stop flag (o, stages.h): *stopped when a stop
 * took the super-step back (the state, its evaluations and the ledger as
 * they were before it).
 */
double ss_rkl2_superstep(struct ss_stepper *st, double tau,
                         const struct ss_advance_options *o, int *stopped);

#endif
