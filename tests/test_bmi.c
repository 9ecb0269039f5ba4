/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_bmi.c - the BMI 2.0 C interface (sandslide/bmi.h), called as the
 * bmi-tester project's stages call a component: bootstrap, info, time,
 * vars, grid, value; then the bits: k updates give the heights `sandslide
 * run` writes at k * output_every (read back from its HDF5 file), and
 * update_until(T) those of a stepper of the same case advanced to T.
 */
#include "check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/sources.h"
#include "model/setup.h"
#include "sandslide/bmi.h"
#include "sandslide/case.h"
#include "sandslide/relax.h"
#include "sandslide/error.h"
#include "sandslide/run.h"
#include "sandslide/snapshot.h"
#include "sandslide/stepper.h"

#define NX 14
#define NY 10
#define ELEV "land_surface__elevation"
#define VOLUME "sand__volume"
#define INFLOW "sand__time_integral_of_source_volume_flux"
#define OUTFLOW "sand__time_integral_of_outflow_volume_flux"
#define SLOPE "sand_surface__max_of_slope_angle"
#define EXTERNAL "sand__external_volume_change"
#define RATE "land_surface__net_deposition_rate"
#define BEDROCK "bedrock_surface__elevation"
#define ANGLE "sand__angle_of_repose"
#define NOUT 7   /* without a bedrock or hysteresis */
static const char *const outputs[NOUT] = {ELEV, ANGLE, VOLUME, INFLOW, OUTFLOW, EXTERNAL, SLOPE};

/* A cone slumping towards an open east side: heights change every step. */
static const char *case_text =
	"[grid]\nnx = 14\nny = 10\ndx = 0.1\ndy = 0.12\norigin = 2 -1\n\n"
	"[model]\nclosure = coulomb\nrepose_angle = 35\nnu = 0.1\n\n"
	"[time]\nend = 1\noutput_every = 0.25\n\n"
	"[boundary]\nwest = wall\neast = open\nsouth = wall\nnorth = wall\n\n"
	"[initial]\ntype = cone\ncenter = 2.7 -0.4\nradius = 0.5\nangle = 50\nheight = 0.1\n";

static struct Bmi *started(void)
{
	struct Bmi *m = ss_bmi_create();
	if (m && m->initialize(m, check_file("cone.ini")) != BMI_SUCCESS) {
		ss_bmi_destroy(m);
		return NULL;
	}
	return m;
}

/* A model initialized from the test file `name`, or NULL after a failed
 * check that gives the library's message. */
static struct Bmi *initialized(const char *name)
{
	struct Bmi *m = ss_bmi_create();
	CHECK(m && m->initialize(m, check_file(name)) == BMI_SUCCESS, "%s: %s", name,
	      ss_error_last_message());
	if (m && !m->data) {
		ss_bmi_destroy(m);
		m = NULL;
	}
	return m;
}

/* The heights of a stepper, [y][x], south row first. */
static void stepper_heights(const struct ss_stepper *st, double *out)
{
	for (int j = 0; j < st->grid.ny; j++)
		for (int i = 0; i < st->grid.nx; i++)
			out[j * st->grid.nx + i] = st->height[ss_grid_index(&st->grid, i, j)];
}

/* A scalar output now (NAN if the call fails). */
static double scalar(struct Bmi *m, const char *name)
{
	double x = NAN;
	return m->get_value(m, name, &x) == BMI_SUCCESS ? x : NAN;
}

static double external(struct Bmi *m)
{
	return scalar(m, EXTERNAL);
}

static int same_bits(const double *a, const double *b, int n)
{
	return memcmp(a, b, (size_t)n * sizeof *a) == 0;
}

static void bootstrap(void)
{
	struct Bmi m;
	CHECK(ss_bmi_register(&m) == &m && m.data == NULL, "register");
	double t;
	CHECK(m.get_current_time(&m, &t) == BMI_FAILURE, "a call before initialize");
	CHECK(m.update(&m) == BMI_FAILURE, "update before initialize");
	CHECK(m.finalize(&m) == BMI_FAILURE, "finalize before initialize");
	CHECK(m.initialize(&m, check_file("missing.ini")) == BMI_FAILURE, "a missing case");
	CHECK(m.data == NULL, "nothing kept of a failed initialize");
	CHECK(m.initialize(&m, check_file("cone.ini")) == BMI_SUCCESS, "%s",
	      ss_error_last_message());
	CHECK(m.initialize(&m, check_file("cone.ini")) == BMI_FAILURE, "a second initialize");
	CHECK(m.finalize(&m) == BMI_SUCCESS, "finalize");
	CHECK(m.finalize(&m) == BMI_FAILURE && m.data == NULL, "a second finalize");
	CHECK(m.initialize(&m, check_file("cone.ini")) == BMI_SUCCESS, "initialize again");
	CHECK(m.finalize(&m) == BMI_SUCCESS, "finalize again");
	ss_bmi_destroy(NULL);
	struct Bmi *h = started();
	CHECK(h != NULL, "create and initialize");
	ss_bmi_destroy(h);   /* finalizes: no leak under the sanitizers */
}

static void info(void)
{
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	char name[BMI_MAX_COMPONENT_NAME], var[NOUT][BMI_MAX_VAR_NAME];
	char *names[NOUT];
	for (int v = 0; v < NOUT; v++)
		names[v] = var[v];
	int in = 0, out = 0;
	CHECK(m->get_component_name(m, name) == BMI_SUCCESS && !strcmp(name, "sandslide"), "name");
	CHECK(m->get_input_item_count(m, &in) == BMI_SUCCESS && in == 3, "%d inputs", in);
	CHECK(m->get_output_item_count(m, &out) == BMI_SUCCESS && out == NOUT, "%d outputs", out);
	CHECK(m->get_input_var_names(m, names) == BMI_SUCCESS && !strcmp(var[0], ELEV) &&
	      !strcmp(var[1], RATE) && !strcmp(var[2], ANGLE), "%s, %s, %s", var[0], var[1],
	      var[2]);
	var[0][0] = 0;
	CHECK(m->get_output_var_names(m, names) == BMI_SUCCESS, "output names");
	for (int v = 0; v < NOUT; v++)
		CHECK(!strcmp(var[v], outputs[v]), "output %d: %s", v, var[v]);
	ss_bmi_destroy(m);
}

static void time_stage(void)
{
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	double start = -1, now = -1, end = -1, step = -1;
	char units[BMI_MAX_UNITS_NAME];
	CHECK(m->get_start_time(m, &start) == BMI_SUCCESS && start == 0.0, "start %g", start);
	CHECK(m->get_current_time(m, &now) == BMI_SUCCESS && now == 0.0, "now %g", now);
	CHECK(m->get_end_time(m, &end) == BMI_SUCCESS && end == 1.0, "end %g", end);
	CHECK(m->get_time_step(m, &step) == BMI_SUCCESS && step == 0.25, "step %g", step);
	CHECK(m->get_time_units(m, units) == BMI_SUCCESS && !strcmp(units, "s"), "%s", units);
	CHECK(m->update(m) == BMI_SUCCESS, "update");
	CHECK(m->get_current_time(m, &now) == BMI_SUCCESS && now == 0.25, "now %g", now);
	CHECK(m->update_until(m, 0.1) == BMI_FAILURE, "update_until into the past");
	CHECK(m->get_current_time(m, &now) == BMI_SUCCESS && now == 0.25, "unchanged %g", now);
	CHECK(m->update_until(m, 0.3) == BMI_SUCCESS, "update_until");
	CHECK(m->get_current_time(m, &now) == BMI_SUCCESS && now == 0.3, "now %g", now);
	CHECK(m->update(m) == BMI_SUCCESS, "update off the lattice");
	CHECK(m->get_current_time(m, &now) == BMI_SUCCESS && now == 0.3 + 0.25, "now %g", now);
	CHECK(m->update_until(m, NAN) == BMI_FAILURE, "update_until NaN");
	ss_bmi_destroy(m);
}

static void vars(void)
{
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	char s[BMI_MAX_TYPE_NAME];
	int v = -1;
	CHECK(m->get_var_type(m, ELEV, s) == BMI_SUCCESS && !strcmp(s, "double"), "%s", s);
	CHECK(m->get_var_units(m, ELEV, s) == BMI_SUCCESS && !strcmp(s, "m"), "%s", s);
	CHECK(m->get_var_location(m, ELEV, s) == BMI_SUCCESS && !strcmp(s, "node"), "%s", s);
	CHECK(m->get_var_itemsize(m, ELEV, &v) == BMI_SUCCESS && v == 8, "itemsize %d", v);
	CHECK(m->get_var_nbytes(m, ELEV, &v) == BMI_SUCCESS && v == NX * NY * 8, "nbytes %d", v);
	CHECK(m->get_var_grid(m, ELEV, &v) == BMI_SUCCESS && v == 0, "grid %d", v);
	/* the read-only diagnostics: scalars on grid 1 */
	const char *units[NOUT] = {"m", "deg", "m3", "m3", "m3", "m3", "deg"};
	for (int k = 2; k < NOUT; k++) {
		CHECK(m->get_var_grid(m, outputs[k], &v) == BMI_SUCCESS && v == 1, "%s: grid %d",
		      outputs[k], v);
		CHECK(m->get_var_units(m, outputs[k], s) == BMI_SUCCESS && !strcmp(s, units[k]),
		      "%s: %s", outputs[k], s);
		CHECK(m->get_var_type(m, outputs[k], s) == BMI_SUCCESS && !strcmp(s, "double"),
		      "%s: %s", outputs[k], s);
		CHECK(m->get_var_nbytes(m, outputs[k], &v) == BMI_SUCCESS && v == 8, "%s: %d",
		      outputs[k], v);
		CHECK(m->get_var_itemsize(m, outputs[k], &v) == BMI_SUCCESS && v == 8, "%s: %d",
		      outputs[k], v);
		CHECK(m->get_var_location(m, outputs[k], s) == BMI_SUCCESS && !strcmp(s, "node"),
		      "%s: %s", outputs[k], s);
	}
	v = 7;
	CHECK(m->get_var_type(m, "sea_water__depth", s) == BMI_FAILURE, "an unknown name");
	CHECK(m->get_var_grid(m, "sea_water__depth", &v) == BMI_FAILURE && v == 7, "untouched");
	CHECK(m->get_var_nbytes(m, NULL, &v) == BMI_FAILURE, "no name");
	CHECK(m->get_var_units(m, RATE, s) == BMI_SUCCESS && !strcmp(s, "m s-1"), "%s", s);
	CHECK(m->get_var_grid(m, RATE, &v) == BMI_SUCCESS && v == 0, "rate grid %d", v);
	CHECK(m->get_var_grid(m, BEDROCK, &v) == BMI_FAILURE, "no bedrock in this case");
	ss_bmi_destroy(m);
}

static void grid(void)
{
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	int rank = 0, size = 0, shape[2] = {0, 0};
	double spacing[2] = {0, 0}, origin[2] = {0, 0}, x[NX];
	char type[BMI_MAX_TYPE_NAME];
	CHECK(m->get_grid_type(m, 0, type) == BMI_SUCCESS && !strcmp(type, "uniform_rectilinear"),
	      "%s", type);
	CHECK(m->get_grid_rank(m, 0, &rank) == BMI_SUCCESS && rank == 2, "rank %d", rank);
	CHECK(m->get_grid_size(m, 0, &size) == BMI_SUCCESS && size == NX * NY, "size %d", size);
	CHECK(m->get_grid_shape(m, 0, shape) == BMI_SUCCESS && shape[0] == NY && shape[1] == NX,
	      "shape %d %d", shape[0], shape[1]);
	CHECK(m->get_grid_spacing(m, 0, spacing) == BMI_SUCCESS && spacing[0] == 0.12 &&
	      spacing[1] == 0.1, "spacing %g %g", spacing[0], spacing[1]);
	/* the centre of the south-west cell, as the HDF5 output's y[0], x[0] */
	CHECK(m->get_grid_origin(m, 0, origin) == BMI_SUCCESS && origin[0] == -1 + 0.5 * 0.12 &&
	      origin[1] == 2 + 0.5 * 0.1, "origin %.17g %.17g", origin[0], origin[1]);
	CHECK(m->get_grid_type(m, 1, type) == BMI_SUCCESS && !strcmp(type, "scalar"), "grid 1: %s",
	      type);
	CHECK(m->get_grid_rank(m, 1, &rank) == BMI_SUCCESS && rank == 0, "grid 1: rank %d", rank);
	CHECK(m->get_grid_size(m, 1, &size) == BMI_SUCCESS && size == 1, "grid 1: size %d", size);
	CHECK(m->get_grid_shape(m, 1, shape) == BMI_FAILURE, "a scalar has no shape");
	CHECK(m->get_grid_rank(m, 2, &rank) == BMI_FAILURE && rank == 0, "grid 2");
	CHECK(m->get_grid_size(m, -1, &size) == BMI_FAILURE, "grid -1");
	CHECK(m->get_grid_x(m, 0, x) == BMI_FAILURE, "get_grid_x: not rectilinear");
	CHECK(m->get_grid_node_count(m, 0, &size) == BMI_FAILURE, "not unstructured");
	ss_bmi_destroy(m);
}

/* get_value is the stepper's heights: after k updates, what `sandslide
 * run` wrote at k * output_every, bit for bit. */
static void value_is_what_run_writes(void)
{
	struct ss_run_options *o = ss_option_object_create(&ss_run_option_table);
	CHECK(o != NULL, "run options");
	if (!o)
		return;
	char json[8192];
	CHECK(ss_option_object_set(o, "case", check_file("cone.ini")) == SS_OK &&
	      ss_option_object_set(o, "output", check_file("cone.h5")) == SS_OK &&
	      ss_option_object_set(o, "force", "1") == SS_OK, "options");
	CHECK(ss_run_case_json(o, json, sizeof json) == SS_OK, "%s", ss_error_last_message());
	ss_option_object_destroy(o);
	struct ss_height_series hs;
	CHECK(ss_snapshot_read_height_series(check_file("cone.h5"), &hs) == SS_OK, "%s",
	      ss_error_last_message());
	CHECK(hs.count == 5 && hs.nx == NX && hs.ny == NY, "%lld snapshots", hs.count);
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	double origin[2];
	if (m && m->get_grid_origin(m, 0, origin) == BMI_SUCCESS)
		CHECK(fabs(origin[0] - (hs.origin_y + 0.06)) < 1e-12 &&
		      fabs(origin[1] - (hs.origin_x + 0.05)) < 1e-12,
		      "origin %g %g, the file's first centre %g %g", origin[0], origin[1],
		      hs.origin_y + 0.06, hs.origin_x + 0.05);
	double h[NX * NY], volume0 = 0.0;
	for (long long k = 0; m && k < hs.count; k++) {
		if (k > 0)
			CHECK(m->update(m) == BMI_SUCCESS, "update %lld", k);
		double t = -1;
		m->get_current_time(m, &t);
		CHECK(t == hs.time[k], "time %g, the file's %g", t, hs.time[k]);
		CHECK(m->get_value(m, ELEV, h) == BMI_SUCCESS, "get_value");
		CHECK(same_bits(h, hs.height + k * NX * NY, NX * NY),
		      "the heights at %g s are not run's", t);
		/* the diagnostics between updates change no bits of what follows */
		double vol = -1, in = -1, out = -1, slope = -1, sum = 0.0;
		CHECK(m->get_value(m, VOLUME, &vol) == BMI_SUCCESS &&
		      m->get_value(m, INFLOW, &in) == BMI_SUCCESS &&
		      m->get_value(m, OUTFLOW, &out) == BMI_SUCCESS &&
		      m->get_value(m, SLOPE, &slope) == BMI_SUCCESS, "diagnostics");
		for (int c = 0; c < NX * NY; c++)
			sum += h[c] * 0.1 * 0.12;
		CHECK_REL(vol, sum, 1e-12, "volume at %g s", t);
		if (k == 0)
			volume0 = vol;
		CHECK(in == 0.0 && out >= 0.0 && (k == 0 || slope < 50.0) && slope > 0.0,
		      "inflow %g, outflow %g, slope %g deg", in, out, slope);
		CHECK_NEAR(vol + out, volume0, 1e-12, "the balance at %g s: %g + %g", t, vol, out);
		if (k == hs.count - 1)
			CHECK(out > 0.0, "sand left through the open side");
	}
	CHECK(hs.count == 5 && !same_bits(hs.height, hs.height + 4 * NX * NY, NX * NY),
	      "the cone moved (the comparison means something)");
	ss_height_series_release(&hs);
	ss_bmi_destroy(m);
	remove(check_file("cone.h5"));
	remove(check_file("cone.xmf"));
	remove(check_file("cone.h5.aux.xml"));
}

/* update_until(T) in one call: the bits of the library's stepper of the
 * same case advanced to T. */
static void update_until_is_the_library(void)
{
	const double T = 0.7;
	struct ss_case c;
	struct ss_stepper st;
	int err = ss_case_load(&c, check_file("cone.ini"), NULL, 0);
	if (!err)
		err = ss_setup_stepper(&c, 0, 0, SS_KERNEL_FAST, &st);
	ss_case_release(&c);
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (err)
		return;
	const struct ss_advance_options adv = {0};
	CHECK(ss_stepper_advance(&st, T, &adv) == SS_ADVANCE_REACHED, "advance");
	double want[NX * NY], got[NX * NY];
	stepper_heights(&st, want);
	ss_stepper_release(&st);
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	double vol;
	CHECK(m->get_value(m, VOLUME, &vol) == BMI_SUCCESS, "a diagnostic first");
	CHECK(m->update_until(m, T) == BMI_SUCCESS, "update_until");
	CHECK(m->get_value(m, ELEV, got) == BMI_SUCCESS && same_bits(got, want, NX * NY),
	      "update_until(%g) is not the stepper's bits", T);
	int inds[3] = {0, NX + 3, NX * NY - 1};
	double some[3];
	CHECK(m->get_value_at_indices(m, ELEV, some, inds, 3) == BMI_SUCCESS &&
	      some[0] == want[0] && some[1] == want[NX + 3] && some[2] == want[NX * NY - 1],
	      "get_value_at_indices");
	ss_bmi_destroy(m);
}

/* set_value then get_value round-trips on flow cells; bad names, indices
 * and values change nothing; the volume set is counted. */
static void set_value_round_trips(void)
{
	struct Bmi *m = started();
	CHECK(m != NULL, "initialize");
	if (!m)
		return;
	double h[NX * NY], back[NX * NY], before[NX * NY];
	CHECK(m->get_value(m, ELEV, before) == BMI_SUCCESS, "get_value");
	for (int c = 0; c < NX * NY; c++)
		h[c] = 0.3 + 0.001 * c;
	CHECK(m->set_value(m, ELEV, h) == BMI_SUCCESS, "%s", ss_error_last_message());
	CHECK(m->get_value(m, ELEV, back) == BMI_SUCCESS && same_bits(back, h, NX * NY),
	      "set then get");
	double added = 0.0;
	for (int c = 0; c < NX * NY; c++)
		added += (h[c] - before[c]) * 0.1 * 0.12;
	CHECK_REL(external(m), added, 1e-12, "the volume set");
	double bad[NX * NY];
	memcpy(bad, h, sizeof bad);
	bad[5] = NAN;
	CHECK(m->set_value(m, ELEV, bad) == BMI_FAILURE, "a NaN height");
	CHECK(m->set_value(m, "sea_water__depth", bad) == BMI_FAILURE, "an unknown name");
	int inds[2] = {3, NX * NY};
	double two[2] = {9.0, 9.0};
	CHECK(m->set_value_at_indices(m, ELEV, inds, 2, two) == BMI_FAILURE, "an index past the end");
	CHECK(m->set_value_at_indices(m, ELEV, inds, -1, two) == BMI_FAILURE, "a negative count");
	CHECK(m->get_value_at_indices(m, ELEV, two, inds, 2) == BMI_FAILURE && two[0] == 9.0,
	      "get at an index past the end");
	CHECK(m->get_value(m, ELEV, back) == BMI_SUCCESS && same_bits(back, h, NX * NY),
	      "refused sets changed nothing");
	CHECK_REL(external(m), added, 1e-12, "nor the volume");
	inds[1] = 4;
	CHECK(m->set_value_at_indices(m, ELEV, inds, 2, two) == BMI_SUCCESS, "at indices");
	CHECK(m->get_value_at_indices(m, ELEV, back, inds, 2) == BMI_SUCCESS && back[0] == 9.0 &&
	      back[1] == 9.0, "at indices round-trip");
	double vol = 1.0;
	CHECK(m->set_value(m, VOLUME, &vol) == BMI_FAILURE, "a diagnostic is read-only");
	int zero[2] = {0, 0}, one = 1;
	double vols[2] = {-1, -2};
	CHECK(m->get_value_at_indices(m, VOLUME, vols, zero, 2) == BMI_SUCCESS && vols[0] > 0.0 &&
	      vols[0] == vols[1], "a scalar at index 0");
	CHECK(m->get_value_at_indices(m, VOLUME, vols, &one, 1) == BMI_FAILURE, "a scalar at 1");
	void *p = NULL;
	CHECK(m->get_value_ptr(m, ELEV, &p) == BMI_FAILURE && p == NULL, "no pointer (halo)");
	CHECK(m->update(m) == BMI_SUCCESS, "update after a set: %s", ss_error_last_message());
	ss_bmi_destroy(m);
}

/* The bits: set_value at t = 0, then update_until(T), gives what
 * `sandslide run` writes at T for the same case whose initial file holds
 * the heights set.  (Square cells: the case's initial file must have
 * dx = dy, setup.c, where the .asc reader takes dx and dy.) */
static void set_then_run_with(const char *integrator)
{
	char square[1024];
	const char *dy = strstr(case_text, "dy = 0.12\n");
	const char *every = strstr(case_text, "output_every = 0.25\n");
	snprintf(square, sizeof square, "%.*sdy = 0.1\n%.*sintegrator = %s\n%s",
	         (int)(dy - case_text), case_text,
	         (int)(every - dy - strlen("dy = 0.12\n")), dy + strlen("dy = 0.12\n"),
	         integrator, every);
	check_write_file(check_file("square.ini"), square);
	double h[NX * NY];
	struct rng r = {27};
	for (int c = 0; c < NX * NY; c++)
		h[c] = 0.2 + 0.15 * rng_uniform(&r);   /* slopes past the repose angle */
	FILE *f = fopen(check_file("bumps.asc"), "w");
	CHECK(f != NULL, "bumps.asc");
	if (!f)
		return;
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 2\nyllcorner -1\ncellsize 0.1\n", NX, NY);
	for (int j = NY - 1; j >= 0; j--)           /* north row first */
		for (int i = 0; i < NX; i++)
			fprintf(f, "%.17g%s", h[j * NX + i], i == NX - 1 ? "\n" : " ");
	fclose(f);
	struct ss_run_options *o = ss_option_object_create(&ss_run_option_table);
	CHECK(o != NULL, "run options");
	if (!o)
		return;
	char json[8192];
	CHECK(ss_option_object_set(o, "case", check_file("square.ini")) == SS_OK &&
	      ss_option_object_set(o, "output", check_file("bumps.h5")) == SS_OK &&
	      ss_option_object_set(o, "set", "initial.type=file") == SS_OK &&
	      ss_option_object_set(o, "set", "initial.file=bumps.asc") == SS_OK &&
	      ss_option_object_set(o, "set", "time.end=0.5") == SS_OK &&
	      ss_option_object_set(o, "set", "time.output_every=0.5") == SS_OK, "options");
	CHECK(ss_run_case_json(o, json, sizeof json) == SS_OK, "%s", ss_error_last_message());
	ss_option_object_destroy(o);
	struct ss_height_series hs;
	CHECK(ss_snapshot_read_height_series(check_file("bumps.h5"), &hs) == SS_OK, "%s",
	      ss_error_last_message());
	CHECK(hs.count == 2 && hs.time[1] == 0.5, "%lld snapshots", hs.count);
	CHECK(hs.count >= 1 && same_bits(hs.height, h, NX * NY), "run read the file's bits");
	struct Bmi *m = ss_bmi_create();
	if (m && m->initialize(m, check_file("square.ini")) != BMI_SUCCESS) {
		ss_bmi_destroy(m);
		m = NULL;
	}
	CHECK(m != NULL, "initialize");
	double got[NX * NY];
	if (m && hs.count == 2) {
		CHECK(m->set_value(m, ELEV, h) == BMI_SUCCESS, "set_value");
		CHECK(m->update_until(m, 0.5) == BMI_SUCCESS, "update_until");
		CHECK(m->get_value(m, ELEV, got) == BMI_SUCCESS &&
		      same_bits(got, hs.height + NX * NY, NX * NY),
		      "%s: set_value + update_until(0.5) is not run's bits from the file",
		      integrator);
		CHECK(!same_bits(got, h, NX * NY), "the bumps moved");
	}
	ss_height_series_release(&hs);
	ss_bmi_destroy(m);
	remove(check_file("square.ini"));
	remove(check_file("bumps.asc"));
	remove(check_file("bumps.h5"));
	remove(check_file("bumps.xmf"));
	remove(check_file("bumps.h5.aux.xml"));
}

static void set_then_run_is_a_run_from_a_file(void)
{
	set_then_run_with("euler");
	set_then_run_with("rkl2");
}

/* Wall cells keep their heights: a set changes, and counts, flow cells
 * only. */
static void set_value_leaves_walls(void)
{
	check_write_file(check_file("walled.ini"), "[grid]\nnx = 6\nny = 4\ndx = 0.5\n\n"
	                 "[model]\nclosure = coulomb\nrepose_angle = 35\nnu = 0.1\n\n"
	                 "[time]\nend = steady\nmax_time = 30\noutput_every = 2\n\n"
	                 "[initial]\ntype = flat\nheight = 0.2\n\n"
	                 "[wall pillar]\nrect = 0 0 1 1\n");
	struct Bmi *m = ss_bmi_create();
	CHECK(m != NULL, "create");
	if (!m)
		return;
	CHECK(m->initialize(m, check_file("walled.ini")) == BMI_SUCCESS, "%s",
	      ss_error_last_message());
	double end = 0, before[24], h[24], back[24];
	CHECK(m->get_end_time(m, &end) == BMI_SUCCESS && end == 30, "end = steady: max_time %g",
	      end);
	CHECK(m->get_value(m, ELEV, before) == BMI_SUCCESS, "get_value");
	for (int c = 0; c < 24; c++)
		h[c] = 0.5;
	CHECK(m->set_value(m, ELEV, h) == BMI_SUCCESS, "set");
	CHECK(m->get_value(m, ELEV, back) == BMI_SUCCESS, "get");
	int walls = 0;
	for (int c = 0; c < 24; c++) {
		const int wall = c % 6 < 2 && c / 6 < 2;   /* rect 0 0 1 1 of 0.5 m cells */
		walls += wall;
		/* a wall has no elevation: NaN, before and after */
		CHECK(wall ? isnan(back[c]) && isnan(before[c]) : back[c] == 0.5, "cell %d: %g", c,
		      back[c]);
	}
	CHECK(walls == 4, "four wall cells");
	CHECK_REL(external(m), 20 * 0.3 * 0.25, 1e-12, "flow cells counted only");
	ss_bmi_destroy(m);
	remove(check_file("walled.ini"));
}

/* The elevation is NaN on walls and on cells without data, as relax gives
 * it (Python's relax, the .h5 output), never the 0 m the stepper holds
 * there, which a coupled model would take for a cliff; get_value_at_indices
 * agrees, and a get then set round trip is accepted and changes nothing. */
static void elevation_is_nan_without_data(const char *nodata)
{
	enum { DX = 8, DY = 6 };
	double dem[DX * DY];
	FILE *f = fopen(check_file("holes.asc"), "w");
	CHECK(f != NULL, "holes.asc");
	if (!f)
		return;
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 0\nyllcorner 0\ncellsize 1\n"
	        "NODATA_value -9999\n", DX, DY);
	for (int j = DY - 1; j >= 0; j--)           /* north row first */
		for (int i = 0; i < DX; i++) {
			/* a void inside and a clipped western edge; a slope that slides */
			const int none = i == 0 || (i == 4 && j == 3);
			dem[j * DX + i] = none ? NAN : 5.0 + 1.5 * i;
			if (none)
				fputs("-9999", f);
			else
				fprintf(f, "%.17g", dem[j * DX + i]);
			fputs(i == DX - 1 ? "\n" : " ", f);
		}
	fclose(f);
	char cfg[256];
	snprintf(cfg, sizeof cfg, "[bmi]\ndem = holes.asc\ntime_step = 0.5\nend = 2\n"
	         "nodata = %s\n", nodata);
	check_write_file(check_file("holes.cfg"), cfg);
	struct Bmi *m = initialized("holes.cfg");
	if (!m)
		return;
	double got[DX * DY], at[DX * DY], want[DX * DY];
	int inds[DX * DY];
	for (int c = 0; c < DX * DY; c++)
		inds[c] = c;
	CHECK(m->update_until(m, 1.0) == BMI_SUCCESS, "update_until");
	CHECK(m->get_value(m, ELEV, got) == BMI_SUCCESS, "get_value");
	CHECK(m->get_value_at_indices(m, ELEV, at, inds, DX * DY) == BMI_SUCCESS, "at indices");
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	CHECK(o && !ss_option_object_set(o, "nodata", nodata) &&
	      !ss_option_object_set(o, "max-time", "1"), "relax options");
	CHECK(o && ss_relax_heights(o, DX, DY, 1.0, 1.0, dem, NULL, want, NULL, 0) == SS_OK, "%s",
	      ss_error_last_message());
	ss_option_object_destroy(o);
	int nans = 0;
	for (int c = 0; c < DX * DY; c++) {
		nans += isnan(got[c]);
		CHECK(isnan(got[c]) == isnan(dem[c]) && isnan(want[c]) == isnan(dem[c]),
		      "--nodata %s, cell %d: %g, relax's %g", nodata, c, got[c], want[c]);
		CHECK(memcmp(&got[c], &at[c], sizeof at[c]) == 0, "cell %d at indices", c);
	}
	CHECK(nans == DY + 1, "--nodata %s: %d NaN cells", nodata, nans);
	double external0 = external(m), back[DX * DY];
	CHECK(m->set_value(m, ELEV, got) == BMI_SUCCESS, "set what get gave: %s",
	      ss_error_last_message());
	CHECK(m->get_value(m, ELEV, back) == BMI_SUCCESS && same_bits(back, got, DX * DY) &&
	      external(m) == external0, "the round trip changed something");
	ss_bmi_destroy(m);
	remove(check_file("holes.cfg"));
	remove(check_file("holes.asc"));
}

static void elevation_is_nan_on_walls_and_nodata(void)
{
	elevation_is_nan_without_data("wall");
	elevation_is_nan_without_data("open");
}

/* The deposition rate is a source: a rate field on a rectangle gives the
 * bits of the same case with a source pouring that rate there, its volume
 * is the inflow, and the ledger closes: volume = initial + inflow -
 * outflow + external. */
static void rate_is_a_source(void)
{
	static const char *walled =
		"[grid]\nnx = 14\nny = 10\ndx = 0.1\n\n"
		"[model]\nclosure = coulomb\nrepose_angle = 35\nnu = 0.1\n\n"
		"[time]\nend = 2\noutput_every = 0.5\n\n"
		"[boundary]\nwest = wall\neast = open\nsouth = wall\nnorth = wall\n\n"
		"[initial]\ntype = flat\nheight = 0.05\n";
	char poured[1024];
	snprintf(poured, sizeof poured, "%s\n[source pour]\nrect = 0.3 0.2 0.7 0.6\n"
	         "rate = 0.02\nstart = 0\nstop = 100\n", walled);
	check_write_file(check_file("flat.ini"), walled);
	check_write_file(check_file("poured.ini"), poured);
	struct ss_case c;
	struct ss_stepper st;
	int err = ss_case_load(&c, check_file("poured.ini"), NULL, 0);
	CHECK(!err, "%s", ss_error_last_message());
	if (err)
		return;
	err = ss_setup_stepper(&c, 0, 0, SS_KERNEL_FAST, &st);
	ss_case_release(&c);
	CHECK(!err, "%s", ss_error_last_message());
	if (err)
		return;
	const struct ss_advance_options o = {0};
	CHECK(ss_stepper_advance(&st, 1.5, &o) == SS_ADVANCE_REACHED, "the poured case");
	double want[NX * NY], got[NX * NY], rate[NX * NY], before[NX * NY];
	stepper_heights(&st, want);
	/* the source's cells, as the stepper has them: rate / 0.02 */
	for (int j = 0; j < NY; j++)
		for (int i = 0; i < NX; i++) {
			const double *r = st.sources->rate;
			rate[j * NX + i] = r && r[ss_grid_index(&st.grid, i, j)] > 0.0 ? 0.02 : 0.0;
		}
	const double inflow = ss_stepper_inflow(&st);
	ss_stepper_release(&st);

	struct Bmi *m = initialized("flat.ini");
	if (!m)
		return;
	const double v0 = scalar(m, VOLUME);
	double back[NX * NY];
	CHECK(m->set_value(m, RATE, rate) == BMI_SUCCESS, "%s", ss_error_last_message());
	CHECK(m->get_value(m, RATE, back) == BMI_SUCCESS && same_bits(back, rate, NX * NY),
	      "the rate set is the rate got");
	CHECK(m->update_until(m, 1.5) == BMI_SUCCESS, "update_until");
	CHECK(m->get_value(m, ELEV, got) == BMI_SUCCESS && same_bits(got, want, NX * NY),
	      "a rate field is not the bits of a source of that rate");
	CHECK(scalar(m, INFLOW) == inflow, "inflow %.17g, the source's %.17g", scalar(m, INFLOW),
	      inflow);
	CHECK_REL(inflow, 0.02 * 1.5 * 0.4 * 0.4, 1e-12, "the rate's volume is the inflow");
	/* refused rates change neither the field nor what follows */
	double bad[NX * NY];
	memcpy(bad, rate, sizeof bad);
	bad[3 * NX + 4] = INFINITY;
	CHECK(m->set_value(m, RATE, bad) == BMI_FAILURE, "an infinite rate");
	int at = 3 * NX + 4;
	double nan = NAN;
	CHECK(m->set_value_at_indices(m, RATE, &at, 1, &nan) == BMI_FAILURE, "a NaN rate");
	CHECK(m->get_value(m, RATE, back) == BMI_SUCCESS && same_bits(back, rate, NX * NY),
	      "a refused rate changed the field");
	/* the ledger with all three: a rate, an external set, the outflow */
	CHECK(m->get_value(m, ELEV, before) == BMI_SUCCESS, "get");
	for (int k = 0; k < NX * NY; k++)     /* a steep step by the open side */
		before[k] += k % NX >= NX - 3 ? 0.2 : 0.01;
	CHECK(m->set_value(m, ELEV, before) == BMI_SUCCESS, "set");
	for (int k = 0; k < NX * NY; k++)
		rate[k] = k % NX == NX - 2 ? -0.001 : rate[k];   /* erosion, no bedrock */
	CHECK(m->set_value(m, RATE, rate) == BMI_SUCCESS, "a negative rate without bedrock: %s",
	      ss_error_last_message());
	CHECK(m->update_until(m, 4.0) == BMI_SUCCESS, "update_until 4");
	const double v = scalar(m, VOLUME), in = scalar(m, INFLOW), out = scalar(m, OUTFLOW),
	             ext = scalar(m, EXTERNAL);
	CHECK(out > 0.0 && ext > 0.0, "outflow %g, external %g", out, ext);
	CHECK_REL(v, v0 + in - out + ext, 1e-12, "volume %.17g = %.17g + %.17g - %.17g + %.17g",
	          v, v0, in, out, ext);
	ss_bmi_destroy(m);
	remove(check_file("flat.ini"));
	remove(check_file("poured.ini"));
}

/* A case with a bedrock: the bedrock is an output, and a negative rate
 * (erosion, which has no floor at the rock) is refused. */
static void bedrock_and_erosion(void)
{
	check_write_file(check_file("rock.asc"), "ncols 4\nnrows 3\nxllcorner 0\n"
	                 "yllcorner 0\ncellsize 1\n0 0 0 0\n0 0.1 0.1 0\n0 0 0 0\n");
	check_write_file(check_file("rock.ini"), "[grid]\nnx = 4\nny = 3\ndx = 1\n\n"
	                 "[model]\nclosure = coulomb\nrepose_angle = 35\nnu = 0.1\n\n"
	                 "[time]\nend = 10\noutput_every = 1\n\n"
	                 "[initial]\ntype = flat\nheight = 0.3\nbedrock = rock.asc\n");
	struct Bmi *m = initialized("rock.ini");
	if (!m)
		return;
	int n = 0, grid = -1;
	CHECK(m->get_output_item_count(m, &n) == BMI_SUCCESS && n == NOUT + 1, "%d outputs", n);
	CHECK(m->get_var_grid(m, BEDROCK, &grid) == BMI_SUCCESS && grid == 0, "bedrock grid");
	double rock[12], rate[12] = {0};
	CHECK(m->get_value(m, BEDROCK, rock) == BMI_SUCCESS && rock[0] == 0.0 &&
	      rock[5] == 0.1 && rock[6] == 0.1, "bedrock %g %g %g", rock[0], rock[5], rock[6]);
	rate[5] = -1e-3;
	CHECK(m->set_value(m, RATE, rate) == BMI_FAILURE, "erosion over a bedrock");
	rate[5] = 1e-3;
	CHECK(m->set_value(m, RATE, rate) == BMI_SUCCESS, "deposition over a bedrock");
	CHECK(m->set_value(m, BEDROCK, rock) == BMI_FAILURE, "the bedrock is an output only");
	ss_bmi_destroy(m);
	remove(check_file("rock.asc"));
	remove(check_file("rock.ini"));
}

/* A case with hysteresis (doc/model.md#hysteresis): which cells move is
 * an output, 1 where sand moves and 0 where it rests, NaN on walls. */
static void flowing_state(void)
{
	check_write_file(check_file("pour.ini"), "[grid]\nnx = 12\nny = 10\ndx = 0.05\n\n"
	                 "[model]\nclosure = coulomb\nrepose_angle = 30\nstatic_angle = 36\n"
	                 "nu = 0.1\n\n[time]\nend = 10\noutput_every = 0.5\n\n"
	                 "[boundary]\neast = open\n\n"
	                 "[initial]\ntype = flat\nheight = 0\n\n"
	                 "[wall post]\nrect = 0 0 0.05 0.05\n\n"
	                 "[source pour]\nrect = 0.2 0.2 0.3 0.3\nrate = 0.05\n");
	struct Bmi *m = initialized("pour.ini");
	if (!m)
		return;
	int n = 0, grid = -1;
	/* the flowing state for the angle: hysteresis takes one */
	CHECK(m->get_output_item_count(m, &n) == BMI_SUCCESS && n == NOUT, "%d outputs", n);
	CHECK(m->get_var_grid(m, "sand__flowing_state", &grid) == BMI_SUCCESS && grid == 0,
	      "flowing state's grid");
	CHECK(m->get_var_grid(m, ANGLE, &grid) == BMI_FAILURE, "an angle field with hysteresis");
	double moving[120];
	int ones = 0, bad = 0;
	for (int k = 0; k < 8 && m->update(m) == BMI_SUCCESS; k++) {
		CHECK(m->get_value(m, "sand__flowing_state", moving) == BMI_SUCCESS, "get");
		for (int c = 0; c < 120; c++) {
			ones += moving[c] == 1.0;
			bad += !(moving[c] == 0.0 || moving[c] == 1.0 || (c == 0 && isnan(moving[c])));
		}
	}
	CHECK(ones > 0 && bad == 0, "flowing state: %d ones over 8 updates, %d values not 0, 1 "
	      "or NaN on the wall", ones, bad);
	ss_bmi_destroy(m);
	remove(check_file("pour.ini"));
}

/* pile.asc (DX x DY cells of 0.5 m, 50-degree flanks) into the scratch
 * folder, and its heights into dem ([y][x], south row first). */
enum { PILE_NX = 12, PILE_NY = 9 };
static int write_pile(double *dem)
{
	for (int j = 0; j < PILE_NY; j++)
		for (int i = 0; i < PILE_NX; i++) {
			const double r = hypot(i - 5.5, j - 4.0);
			dem[j * PILE_NX + i] = 0.1 + fmax(0.0, 1.2 * (3.0 - r)) * 0.5;
		}
	FILE *f = fopen(check_file("pile.asc"), "w");
	CHECK(f != NULL, "pile.asc");
	if (!f)
		return -1;
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 100\nyllcorner 200\ncellsize 0.5\n", PILE_NX,
	        PILE_NY);
	for (int j = PILE_NY - 1; j >= 0; j--)           /* north row first */
		for (int i = 0; i < PILE_NX; i++)
			fprintf(f, "%.17g%s", dem[j * PILE_NX + i], i == PILE_NX - 1 ? "\n" : " ");
	return fclose(f);
}

/* The repose angle as an input (doc/bmi.md, doc/model.md#materials): set
 * at the start it is the run with that angle raster; a pile steeper than
 * its angle slides, one below it holds to the bit; setting the angles the
 * model has changes nothing; a bad angle is refused and changes nothing. */
static void angle_field(void)
{
	enum { DX = PILE_NX, DY = PILE_NY, N = PILE_NX * PILE_NY };
	double dem[N], half[N], got[N], want[N], angles[N];
	if (write_pile(dem))
		return;
	FILE *f = fopen(check_file("half.asc"), "w");   /* west 30, east 40 degrees */
	CHECK(f != NULL, "half.asc");
	if (!f)
		return;
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 100\nyllcorner 200\ncellsize 0.5\n", DX, DY);
	for (int j = DY - 1; j >= 0; j--)
		for (int i = 0; i < DX; i++)
			fprintf(f, "%d%s", i < DX / 2 ? 30 : 40, i == DX - 1 ? "\n" : " ");
	fclose(f);
	for (int c = 0; c < N; c++)
		half[c] = c % DX < DX / 2 ? 30.0 : 40.0;
	const char *common = "time_step = 0.5\nend = 3\nnu = 0.1\nsides = open\ntile = 4x3\n"
	                     "integrator = rkl2\n";
	char text[512];
	snprintf(text, sizeof text, "[bmi]\ndem = pile.asc\nangle = half.asc\n%s", common);
	check_write_file(check_file("half.cfg"), text);
	snprintf(text, sizeof text, "[bmi]\ndem = pile.asc\nangle = 33\n%s", common);
	check_write_file(check_file("uniform.cfg"), text);

	/* the raster given at initialize (its name relative to the config),
	 * and the same angles set at t = 0 */
	struct Bmi *a = initialized("half.cfg"), *b = initialized("uniform.cfg");
	if (a && b) {
		CHECK(b->get_value(b, ANGLE, angles) == BMI_SUCCESS && angles[0] == 33.0 &&
		      angles[N - 1] == 33.0, "uniform angles %g %g", angles[0], angles[N - 1]);
		CHECK(b->set_value(b, ANGLE, half) == BMI_SUCCESS, "%s", ss_error_last_message());
		CHECK(b->get_value(b, ANGLE, angles) == BMI_SUCCESS && same_bits(angles, half, N),
		      "the angles set are not read back");
		CHECK(a->update_until(a, 1.5) == BMI_SUCCESS && b->update_until(b, 1.5) == BMI_SUCCESS,
		      "update_until");
		CHECK(a->get_value(a, ELEV, want) == BMI_SUCCESS &&
		      b->get_value(b, ELEV, got) == BMI_SUCCESS && same_bits(got, want, N),
		      "angles set at t = 0 are not the run with that angle raster");
		CHECK(!same_bits(got, dem, N), "the pile slid");
		/* the angles it has, set again: not a bit changes */
		CHECK(b->get_value(b, ANGLE, angles) == BMI_SUCCESS &&
		      b->set_value(b, ANGLE, angles) == BMI_SUCCESS, "%s", ss_error_last_message());
		CHECK(a->update_until(a, 3.0) == BMI_SUCCESS && b->update_until(b, 3.0) == BMI_SUCCESS,
		      "update_until");
		CHECK(a->get_value(a, ELEV, want) == BMI_SUCCESS &&
		      b->get_value(b, ELEV, got) == BMI_SUCCESS && same_bits(got, want, N),
		      "setting the angles the model has changed the heights");
	}
	ss_bmi_destroy(a);
	ss_bmi_destroy(b);

	/* 55 degrees holds the 50-degree pile to the bit; 33 then lets it
	 * slide, conserving the sand (no open side: sides = open is only
	 * the outer ring's, the pile stays inside) */
	b = initialized("uniform.cfg");
	if (!b)
		return;
	for (int c = 0; c < N; c++)
		angles[c] = 55.0;
	const double volume = scalar(b, VOLUME);
	CHECK(b->set_value(b, ANGLE, angles) == BMI_SUCCESS && b->update(b) == BMI_SUCCESS &&
	      b->update(b) == BMI_SUCCESS, "%s", ss_error_last_message());
	CHECK(b->get_value(b, ELEV, got) == BMI_SUCCESS && same_bits(got, dem, N),
	      "a 50-degree pile moved under a 55-degree angle");
	for (int c = 0; c < N; c++)
		angles[c] = 33.0;
	CHECK(b->set_value(b, ANGLE, angles) == BMI_SUCCESS && b->update(b) == BMI_SUCCESS,
	      "%s", ss_error_last_message());
	CHECK(b->get_value(b, ELEV, got) == BMI_SUCCESS && !same_bits(got, dem, N),
	      "the pile did not slide at 33 degrees");
	CHECK(fabs(scalar(b, VOLUME) + scalar(b, OUTFLOW) - volume) <= 1e-12 * volume,
	      "volume %.17g + outflow %.17g, was %.17g", scalar(b, VOLUME), scalar(b, OUTFLOW),
	      volume);
	/* one cell's angle */
	int at = 3 * DX + 4;
	double one = 45.0;
	CHECK(b->set_value_at_indices(b, ANGLE, &at, 1, &one) == BMI_SUCCESS &&
	      b->get_value(b, ANGLE, angles) == BMI_SUCCESS && angles[at] == 45.0 &&
	      angles[at + 1] == 33.0, "one cell's angle: %g, beside %g", angles[at],
	      angles[at + 1]);
	/* refused, the angles as they were */
	const double bad[] = {95.0, 0.0, -30.0, NAN, INFINITY};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		CHECK(b->set_value_at_indices(b, ANGLE, &at, 1, (double *)&bad[k]) == BMI_FAILURE &&
		      strstr(ss_error_last_message(), ANGLE), "angle %g accepted: %s", bad[k],
		      ss_error_last_message());
		CHECK(b->get_value(b, ANGLE, angles) == BMI_SUCCESS && angles[at] == 45.0,
		      "a refused angle changed the field: %g", angles[at]);
	}
	CHECK(b->update(b) == BMI_SUCCESS, "update after a refused set");
	ss_bmi_destroy(b);
	remove(check_file("half.cfg"));
	remove(check_file("uniform.cfg"));
	remove(check_file("half.asc"));
	remove(check_file("pile.asc"));
}

/* A BMI config naming a case is that case; one naming a DEM is set up as
 * relax sets it up: update_until(T) gives the bits of relax with
 * max_time T on the same heights.  Bad configs fail and keep nothing. */
static void config_names_a_case_or_a_dem(void)
{
	enum { DX = 12, DY = 9 };
	double dem[DX * DY];
	for (int j = 0; j < DY; j++)
		for (int i = 0; i < DX; i++) {
			const double r = hypot(i - 5.5, j - 4.0);
			dem[j * DX + i] = 0.1 + fmax(0.0, 1.2 * (3.0 - r)) * 0.5;   /* 50 deg flanks */
		}
	FILE *f = fopen(check_file("pile.asc"), "w");
	CHECK(f != NULL, "pile.asc");
	if (!f)
		return;
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 100\nyllcorner 200\ncellsize 0.5\n", DX, DY);
	for (int j = DY - 1; j >= 0; j--)           /* north row first */
		for (int i = 0; i < DX; i++)
			fprintf(f, "%.17g%s", dem[j * DX + i], i == DX - 1 ? "\n" : " ");
	fclose(f);
	check_write_file(check_file("dem.cfg"), "; a DEM\n[bmi]\ndem = pile.asc\n"
	                 "time_step = 0.5\nend = 3\nangle = 33\nnu = 0.1\nsides = open\n");
	struct Bmi *m = initialized("dem.cfg");
	if (!m)
		return;
	int shape[2] = {0, 0};
	double spacing[2], origin[2], step = 0, end = 0;
	CHECK(m->get_grid_shape(m, 0, shape) == BMI_SUCCESS && shape[0] == DY && shape[1] == DX,
	      "shape %d x %d", shape[0], shape[1]);
	CHECK(m->get_grid_spacing(m, 0, spacing) == BMI_SUCCESS && spacing[0] == 0.5 &&
	      spacing[1] == 0.5, "spacing");
	CHECK(m->get_grid_origin(m, 0, origin) == BMI_SUCCESS && origin[0] == 200.25 &&
	      origin[1] == 100.25, "origin %g %g", origin[0], origin[1]);
	CHECK(m->get_time_step(m, &step) == BMI_SUCCESS && step == 0.5, "step %g", step);
	CHECK(m->get_end_time(m, &end) == BMI_SUCCESS && end == 3, "end %g", end);
	double got[DX * DY], want[DX * DY];
	CHECK(m->update_until(m, 1.0) == BMI_SUCCESS, "update_until");
	CHECK(m->get_value(m, ELEV, got) == BMI_SUCCESS, "get_value");
	ss_bmi_destroy(m);
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	CHECK(o && !ss_option_object_set(o, "angle", "33") && !ss_option_object_set(o, "nu", "0.1") &&
	      !ss_option_object_set(o, "sides", "open") &&
	      !ss_option_object_set(o, "max-time", "1"), "relax options");
	CHECK(o && ss_relax_heights(o, DX, DY, 0.5, 0.5, dem, NULL, want, NULL, 0) == SS_OK, "%s",
	      ss_error_last_message());
	ss_option_object_destroy(o);
	CHECK(same_bits(got, want, DX * DY), "the DEM's update_until(1) is not relax's "
	      "--max-time 1");
	CHECK(!same_bits(got, dem, DX * DY), "the pile slid");

	/* a config naming a case is the case */
	check_write_file(check_file("case.cfg"), "[bmi]\ncase = cone.ini\n");
	struct Bmi *a = started(), *b = ss_bmi_create();
	CHECK(b && b->initialize(b, check_file("case.cfg")) == BMI_SUCCESS, "%s",
	      ss_error_last_message());
	double ha[NX * NY], hb[NX * NY];
	if (a && b && b->data) {
		CHECK(a->update(a) == BMI_SUCCESS && b->update(b) == BMI_SUCCESS, "update");
		CHECK(a->get_value(a, ELEV, ha) == BMI_SUCCESS &&
		      b->get_value(b, ELEV, hb) == BMI_SUCCESS && same_bits(ha, hb, NX * NY),
		      "case = cone.ini is not cone.ini");
	}
	ss_bmi_destroy(a);
	ss_bmi_destroy(b);

	/* device = cpu is the default; a GPU is refused with the reason (this
	 * build has no CUDA, the machine no GPU, or the BMI's loop is not on
	 * one yet: doc/gpu.md) */
	check_write_file(check_file("case.cfg"), "[bmi]\ncase = cone.ini\ndevice = cpu\n");
	m = ss_bmi_create();
	CHECK(m && m->initialize(m, check_file("case.cfg")) == BMI_SUCCESS,
	      "case with device = cpu: %s", ss_error_last_message());
	ss_bmi_destroy(m);
	static const char *const gpus[] = {"[bmi]\ncase = cone.ini\ndevice = cuda\n",
	                                   "[bmi]\ndem = pile.asc\ntime_step = 1\ndevice = cuda:1\n"};
	for (size_t k = 0; k < sizeof gpus / sizeof *gpus; k++) {
		check_write_file(check_file("bad.cfg"), gpus[k]);
		m = ss_bmi_create();
		CHECK(m && m->initialize(m, check_file("bad.cfg")) == BMI_FAILURE && !m->data,
		      "%s accepted", gpus[k]);
		CHECK(strstr(ss_error_last_message(), "[bmi] device = cuda") &&
		      (strstr(ss_error_last_message(), "no CUDA") ||
		       strstr(ss_error_last_message(), "GPU")),
		      "%s: the refusal does not say why: %s", gpus[k], ss_error_last_message());
		ss_bmi_destroy(m);
	}

	/* refused, each with nothing kept */
	static const char *const bad[] = {
		"[bmi]\ndem = pile.asc\n",                                   /* no time_step */
		"[bmi]\ndem = pile.asc\ncase = cone.ini\ntime_step = 1\n",     /* both */
		"[bmi]\ndem = pile.asc\ntime_step = 1\nangel = 33\n",          /* unknown key */
		"[bmi]\ndem = pile.asc\ntime_step = -1\n",
		"[bmi]\ndem = pile.asc\ntime_step = 1\noutput = x.h5\n",
		"[bmi]\ncase = cone.ini\nangle = 33\n",
		"[bmi]\ndem = missing.asc\ntime_step = 1\n",
		"[bmi]\nend = 3\n",
		"[bmi]\ncase = cone.ini\n[grid]\nnx = 3\n",
		"[bmi]\ncase = cone.ini\ndevice = gpu\n",
	};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		check_write_file(check_file("bad.cfg"), bad[k]);
		m = ss_bmi_create();
		CHECK(m && m->initialize(m, check_file("bad.cfg")) == BMI_FAILURE && !m->data,
		      "config %zu accepted: %s", k, bad[k]);
		ss_bmi_destroy(m);
	}
	remove(check_file("bad.cfg"));
	remove(check_file("case.cfg"));
	remove(check_file("dem.cfg"));
	remove(check_file("pile.asc"));
}

int main(void)
{
	if (check_scratch_make("ss_test_bmi"))
		return 2;
	ss_error_set_quiet(1);
	check_write_file(check_file("cone.ini"), case_text);
	RUN(bootstrap);
	RUN(info);
	RUN(time_stage);
	RUN(vars);
	RUN(grid);
	RUN(value_is_what_run_writes);
	RUN(update_until_is_the_library);
	RUN(set_value_round_trips);
	RUN(set_then_run_is_a_run_from_a_file);
	RUN(set_value_leaves_walls);
	RUN(elevation_is_nan_on_walls_and_nodata);
	RUN(rate_is_a_source);
	RUN(bedrock_and_erosion);
	RUN(flowing_state);
	RUN(angle_field);
	RUN(config_names_a_case_or_a_dem);
	remove(check_file("cone.ini"));
	rmdir(check_scratch());
	return check_report();
}
