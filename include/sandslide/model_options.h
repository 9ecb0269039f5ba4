/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * model_options.h - the options of the model and its time stepping that
 * `run` and `relax` share: one table (ss_model_option_table), read as
 * case-file keys by the case parser ([model] closure, [time] cfl, ...) and
 * as command-line options by relax (--closure, --cfl, ...), so that each
 * has one default, one range and one message wherever it is given.  A
 * case must give repose_angle (SS_OPTION_CASE_REQUIRED) and nu or the
 * sliding layer it derives from: a case states its physics, where relax's
 * defaults suit a DEM whose time scale does not matter.
 * doc/model.md gives the equations they enter; doc/case-file.md and
 * `sandslide relax --help` list them.
 */
#ifndef SANDSLIDE_MODEL_OPTIONS_H
#define SANDSLIDE_MODEL_OPTIONS_H

#include "sandslide/closure.h"
#include "sandslide/option.h"
#include "sandslide/integrator.h"

/* What nu may be derived from, for the viscoplastic closures
 * (doc/model.md#nu-from-the-sliding-layer): a case's [model] keys only. */
struct ss_sliding_layer {
	double delta;                     /* thickness, m */
	double density;                   /* kg/m^3 */
	double gravity;                   /* m/s^2 */
	double viscosity;                 /* Pa s (bingham, casson) */
	double consistency;               /* Pa s^gamma (herschel-bulkley) */
};

struct ss_model_options {
	enum ss_closure_kind closure;     /* f_sl of doc/model.md */
	double angle_deg;                 /* repose angle a_cr, degrees in (0, 90) */
	const char *angle_file;           /* a raster of each cell's a_cr, degrees
	                                   * (doc/model.md#materials); NULL:
	                                   * angle_deg everywhere */
	const char *materials_file;       /* a raster of material classes
	                                   * (doc/model.md#materials), or NULL */
	double static_angle_deg;          /* a_s >= a_cr, where sand at rest
	                                   * starts to slide (hysteresis,
	                                   * doc/model.md); NaN: a_cr, none */
	double gamma;                     /* herschel-bulkley exponent, > 0 */
	double nu;                        /* m^2/s, > 0 (a case may derive it
	                                   * from the sliding layer: case.h) */
	double cfl;                       /* fraction of forward Euler's stable
	                                   * step, (0, 1] */
	double steady_tol;                /* m/s: steady when max |dh/dt| is below */
	double steady_slope_tol;          /* and no sand face steeper than
	                                   * tan a_cr by more (stepper.h) */
	double max_time;                  /* s: a steady run stops here anyway;
	                                   * NaN: no such limit */
	enum ss_integrator integrator;    /* auto: ss_integrator_resolve */
	enum ss_rest_mode rest;           /* the approach to rest (integrator.h) */
	int rkl2_max_stages;              /* RKL2: stages per super-step */
	double rkl2_tol;                  /* RKL2: error estimate per super-step,
	                                   * in tan(a_cr) min(dx, dy) */
	double rkl2_pouring_tol;          /*   the same while a source pours */
	struct ss_sliding_layer layer;    /* NaN where not given (a case's nu is
	                                   * given or derived from it: case.h) */
	int nu_from_layer;                /* nu was derived from the layer (a
	                                   * case that gives the layer, not nu) */
};

/* The table: name (relax's --NAME), case key, kind, default, range, help.
 * The rows flagged SS_OPTION_FITTABLE are the keys `sandslide fit` may
 * free (fit.h), each for the closures of its applies_to. */
extern const struct ss_option_table ss_model_option_table;

/* Whether the row o of the model's table is a key of the sliding layer
 * (the keys nu is derived from). */
int ss_model_option_is_layer(const struct ss_option *o);

/* Every option at its default (the table's). */
void ss_model_options_init(struct ss_model_options *m);

/* max_time as a time limit: INFINITY when there is none. */
double ss_model_time_limit(const struct ss_model_options *m);

/* The closure of the model's law, angle and nu (ss_closure_init). */
int ss_model_closure(const struct ss_model_options *m, struct ss_closure *c);

/* nu from the sliding layer and the repose angle for m's closure
 * (bingham, herschel-bulkley, casson; [Paper] eqs. 8 and 12,
 * doc/model.md#nu-from-the-sliding-layer): the layer's keys that closure
 * takes must be set.  The result may be not finite or not positive (the
 * caller says where it came from); NaN for coulomb, which takes nu. */
double ss_model_nu_from_layer(const struct ss_model_options *m);

#endif
