/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * rest.h - a stepper's approach to rest (doc/model.md#the-approach-to-rest):
 * once a run that asked to come to rest moves slowly, Chebyshev
 * super-steps (chebyshev.h) take it the rest of the way.
 *
 * Near rest the Coulomb flux is linear in the excess slope, so what is
 * left of the motion decays like a diffusion along each sliding region:
 * forward Euler needs of the order of (L/dx)^2 steps per e-fold for a
 * region L long, RKL2 keeps up to 0.7 of its grid-scale remainder a
 * super-step whatever its length (rkl2.h), and each crawls.  A Chebyshev
 * super-step of s stages damps every rate of [b / s^2, b] by 1/cosh(2) =
 * 0.27 and moves the slower ones as forward Euler over 0.96 s^2 / b (b the
 * largest rate of the stencil, forward Euler's 2 / dt for every slope):
 * about sqrt((L/dx)^2) = L/dx evaluations per e-fold.
 *
 * The rules:
 *
 *   entry     a step whose rate (max |dh/dt|; RKL2: |Y_s - Y_0| / tau)
 *             falls below SS_REST_EXCESS nu Lambda(inf) / min(dx, dy),
 *             the rate of a face steeper than the repose angle by that
 *             excess in slope (SS_REST_EXCESS_RKL2 after RKL2), with
 *             steady asked for, no source on and none to come; the first
 *             super-step has SS_REST_START_STAGES;
 *   steps     super-steps of s stages damping [b / s^2, b]; their length
 *             is the slow modes' tau (chebyshev.h), not accurate in time,
 *             and the steady rule reads their mean rate |Y_s - Y_0| / tau
 *             as it reads RKL2's;
 *   stages    from the rate lambda of the mode that dominated the last
 *             super-step (ss_chebyshev_slow_rate, from its change and its
 *             rate at the start): s = sqrt(b / lambda), lambda at the lower
 *             end, at most twice the last s and rkl2_max_stages.  Never
 *             more: a slow mode past the first zero of p_s changes sign,
 *             and the faces it pushes below the repose angle stop there;
 *   exit      only by steady (or the caller's end); heights changed from
 *             outside start over.
 *
 * Near rest the sliding faces stop changing, and the state the flow comes
 * to rest in depends little on how it gets there: the end states differ
 * from forward Euler's by far less than the closures' end states differ
 * from each other (doc/model.md measures it).  The super-steps carry their
 * increments in the arrays of RKL2's stages (sweep.h: D_j with gamma~ =
 * 0), owned here when the integrator is forward Euler, borrowed from RKL2
 * otherwise.  Not with a bedrock: the stages have negative weights, as
 * RKL2's do.
 */
#ifndef SANDSLIDE_CORE_REST_H
#define SANDSLIDE_CORE_REST_H

/* The excess slope below whose rate the approach to rest begins: at 1e-2
 * the end states of fractal and real DEMs stay within 0.03 tan(a) dx of
 * forward Euler's (doc/model.md#the-approach-to-rest has the table); 1e-3
 * halves that for up to 1.4 times the evaluations, 1e-1 lets the grid
 * scale remainder at the start of the approach leave 0.13.  After RKL2,
 * which keeps up to 0.7 of that remainder a super-step (rkl2.h), 1e-3:
 * the drained room of test_rkl2 ends 0.12 tan(a) dx from forward Euler's
 * end state at 1e-2 and 0.009 at 1e-3, in fewer evaluations. */
#define SS_REST_EXCESS 1e-2
#define SS_REST_EXCESS_RKL2 1e-3
/* The stages of a first super-step. */
#define SS_REST_START_STAGES 8

struct ss_stepper;

struct ss_rest {
	double *y0, *d1, *d2, *m0;  /* the stage arrays (sweep.h) */
	int own;                    /* y0 .. m0 are allocated here */
	double entry_rate;          /* m/s: the rate below which it begins */
	double b;                   /* the largest rate of the stencil, 1/s */
	int stages;                 /* of the next super-step; 0: not begun */
	long long steps;            /* super-steps taken */
	long long evaluations;      /* spent approaching rest */
};

/* For st prepared with its integrator's state (ss_stepper_prepare):
 * SS_ERR_FAIL when an allocation fails. */
int ss_rest_create(struct ss_rest **out, const struct ss_stepper *st);
void ss_rest_destroy(struct ss_rest *r);

/* The entry rate and the stencil's largest rate from st's CFL table and
 * closure, the approach not begun: at create, and again when the
 * materials change (ss_stepper_change_materials). */
void ss_rest_scale(struct ss_rest *r, const struct ss_stepper *st);

/* Whether the approach begins after a step of rate `rate` (m/s) that
 * ended with no source on and none to come; if so it has begun. */
int ss_rest_begins(struct ss_rest *r, double rate);

/* The length of the next super-step, s (its slow modes' tau). */
double ss_rest_length(const struct ss_rest *r);

/* One super-step from the state the stepper measured: the stages, their
 * outflow in the ledger, the evaluations; then the stages of the next.
 * Returns max |Y_s - Y_0| over every rank (m, INFINITY on NaN) and the
 * super-step's length in *tau (s).  Between its stages the caller's
 * progress and stop flag (o, stages.h): *stopped when a stop took the
 * super-step back. */
struct ss_advance_options;
double ss_rest_superstep(struct ss_stepper *st, double *tau,
                         const struct ss_advance_options *o, int *stopped);

#endif
