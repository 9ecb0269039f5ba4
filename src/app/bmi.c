/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * bmi.c - sandslide behind the CSDMS Basic Model Interface (bmi.h): a case
 * file set up as `sandslide run` sets it up, stepped without output, its
 * heights read and written as one uniform_rectilinear grid.
 */
#include "sandslide/bmi.h"

#include <ini.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/drive.h"
#include "app/relax_inputs.h"
#include "base/strings.h"
#include "model/materials.h"
#include "model/setup.h"
#include "sandslide/case.h"
#include "sandslide/dem.h"
#include "sandslide/device.h"
#include "sandslide/error.h"
#include "sandslide/relax.h"
#include "sandslide/stepper.h"

#define ELEVATION "land_surface__elevation"
#define RATE "land_surface__net_deposition_rate"
#define ANGLE "sand__angle_of_repose"

/* The variables: the elevation, the deposition rate and the repose angle
 * (the inputs) and the bedrock on grid 0, and read-only diagnostics of the whole model on
 * grid 1 (a scalar), from ss_stepper_diagnostics.  The bedrock is there
 * only when the case has one. */
enum var_id {
	VAR_ELEVATION, VAR_RATE, VAR_ANGLE, VAR_BEDROCK, VAR_MOVING, VAR_VOLUME, VAR_INFLOW, VAR_OUTFLOW,
	VAR_EXTERNAL, VAR_SLOPE, VAR_COUNT
};

static const struct var {
	const char *name, *units;
	int grid;
	int input, output;
} vars[VAR_COUNT] = {
	[VAR_ELEVATION] = {ELEVATION, "m", 0, 1, 1},
	[VAR_RATE] = {RATE, "m s-1", 0, 1, 0},
	[VAR_ANGLE] = {ANGLE, "deg", 0, 1, 1},
	[VAR_BEDROCK] = {"bedrock_surface__elevation", "m", 0, 0, 1},
	[VAR_MOVING] = {"sand__flowing_state", "1", 0, 0, 1},
	[VAR_VOLUME] = {"sand__volume", "m3", 1, 0, 1},
	[VAR_INFLOW] = {"sand__time_integral_of_source_volume_flux", "m3", 1, 0, 1},
	[VAR_OUTFLOW] = {"sand__time_integral_of_outflow_volume_flux", "m3", 1, 0, 1},
	[VAR_EXTERNAL] = {"sand__external_volume_change", "m3", 1, 0, 1},
	[VAR_SLOPE] = {"sand_surface__max_of_slope_angle", "deg", 1, 0, 1},
};

/* What initialize builds and finalize releases. */
struct bmi_state {
	struct ss_stepper st;
	double end;          /* s: the case's end, or max_time when steady */
	double step;         /* s: the case's output_every */
	double *rate;        /* m/s, ny * nx [y][x]: the deposition rate set
	                      * (the stepper's rate field), 0 until set */
	double *rate_next;   /* the same room: a set is built here, and the two
	                      * swap when the stepper takes it */
	int cells;           /* nx * ny (fits an int: checked) */
	uint8_t *nodata;     /* ny * nx [y][x]: 1 where a DEM has no data
	                      * (walls or open cells by its nodata option);
	                      * NULL: none (a case, or a DEM without) */
};

static struct bmi_state *state(struct Bmi *self)
{
	return self ? self->data : NULL;
}

static int present(const struct bmi_state *s, int v)
{
	/* with hysteresis the materials are the states: one repose angle */
	return (v != VAR_BEDROCK || (s && s->st.bedrock)) &&
	       (v != VAR_MOVING || (s && s->st.hysteresis)) &&
	       (v != VAR_ANGLE || (s && !s->st.hysteresis));
}

/* The variable called name that this model has, or NULL. */
static const struct var *find_var_of(const struct bmi_state *s, const char *name)
{
	for (int v = 0; name && v < VAR_COUNT; v++)
		if (!strcmp(name, vars[v].name) && present(s, v))
			return &vars[v];
	return NULL;
}

/* ---- initialize, run, finalize ------------------------------------------ */

/*
 * The config initialize takes (doc/bmi.md#the-config): a case file, or an
 * INI file whose only section, [bmi], names a case file or a DEM:
 *
 *     [bmi]
 *     dem = terrain.tif    ; a raster relax reads, set up as `sandslide relax`
 *     time_step = 10       ; s: what update advances (needed with dem)
 *     end = 600            ; s: the end time (default: max_time, else none)
 *     angle = 33           ; any other key: relax's option of that name
 *     device = cpu         ; where it computes (device.h): only the CPU yet
 *
 * or `case = room.ini` (and device) alone.  File names are relative to the config's
 * folder.  A file without a [bmi] section is a case file.
 */
#define CONFIG_MAX_KEYS 64

struct config {
	const char *path;
	int bmi_section, other_section;   /* seen */
	int count;
	char *key[CONFIG_MAX_KEYS], *value[CONFIG_MAX_KEYS];
	int err;                          /* out of memory, too many keys */
};

static int config_handler(void *user, const char *section, const char *key, const char *value)
{
	struct config *c = user;
	if (strcmp(section, "bmi") != 0) {
		c->other_section = 1;
		return 1;
	}
	c->bmi_section = 1;
	if (c->err)
		return 1;
	if (c->count == CONFIG_MAX_KEYS) {
		c->err = ss_error_input("%s: more than %d keys in [bmi]", c->path, CONFIG_MAX_KEYS);
		return 1;
	}
	c->key[c->count] = strdup(key);
	c->value[c->count] = strdup(value);
	if (!c->key[c->count] || !c->value[c->count]) {
		free(c->key[c->count]);
		free(c->value[c->count]);
		c->err = ss_error_fail("%s: out of memory", c->path);
		return 1;
	}
	c->count++;
	return 1;
}

static void config_release(struct config *c)
{
	for (int k = 0; k < c->count; k++) {
		free(c->key[k]);
		free(c->value[k]);
	}
	c->count = 0;
}

/* The value of key in [bmi], or NULL. */
static const char *config_get(const struct config *c, const char *key)
{
	for (int k = 0; k < c->count; k++)
		if (!strcmp(c->key[k], key))
			return c->value[k];
	return NULL;
}

/* name resolved against the config's folder into out. */
static int config_path(const struct config *c, const char *name, char *out, size_t size)
{
	const char *slash = strrchr(c->path, '/');
	const int dir = name[0] == '/' || !slash ? 0 : (int)(slash - c->path) + 1;
	if (snprintf(out, size, "%.*s%s", dir, c->path, name) >= (int)size)
		return ss_error_input("%s: the file name '%s' is too long", c->path, name);
	return SS_OK;
}

/* A case file into s (as `sandslide run` sets it up). */
static int setup_case(struct bmi_state *s, const char *path)
{
	struct ss_case c;
	int err = ss_case_load(&c, path, NULL, 0);
	if (err)
		return err;
	if ((double)c.nx * c.ny * sizeof(double) > INT_MAX)
		err = ss_error_input("BMI initialize: %s: %d x %d cells is more than the BMI's int "
		                     "sizes can count", path, c.nx, c.ny);
	if (!err)
		err = ss_setup_stepper(&c, 0, 0, SS_KERNEL_FAST, &s->st);
	if (!err) {
		s->end = c.steady ? c.model.max_time : c.end;
		s->step = c.output_every;
	}
	ss_case_release(&c);
	return err;
}

/* Whether relax's option key with this value names a file, which the
 * config names relative to its folder: the rasters, the material table, an
 * angle that is not a number (model_options.h). */
static int names_file(const char *key, const char *value)
{
	static const char *const files[] = {"dem", "bedrock", "materials", "material-table",
	                                    "material_table"};
	for (size_t k = 0; k < sizeof files / sizeof *files; k++)
		if (!strcmp(key, files[k]))
			return 1;
	char *end;
	(void)strtod(value, &end);
	return !strcmp(key, "angle") && end == value;
}

/* A DEM and relax's options by name into s (as `sandslide relax` sets
 * it up: its CRS check, nodata, sides, bedrock). */
static int setup_dem(struct bmi_state *s, const struct config *cf)
{
	const char *step = config_get(cf, "time_step"), *end = config_get(cf, "end");
	if (!step)
		return ss_error_input("%s: [bmi] with dem needs time_step (s: what update "
		                      "advances)", cf->path);
	if (ss_parse_real(step, 0.0, INFINITY, &s->step) || !(s->step > 0.0))
		return ss_error_input("%s: [bmi] time_step '%s': expected seconds > 0", cf->path,
		                      step);
	if (end && (ss_parse_real(end, 0.0, INFINITY, &s->end) || !(s->end > 0.0)))
		return ss_error_input("%s: [bmi] end '%s': expected seconds > 0", cf->path, end);
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	if (!o)
		return SS_ERR_FAIL;
	char path[4096];
	int err = SS_OK;
	for (int k = 0; !err && k < cf->count; k++) {
		const char *key = cf->key[k], *value = cf->value[k];
		if (!strcmp(key, "time_step") || !strcmp(key, "end") || !strcmp(key, "device"))
			continue;   /* device: setup's, checked */
		if (!strcmp(key, "case"))
			err = ss_error_input("%s: [bmi] names a case or a dem, not both", cf->path);
		else if (!strcmp(key, "output") || !strcmp(key, "report") ||
		         !strcmp(key, "threads") || !strcmp(key, "force") ||
		         !strcmp(key, "output_every") || !strcmp(key, "output-every"))
			err = ss_error_input("%s: [bmi] %s: not a BMI setting (the BMI writes no "
			                     "files; threads: OMP_NUM_THREADS)", cf->path, key);
		else if (names_file(key, value)) {
			if (!(err = config_path(cf, value, path, sizeof path)))
				err = ss_option_object_set(o, key, path);
		} else {
			/* its message names the key and what it accepts */
			err = ss_option_object_set(o, key, value);
		}
	}
	struct ss_relax_inputs in = {0};
	if (!err)
		err = ss_relax_inputs_read(o, &in);
	if (!err && (double)in.dem.nx * in.dem.ny * sizeof(double) > INT_MAX)
		err = ss_error_input("BMI initialize: %s: %d x %d cells is more than the BMI's int "
		                     "sizes can count", o->dem, in.dem.nx, in.dem.ny);
	if (!err)
		err = ss_relax_setup_stepper(o, &in, 0, &s->st, NULL);
	/* kept for get_value: a cell without data has no elevation */
	if (!err && in.dem.nodata) {
		const size_t cells = (size_t)in.dem.nx * (size_t)in.dem.ny;
		if (!(s->nodata = ss_alloc(cells, 1, "the BMI's nodata flags"))) {
			ss_stepper_release(&s->st);
			err = SS_ERR_FAIL;
		} else
			memcpy(s->nodata, in.dem.nodata, cells);
	}
	if (!err && !end)
		s->end = isfinite(o->model.max_time) ? o->model.max_time : INFINITY;
	ss_relax_inputs_release(&in);
	ss_option_object_destroy(o);
	return err;
}

/* [bmi] device = cpu|cuda[:N] (device.h): the CPU, or the reason the
 * BMI cannot have the GPU it names. */
static int check_device(const char *config_file, const char *value)
{
	struct ss_device d;
	if (ss_device_parse(value, &d))
		return ss_error_input("%s: [bmi] device '%s': expected cpu, cuda or cuda:N (N from "
		                      "0 to 63)", config_file, value);
	char what[4200];
	snprintf(what, sizeof what, "%s: [bmi] device = %s", config_file, value);
	return ss_drive_check_device(&d, what, "the BMI");
}

/* The model config_file describes (above) into s. */
static int setup(struct bmi_state *s, const char *config_file)
{
	struct config cf = {.path = config_file};
	const int line = ini_parse(config_file, config_handler, &cf);
	int err = cf.err;
	if (!err && line < 0)
		err = ss_error_input("BMI initialize: cannot read '%s'", config_file);
	if (!err && !cf.bmi_section) {
		config_release(&cf);   /* a case file */
		return setup_case(s, config_file);
	}
	if (!err && line > 0)
		err = ss_error_input("%s:%d: not a line of an INI file", config_file, line);
	if (!err && cf.other_section)
		err = ss_error_input("%s: a BMI config has one section, [bmi] (a case file has "
		                     "none)", config_file);
	const char *case_name = config_get(&cf, "case"), *dem = config_get(&cf, "dem");
	const char *device = config_get(&cf, "device");
	if (!err && device)
		err = check_device(config_file, device);
	if (!err && !case_name == !dem)
		err = ss_error_input("%s: [bmi] needs case = CASE.ini or dem = DEM", config_file);
	if (!err && case_name) {
		char path[4096];
		if (cf.count > 1 + (device != NULL))
			err = ss_error_input("%s: [bmi] with case takes no other key but device: "
			                     "the case file says the rest", config_file);
		if (!err)
			err = config_path(&cf, case_name, path, sizeof path);
		if (!err)
			err = setup_case(s, path);
	} else if (!err) {
		err = setup_dem(s, &cf);
	}
	config_release(&cf);
	return err;
}

static int bmi_initialize(struct Bmi *self, const char *config_file)
{
	if (!self || self->data) {
		if (self)
			ss_error_input("BMI initialize: already initialized (finalize first)");
		return BMI_FAILURE;
	}
	if (!config_file)
		return ss_error_input("BMI initialize: no config file given"), BMI_FAILURE;
	struct bmi_state *s = ss_alloc(1, sizeof *s, "the BMI state");
	if (!s)
		return BMI_FAILURE;
	int err = setup(s, config_file);
	if (!err) {
		s->cells = s->st.grid.nx * s->st.grid.ny;
		s->rate = ss_alloc((size_t)s->cells, sizeof(double), "the BMI's deposition rate");
		s->rate_next = ss_alloc((size_t)s->cells, sizeof(double), "the BMI's deposition rate");
		if (!s->rate || !s->rate_next) {
			ss_free(s->rate);
			ss_free(s->rate_next);
			ss_stepper_release(&s->st);
			err = SS_ERR_FAIL;
		}
	}
	if (err) {
		ss_free(s->nodata);
		ss_free(s);
		return BMI_FAILURE;
	}
	self->data = s;
	return BMI_SUCCESS;
}

/* Advance to t (> the current time); BMI_FAILURE if the stepper stopped
 * short (a non-finite height, a vanished time step). */
static int advance_to(struct bmi_state *s, double t)
{
	const struct ss_advance_options o = {0};   /* no steady stop: driven */
	const enum ss_advance_end e = ss_stepper_advance(&s->st, t, &o);
	if (e == SS_ADVANCE_REACHED)
		return BMI_SUCCESS;
	ss_error_fail("BMI: the model stopped at t = %g s before %g s: %s", s->st.time, t,
	              e == SS_ADVANCE_NONFINITE ? "a height became non-finite"
	                                        : "its time step vanished");
	return BMI_FAILURE;
}

/* One time step: to the next multiple of output_every when the time is on
 * one (so k updates reach k * output_every as `sandslide run` does),
 * otherwise by output_every. */
static int bmi_update(struct Bmi *self)
{
	struct bmi_state *s = state(self);
	if (!s)
		return BMI_FAILURE;
	const double t = s->st.time;
	const double k = nearbyint(t / s->step);
	const double target = k * s->step == t ? (k + 1.0) * s->step : t + s->step;
	return advance_to(s, target);
}

static int bmi_update_until(struct Bmi *self, double then)
{
	struct bmi_state *s = state(self);
	if (!s || !isfinite(then) || then < s->st.time)
		return BMI_FAILURE;
	if (then == s->st.time)
		return BMI_SUCCESS;
	return advance_to(s, then);
}

static int bmi_finalize(struct Bmi *self)
{
	struct bmi_state *s = state(self);
	if (!s)
		return BMI_FAILURE;
	ss_stepper_release(&s->st);
	ss_free(s->rate);
	ss_free(s->rate_next);
	ss_free(s->nodata);
	ss_free(s);
	self->data = NULL;
	return BMI_SUCCESS;
}

/* ---- exchange items ----------------------------------------------------- */

static int bmi_get_component_name(struct Bmi *self, char *name)
{
	if (!state(self) || !name)
		return BMI_FAILURE;
	strcpy(name, "sandslide");
	return BMI_SUCCESS;
}

/* The names of the variables that are inputs (or outputs) of this model,
 * in the table's order, into names (NULL: only counted). */
static int list_vars(const struct bmi_state *s, int outputs, char **names)
{
	int n = 0;
	for (int v = 0; v < VAR_COUNT; v++) {
		if (!present(s, v) || !(outputs ? vars[v].output : vars[v].input))
			continue;
		if (names)
			strcpy(names[n], vars[v].name);
		n++;
	}
	return n;
}

static int bmi_get_input_item_count(struct Bmi *self, int *count)
{
	if (!state(self) || !count)
		return BMI_FAILURE;
	*count = list_vars(state(self), 0, NULL);
	return BMI_SUCCESS;
}

static int bmi_get_output_item_count(struct Bmi *self, int *count)
{
	if (!state(self) || !count)
		return BMI_FAILURE;
	*count = list_vars(state(self), 1, NULL);
	return BMI_SUCCESS;
}

/* names[k] must be room for BMI_MAX_VAR_NAME bytes, for each name */
static int var_names(struct Bmi *self, int outputs, char **names)
{
	const struct bmi_state *s = state(self);
	if (!s || !names)
		return BMI_FAILURE;
	const int n = list_vars(s, outputs, NULL);
	for (int k = 0; k < n; k++)
		if (!names[k])
			return BMI_FAILURE;
	list_vars(s, outputs, names);
	return BMI_SUCCESS;
}

static int bmi_get_input_var_names(struct Bmi *self, char **names)
{
	return var_names(self, 0, names);
}

static int bmi_get_output_var_names(struct Bmi *self, char **names)
{
	return var_names(self, 1, names);
}

/* ---- variable information ----------------------------------------------- */

static int bmi_get_var_grid(struct Bmi *self, const char *name, int *grid)
{
	const struct var *v = find_var_of(state(self), name);
	if (!state(self) || !v || !grid)
		return BMI_FAILURE;
	*grid = v->grid;
	return BMI_SUCCESS;
}

/* text into out for a known variable */
static int var_text(struct Bmi *self, const char *name, char *out, const char *text)
{
	if (!state(self) || !find_var_of(state(self), name) || !out)
		return BMI_FAILURE;
	strcpy(out, text);
	return BMI_SUCCESS;
}

static int bmi_get_var_type(struct Bmi *self, const char *name, char *type)
{
	return var_text(self, name, type, "double");
}

static int bmi_get_var_units(struct Bmi *self, const char *name, char *units)
{
	const struct var *v = find_var_of(state(self), name);
	return var_text(self, name, units, v ? v->units : "");
}

static int bmi_get_var_location(struct Bmi *self, const char *name, char *location)
{
	return var_text(self, name, location, "node");
}

static int bmi_get_var_itemsize(struct Bmi *self, const char *name, int *size)
{
	if (!state(self) || !find_var_of(state(self), name) || !size)
		return BMI_FAILURE;
	*size = (int)sizeof(double);
	return BMI_SUCCESS;
}

static int bmi_get_var_nbytes(struct Bmi *self, const char *name, int *nbytes)
{
	struct bmi_state *s = state(self);
	const struct var *v = find_var_of(state(self), name);
	if (!s || !v || !nbytes)
		return BMI_FAILURE;
	*nbytes = (v->grid == 0 ? s->cells : 1) * (int)sizeof(double);
	return BMI_SUCCESS;
}

/* ---- time ----------------------------------------------------------------- */

static int time_value(struct Bmi *self, double *out, int which)
{
	struct bmi_state *s = state(self);
	if (!s || !out)
		return BMI_FAILURE;
	*out = which == 0 ? s->st.time : which == 1 ? 0.0 : which == 2 ? s->end : s->step;
	return BMI_SUCCESS;
}

static int bmi_get_current_time(struct Bmi *self, double *t) { return time_value(self, t, 0); }
static int bmi_get_start_time(struct Bmi *self, double *t) { return time_value(self, t, 1); }
static int bmi_get_end_time(struct Bmi *self, double *t) { return time_value(self, t, 2); }
static int bmi_get_time_step(struct Bmi *self, double *t) { return time_value(self, t, 3); }

static int bmi_get_time_units(struct Bmi *self, char *units)
{
	if (!state(self) || !units)
		return BMI_FAILURE;
	strcpy(units, "s");
	return BMI_SUCCESS;
}

/* ---- getters and setters -------------------------------------------------- */

/* The halo index of the flat [y][x] index c. */
static ptrdiff_t at_of(const struct ss_stepper *st, int c)
{
	return ss_grid_index(&st->grid, c % st->grid.nx, c / st->grid.nx);
}

/* The diagnostic v (not the elevation) of the current state. */
static double diagnostic(struct bmi_state *s, const struct var *v)
{
	struct ss_diagnostics d;
	ss_stepper_diagnostics(&s->st, &d);
	switch (v - vars) {
	case VAR_VOLUME: return d.volume;
	case VAR_INFLOW: return d.inflow;
	case VAR_OUTFLOW: return d.outflow;
	case VAR_EXTERNAL: return d.external;
	default: return d.max_slope_deg;
	}
}

/* The grid-0 variable v at the flat [y][x] index c: the bedrock is NaN
 * where no sand can lie (walls, open cells: the stepper's -infinity); the
 * elevation is NaN on walls and cells without data, as the .h5 output and
 * Python's relax give it: the stepper holds 0 or the open level there,
 * which a coupled model would take for a cliff (doc/bmi.md). */
static double grid_value(const struct bmi_state *s, const struct var *v, int c)
{
	switch (v - vars) {
	case VAR_RATE: return s->rate[c];
	case VAR_ANGLE: {   /* the angle its faces take; none on a wall */
		const ptrdiff_t at = at_of(&s->st, c);
		if (ss_cell_type_get(s->st.cell_types, at) == SS_CELL_WALL)
			return NAN;
		return s->st.material ? s->st.materials[s->st.material[at]].repose_angle_deg
		                      : s->st.closure.repose_angle_deg;
	}
	case VAR_MOVING: {   /* hysteresis: 1 where sand moves (stepper.h) */
		const ptrdiff_t at = at_of(&s->st, c);
		if (ss_cell_type_get(s->st.cell_types, at) != SS_CELL_FLOW)
			return NAN;
		return s->st.material[at] & 1 ? 1.0 : 0.0;
	}
	case VAR_BEDROCK: {
		const double b = s->st.bedrock[at_of(&s->st, c)];
		return isinf(b) ? NAN : b;
	}
	default: {
		const ptrdiff_t at = at_of(&s->st, c);
		if ((s->nodata && s->nodata[c]) ||
		    ss_cell_type_get(s->st.cell_types, at) == SS_CELL_WALL)
			return NAN;
		return s->st.height[at];
	}
	}
}

static int bmi_get_value(struct Bmi *self, const char *name, void *dest)
{
	struct bmi_state *s = state(self);
	const struct var *v = find_var_of(state(self), name);
	if (!s || !v || !dest)
		return BMI_FAILURE;
	if (v->grid == 1) {
		*(double *)dest = diagnostic(s, v);
		return BMI_SUCCESS;
	}
	double *out = dest;
	for (int c = 0; c < s->cells; c++)
		out[c] = grid_value(s, v, c);
	return BMI_SUCCESS;
}

/* The heights live with a halo ring: no contiguous [y][x] array to point
 * at. */
static int bmi_get_value_ptr(struct Bmi *self, const char *name, void **dest_ptr)
{
	(void)self, (void)name, (void)dest_ptr;
	return BMI_FAILURE;
}

/* inds[0..count-1] all in [0, cells), count >= 0 */
static int indices_ok(const struct bmi_state *s, const int *inds, int count)
{
	if (count < 0 || (count > 0 && !inds))
		return 0;
	for (int k = 0; k < count; k++)
		if (inds[k] < 0 || inds[k] >= s->cells)
			return 0;
	return 1;
}

static int bmi_get_value_at_indices(struct Bmi *self, const char *name, void *dest, int *inds,
                                    int count)
{
	struct bmi_state *s = state(self);
	const struct var *v = find_var_of(state(self), name);
	if (!s || !v || (count > 0 && !dest))
		return BMI_FAILURE;
	double *out = dest;
	if (v->grid == 1) {   /* a scalar: index 0 only */
		if (count < 0 || (count > 0 && !inds))
			return BMI_FAILURE;
		for (int k = 0; k < count; k++)
			if (inds[k] != 0)
				return BMI_FAILURE;
		const double x = count > 0 ? diagnostic(s, v) : 0.0;
		for (int k = 0; k < count; k++)
			out[k] = x;
		return BMI_SUCCESS;
	}
	if (!indices_ok(s, inds, count))
		return BMI_FAILURE;
	for (int k = 0; k < count; k++)
		out[k] = grid_value(s, v, inds[k]);
	return BMI_SUCCESS;
}

/* Set the flow cells among inds[0..count-1] (NULL: every cell in order)
 * to src[0..count-1], after checking every value; the volume added is
 * booked in the stepper's external ledger.  An index given twice is
 * written twice, in order: the last value stays, and each write's change
 * is counted, so the sum is the net change. */
static int set_heights(struct bmi_state *s, const int *inds, int count, const double *src)
{
	struct ss_stepper *st = &s->st;
	for (int k = 0; k < count; k++) {
		const ptrdiff_t at = at_of(st, inds ? inds[k] : k);
		if (ss_cell_type_get(st->cell_types, at) != SS_CELL_FLOW)
			continue;
		if (!isfinite(src[k])) {
			ss_error_input("BMI set_value: " ELEVATION " item %d is not finite", k);
			return BMI_FAILURE;
		}
		if (st->bedrock && src[k] < st->bedrock[at]) {
			ss_error_input("BMI set_value: " ELEVATION " item %d, %g m, is below the "
			               "bedrock, %g m", k, src[k], st->bedrock[at]);
			return BMI_FAILURE;
		}
	}
	double added = 0.0;
	for (int k = 0; k < count; k++) {
		const ptrdiff_t at = at_of(st, inds ? inds[k] : k);
		if (ss_cell_type_get(st->cell_types, at) != SS_CELL_FLOW)
			continue;
		added += src[k] - st->height[at];
		st->height[at] = src[k];
	}
	ss_stepper_book_external(st, added * st->grid.dx * st->grid.dy);
	ss_stepper_heights_changed(st);
	return BMI_SUCCESS;
}

/* The deposition rate at inds (NULL: every cell) becomes src; the stepper
 * takes the whole field (ss_stepper_set_rate_field checks it: finite, not
 * negative over a bedrock).  Refused: the field is as it was. */
static int set_rate(struct bmi_state *s, const int *inds, int count, const double *src)
{
	memcpy(s->rate_next, s->rate, (size_t)s->cells * sizeof(double));
	for (int k = 0; k < count; k++)
		s->rate_next[inds ? inds[k] : k] = src[k];
	if (ss_stepper_set_rate_field(&s->st, s->rate_next))
		return BMI_FAILURE;
	double *taken = s->rate_next;
	s->rate_next = s->rate;
	s->rate = taken;
	return BMI_SUCCESS;
}

/* The repose angle at inds (NULL: every cell) becomes src
 * (ss_materials_change_angles checks it: degrees in (0, 90) where sand
 * lies).  Refused: the angles are as they were. */
static int set_angles(struct bmi_state *s, const int *inds, int count, const double *src)
{
	double *angle = ss_alloc((size_t)s->cells, sizeof *angle, "the BMI's repose angles");
	if (!angle)
		return BMI_FAILURE;
	for (int c = 0; c < s->cells; c++)
		angle[c] = grid_value(s, &vars[VAR_ANGLE], c);
	for (int k = 0; k < count; k++)
		angle[inds ? inds[k] : k] = src[k];
	const int err = ss_materials_change_angles(&s->st, angle, "BMI set_value: " ANGLE);
	ss_free(angle);
	return err ? BMI_FAILURE : BMI_SUCCESS;
}

/* Set input variable v at inds (NULL: every cell) to src. */
static int set_input(struct bmi_state *s, const struct var *v, const int *inds, int count,
                     const double *src)
{
	switch (v - vars) {
	case VAR_RATE: return set_rate(s, inds, count, src);
	case VAR_ANGLE: return set_angles(s, inds, count, src);
	default: return set_heights(s, inds, count, src);
	}
}

/* The input variable called name: elevation, rate or angle, else NULL. */
static const struct var *find_input(const struct bmi_state *s, const char *name)
{
	const struct var *v = find_var_of(s, name);
	if (v && !v->input) {
		ss_error_input("BMI set_value: %s is an output only", name);
		return NULL;
	}
	return v;
}

static int bmi_set_value(struct Bmi *self, const char *name, void *src)
{
	struct bmi_state *s = state(self);
	const struct var *v = find_input(s, name);
	if (!s || !v || !src)
		return BMI_FAILURE;
	return set_input(s, v, NULL, s->cells, src);
}

static int bmi_set_value_at_indices(struct Bmi *self, const char *name, int *inds, int count,
                                    void *src)
{
	struct bmi_state *s = state(self);
	const struct var *v = find_input(s, name);
	if (!s || !v || (count > 0 && !src) || !indices_ok(s, inds, count))
		return BMI_FAILURE;
	return set_input(s, v, inds, count, src);
}

/* ---- grid ----------------------------------------------------------------- */

/* Grid 0: the raster; grid 1: a scalar (the diagnostics). */
static int bmi_get_grid_rank(struct Bmi *self, int grid, int *rank)
{
	if (!state(self) || (grid != 0 && grid != 1) || !rank)
		return BMI_FAILURE;
	*rank = grid == 0 ? 2 : 0;
	return BMI_SUCCESS;
}

static int bmi_get_grid_size(struct Bmi *self, int grid, int *size)
{
	struct bmi_state *s = state(self);
	if (!s || (grid != 0 && grid != 1) || !size)
		return BMI_FAILURE;
	*size = grid == 0 ? s->cells : 1;
	return BMI_SUCCESS;
}

static int bmi_get_grid_type(struct Bmi *self, int grid, char *type)
{
	if (!state(self) || (grid != 0 && grid != 1) || !type)
		return BMI_FAILURE;
	strcpy(type, grid == 0 ? "uniform_rectilinear" : "scalar");
	return BMI_SUCCESS;
}

static int bmi_get_grid_shape(struct Bmi *self, int grid, int *shape)
{
	struct bmi_state *s = state(self);
	if (!s || grid != 0 || !shape)
		return BMI_FAILURE;
	shape[0] = s->st.grid.ny;
	shape[1] = s->st.grid.nx;
	return BMI_SUCCESS;
}

static int bmi_get_grid_spacing(struct Bmi *self, int grid, double *spacing)
{
	struct bmi_state *s = state(self);
	if (!s || grid != 0 || !spacing)
		return BMI_FAILURE;
	spacing[0] = s->st.grid.dy;
	spacing[1] = s->st.grid.dx;
	return BMI_SUCCESS;
}

/* The centre of cell (0, 0), [y, x]: the HDF5 output's y[0] and x[0]. */
static int bmi_get_grid_origin(struct Bmi *self, int grid, double *origin)
{
	struct bmi_state *s = state(self);
	if (!s || grid != 0 || !origin)
		return BMI_FAILURE;
	const struct ss_grid *g = &s->st.grid;
	origin[0] = g->origin_y + 0.5 * g->dy;
	origin[1] = g->origin_x + 0.5 * g->dx;
	return BMI_SUCCESS;
}

/* Not a grid sandslide has: rectilinear, curvilinear, unstructured. */
static int no_grid_doubles(struct Bmi *self, int grid, double *v)
{
	(void)self, (void)grid, (void)v;
	return BMI_FAILURE;
}

static int no_grid_ints(struct Bmi *self, int grid, int *v)
{
	(void)self, (void)grid, (void)v;
	return BMI_FAILURE;
}

/* ---- registration --------------------------------------------------------- */

struct Bmi *ss_bmi_register(struct Bmi *m)
{
	if (!m)
		return NULL;
	m->data = NULL;
	m->initialize = bmi_initialize;
	m->update = bmi_update;
	m->update_until = bmi_update_until;
	m->finalize = bmi_finalize;
	m->get_component_name = bmi_get_component_name;
	m->get_input_item_count = bmi_get_input_item_count;
	m->get_output_item_count = bmi_get_output_item_count;
	m->get_input_var_names = bmi_get_input_var_names;
	m->get_output_var_names = bmi_get_output_var_names;
	m->get_var_grid = bmi_get_var_grid;
	m->get_var_type = bmi_get_var_type;
	m->get_var_units = bmi_get_var_units;
	m->get_var_itemsize = bmi_get_var_itemsize;
	m->get_var_nbytes = bmi_get_var_nbytes;
	m->get_var_location = bmi_get_var_location;
	m->get_current_time = bmi_get_current_time;
	m->get_start_time = bmi_get_start_time;
	m->get_end_time = bmi_get_end_time;
	m->get_time_units = bmi_get_time_units;
	m->get_time_step = bmi_get_time_step;
	m->get_value = bmi_get_value;
	m->get_value_ptr = bmi_get_value_ptr;
	m->get_value_at_indices = bmi_get_value_at_indices;
	m->set_value = bmi_set_value;
	m->set_value_at_indices = bmi_set_value_at_indices;
	m->get_grid_rank = bmi_get_grid_rank;
	m->get_grid_size = bmi_get_grid_size;
	m->get_grid_type = bmi_get_grid_type;
	m->get_grid_shape = bmi_get_grid_shape;
	m->get_grid_spacing = bmi_get_grid_spacing;
	m->get_grid_origin = bmi_get_grid_origin;
	m->get_grid_x = no_grid_doubles;
	m->get_grid_y = no_grid_doubles;
	m->get_grid_z = no_grid_doubles;
	m->get_grid_node_count = no_grid_ints;
	m->get_grid_edge_count = no_grid_ints;
	m->get_grid_face_count = no_grid_ints;
	m->get_grid_edge_nodes = no_grid_ints;
	m->get_grid_face_edges = no_grid_ints;
	m->get_grid_face_nodes = no_grid_ints;
	m->get_grid_nodes_per_face = no_grid_ints;
	return m;
}

struct Bmi *ss_bmi_create(void)
{
	struct Bmi *m = ss_alloc(1, sizeof *m, "a BMI model");
	return m ? ss_bmi_register(m) : NULL;
}

void ss_bmi_destroy(struct Bmi *m)
{
	if (!m)
		return;
	if (m->data)
		bmi_finalize(m);
	ss_free(m);
}
