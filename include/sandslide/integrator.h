/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * integrator.h - the time integrators a stepper may use (stepper.h,
 * doc/model.md#forward-euler, #rkl2-super-steps), their names, and the one
 * rule of `auto`.  Apart from stepper.h so that what only names an
 * integrator (the model options, the output's metadata) needs nothing of
 * the stepper.
 */
#ifndef SANDSLIDE_INTEGRATOR_H
#define SANDSLIDE_INTEGRATOR_H

enum ss_integrator {
	SS_INTEGRATOR_EULER,    /* forward Euler: the reference */
	SS_INTEGRATOR_RKL2,     /* RKL2 super-steps (doc/model.md#rkl2-super-steps) */
	SS_INTEGRATOR_AUTO,     /* a choice for the caller to resolve with
	                         * ss_integrator_resolve; never a stepper's */
};

#define SS_INTEGRATOR_NAMES "auto, euler or rkl2"
/* "euler", "rkl2" or "auto". */
const char *ss_integrator_name(enum ss_integrator integrator);
/* 0 and *out for one of SS_INTEGRATOR_NAMES, else -1. */
int ss_integrator_parse(const char *name, enum ss_integrator *out);
/* The integrator a stepper uses: the one asked for, and for auto (the one
 * place this rule is written): euler with a bedrock (RKL2's stages have
 * negative weights, so the per-face limit cannot keep sand above the
 * rock); euler to relax a surface to rest (relax: forward Euler's path
 * until the motion is slow, then the approach to rest's super-steps);
 * else rkl2 (doc/model.md#which-integrator-is-the-default says why). */
enum ss_integrator ss_integrator_resolve(enum ss_integrator asked, int has_bedrock,
                                         int relaxing);

/* The approach to rest of a run that asked to come to rest
 * (doc/model.md#the-approach-to-rest). */
enum ss_rest_mode {
	SS_REST_OFF,            /* the integrator's own steps to the end (a
	                         * stepper set up field by field: the zero) */
	SS_REST_CHEBYSHEV,      /* Chebyshev super-steps once the motion is slow */
};

#define SS_REST_NAMES "chebyshev or off"
/* "chebyshev" or "off". */
const char *ss_rest_mode_name(enum ss_rest_mode rest);
/* 0 and *out for one of SS_REST_NAMES, else -1. */
int ss_rest_mode_parse(const char *name, enum ss_rest_mode *out);

#endif
