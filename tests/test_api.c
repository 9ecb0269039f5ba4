/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_api.c - the entry points for foreign callers (options objects,
 * option.h; relax_report.c, run_report.c): options set by name are
 * checked as the command line checks them and own their text; the JSON formatters say when a buffer is too
 * small and escape what JSON cannot hold; ss_relax_heights gives the bits
 * of ss_relax_run on the same DEM file; a case runs through
 * ss_run_case_json.  Under `make SANITIZE=1 test` it also shows that the
 * options free what they own.
 *
 * Files go to a mkdtemp folder, removed at the end.
 */
#include "check.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sandslide/dem.h"
#include "sandslide/error.h"
#include "sandslide/relax.h"
#include "sandslide/run.h"

/* A steep pile off-centre on a ramp, rows south first, a hole of no data. */
enum { NX = 24, NY = 20 };
static void pile(double *h)
{
	for (int j = 0; j < NY; j++) {
		for (int i = 0; i < NX; i++) {
			const double d = hypot(i - 15.0, j - 6.0);
			h[j * NX + i] = 0.1 * j + fmax(0.0, 8.0 - 1.7 * d);
		}
	}
	h[14 * NX + 3] = h[14 * NX + 4] = NAN;
}

static void relax_options_are_checked_as_the_cli_checks_them(void)
{
	struct ss_relax_options *o = ss_option_object_create(&ss_relax_option_table);
	CHECK(o != NULL, "create");
	if (!o)
		return;
	CHECK(o->model.angle_deg == 35.0 && o->model.nu == 1.0 && o->model.steady_tol == 1e-9 &&
	      isnan(o->model.max_time) && o->sand_shape.kind == SS_SHAPE_NONE, "the table's defaults");
	CHECK(ss_option_object_set(o, "angle", "30") == SS_OK && o->model.angle_deg == 30.0, "angle");
	CHECK(ss_option_object_set(o, "angle", "95") == SS_ERR_INPUT, "angle 95 refused");
	CHECK(!strcmp(ss_error_last_message(), "angle '95': expected degrees in (0, 90), or a raster of them"), "%s",
	      ss_error_last_message());
	CHECK(o->model.angle_deg == 30.0, "a refused value leaves the option as it was");
	CHECK(ss_option_object_set(o, "angle", "30x") == SS_ERR_INPUT, "trailing junk refused");
	CHECK(ss_option_object_set(o, "max_time", "5") == SS_OK && o->model.max_time == 5.0, "max_time");
	CHECK(ss_option_object_set(o, "max-time", "6") == SS_OK && o->model.max_time == 6.0, "max-time");
	CHECK(ss_option_object_set(o, "closure", "casson") == SS_OK &&
	      o->model.closure == SS_CLOSURE_CASSON, "closure");
	CHECK(ss_option_object_set(o, "closure", "bogus") == SS_ERR_INPUT, "bogus closure");
	CHECK(!strcmp(ss_error_last_message(), "closure 'bogus': expected " SS_CLOSURE_NAMES),
	      "%s", ss_error_last_message());
	CHECK(ss_option_object_set(o, "sides", "open") == SS_OK && o->sides == SS_SIDE_OPEN,
	      "sides");
	CHECK(ss_option_object_set(o, "sides", "periodic") == SS_ERR_INPUT, "periodic refused");
	CHECK(ss_option_object_set(o, "nodata", "wall") == SS_OK &&
	      o->nodata_type == SS_CELL_WALL, "nodata");
	CHECK(ss_option_object_set(o, "integrator", "rkl2") == SS_OK &&
	      o->model.integrator == SS_INTEGRATOR_RKL2, "integrator");
	CHECK(ss_option_object_set(o, "threads", "3") == SS_OK && o->job.threads == 3, "threads");
	CHECK(ss_option_object_set(o, "threads", "2.5") == SS_ERR_INPUT, "threads 2.5 refused");
	CHECK(ss_option_object_set(o, "dx", "0.25") == SS_OK && o->read.cellsize == 0.25, "dx");
	CHECK(ss_option_object_set(o, "force", "1") == SS_OK && o->job.force == 1, "force");
	CHECK(ss_option_object_set(o, "force", "yes") == SS_ERR_INPUT, "force yes refused");
	CHECK(ss_option_object_set(o, "tol", "") == SS_ERR_INPUT, "an empty value refused");
	CHECK(ss_option_object_set(o, "bogus", "1") == SS_ERR_INPUT, "unknown key");
	CHECK(!strncmp(ss_error_last_message(), "unknown relax option 'bogus': expected one of ",
	               46) && strstr(ss_error_last_message(), ", angle, ") &&
	      strstr(ss_error_last_message(), ", add-sand, "), "%s", ss_error_last_message());
	CHECK(ss_option_object_set(o, "add-sand", "disk=5,6,2") == SS_OK &&
	      o->sand_shape.kind == SS_SHAPE_DISK && o->sand_shape.v[2] == 2.0, "add-sand");
	CHECK(ss_option_object_set(o, "add-sand", "disk=5,6,0") == SS_ERR_INPUT &&
	      o->sand_shape.v[2] == 2.0, "add-sand with R = 0 refused, the shape kept");

	char path[32] = "first.asc";
	CHECK(ss_option_object_set(o, "output", path) == SS_OK, "output");
	strcpy(path, "changed");
	CHECK(o->job.output && !strcmp(o->job.output, "first.asc"), "the text is copied: %s", o->job.output);
	CHECK(ss_option_object_set(o, "output", "second.asc") == SS_OK &&
	      !strcmp(o->job.output, "second.asc"), "set again (the first copy freed)");
	ss_option_object_destroy(o);
	ss_option_object_destroy(NULL);
}

static void report_json_fits_or_says_so(void)
{
	struct ss_relax_report r;
	memset(&r, 0, sizeof r);
	ss_model_options_init(&r.model);
	r.input = "a \"quoted\" \\ path\n";
	r.nx = 3;
	r.steady = 1;
	r.integrator = "euler";
	r.max_slope_after_deg = NAN;
	snprintf(r.output, sizeof r.output, "out.asc");
	char buf[2048], tiny[40];
	CHECK(ss_relax_report_json(&r, buf, sizeof buf) == SS_OK, "formatted");
	CHECK(strstr(buf, "\"input\": \"a \\\"quoted\\\" \\\\ path\\u000a\",") != NULL,
	      "quotes, backslash and newline escaped: %s", buf);
	CHECK(strstr(buf, "\"max_slope_after_deg\": null\n}\n") != NULL, "NaN is null: %s", buf);
	CHECK(strstr(buf, "\"steady\": true, \"end\": ") && strstr(buf, "\"tol\": 1e-09,"),
	      "the shortest text: %s", buf);
	CHECK(ss_relax_report_json(&r, tiny, sizeof tiny) == SS_ERR_INPUT, "too small");
	CHECK(strstr(ss_error_last_message(), "the buffer has 40") != NULL, "%s",
	      ss_error_last_message());
	CHECK(strlen(tiny) == sizeof tiny - 1, "a cut report is still a string");
}

/* The JSON's line `"key": value` for key, to compare reports. */
static const char *field(const char *json, const char *key)
{
	static char buf[2][128];
	static int k;
	char quoted[64];
	k ^= 1;
	snprintf(quoted, sizeof quoted, "\"%s\": ", key);
	const char *p = strstr(json, quoted);
	if (!p)
		return "(missing)";
	p += strlen(quoted);
	const size_t n = strcspn(p, ",\n");
	snprintf(buf[k], sizeof buf[k], "%.*s", (int)n, p);
	return buf[k];
}

static void relax_heights_gives_the_bits_of_a_relaxed_file(void)
{
	double h[NX * NY], got[NX * NY];
	pile(h);
	/* the file: north row first, "%.17g", -9999 for no data */
	FILE *f = fopen(check_file("pile.asc"), "w");
	if (!f)
		exit(2);
	fprintf(f, "ncols %d\nnrows %d\nxllcorner 0\nyllcorner 0\ncellsize 0.5\n"
	        "NODATA_value -9999\n", NX, NY);
	for (int j = NY - 1; j >= 0; j--)
		for (int i = 0; i < NX; i++)
			fprintf(f, "%.17g%c", isnan(h[j * NX + i]) ? -9999.0 : h[j * NX + i],
			        i + 1 < NX ? ' ' : '\n');
	fclose(f);

	char dem[512], out[512], report[512];
	snprintf(dem, sizeof dem, "%s", check_file("pile.asc"));
	snprintf(out, sizeof out, "%s", check_file("out.asc"));
	snprintf(report, sizeof report, "%s", check_file("report.json"));
	struct ss_relax_options o;
	ss_relax_options_init(&o);
	o.dem = dem;
	o.job.output = out;
	o.report = report;
	o.job.threads = 1;
	struct ss_relax_report r;
	struct ss_raster want;
	int err = ss_relax_run(&o, &r);
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (!err)
		CHECK((err = ss_dem_read(out, NULL, NULL, &want)) == SS_OK, "%s",
		      ss_error_last_message());
	if (err)
		return;

	struct ss_relax_options *p = ss_option_object_create(&ss_relax_option_table);
	char json[4096];
	CHECK(p && ss_option_object_set(p, "threads", "1") == SS_OK, "threads");
	CHECK(ss_relax_heights(p, NX, NY, 0.5, 0.5, h, NULL, got, json, sizeof json) == SS_OK,
	      "%s", ss_error_last_message());
	int differ = 0;
	for (int m = 0; m < NX * NY; m++) {
		const int hole = want.nodata && want.nodata[m];
		differ += hole ? !isnan(got[m]) : memcmp(&got[m], &want.values[m], sizeof got[m]) != 0;
	}
	CHECK(differ == 0, "%d of %d cells differ from ss_relax_run's file", differ, NX * NY);
	CHECK(isnan(got[14 * NX + 3]) && isnan(h[14 * NX + 3]), "no data stays NaN");

	char file[4096] = "";
	f = fopen(report, "r");
	if (f) {
		file[fread(file, 1, sizeof file - 1, f)] = '\0';
		fclose(f);
	}
	const char *same[] = {"nx", "ny", "dx", "dy", "closure", "steady", "steps", "time",
	                      "cells_moved", "volume_moved", "volume_before", "volume_after",
	                      "outflow", "max_slope_before_deg", "max_slope_after_deg"};
	for (size_t k = 0; k < sizeof same / sizeof *same; k++)
		CHECK(!strcmp(field(json, same[k]), field(file, same[k])), "%s: %s, the file's %s",
		      same[k], field(json, same[k]), field(file, same[k]));
	CHECK(!strcmp(field(json, "input"), "\"(array)\""), "%s", field(json, "input"));

	/* in place, and refusals */
	CHECK(ss_relax_heights(p, NX, NY, 0.5, 0.5, h, NULL, h, NULL, 0) == SS_OK, "in place");
	int same_bits = 1;
	for (int m = 0; m < NX * NY; m++)
		same_bits &= isnan(got[m]) ? isnan(h[m]) : !memcmp(&got[m], &h[m], sizeof h[m]);
	CHECK(same_bits, "relaxed over its input: the same bits");
	h[5] = INFINITY;
	CHECK(ss_relax_heights(p, NX, NY, 0.5, 0.5, h, NULL, got, NULL, 0) == SS_ERR_INPUT,
	      "an infinite height refused");
	CHECK(strstr(ss_error_last_message(), "cell (5, 0)") != NULL, "%s",
	      ss_error_last_message());
	CHECK(ss_relax_heights(p, 0, NY, 0.5, 0.5, h, NULL, got, NULL, 0) == SS_ERR_INPUT,
	      "no columns refused");
	CHECK(ss_relax_heights(p, NX, NY, 0.5, -1.0, h, NULL, got, NULL, 0) == SS_ERR_INPUT,
	      "dy < 0 refused");
	ss_option_object_destroy(p);
	ss_raster_release(&want);
	remove(dem);
	remove(out);
	remove(report);
}

static void bedrock_in_memory_holds_the_sand(void)
{
	double h[NX * NY], rock[NX * NY], got[NX * NY];
	pile(h);
	for (int m = 0; m < NX * NY; m++)
		rock[m] = isnan(h[m]) ? NAN : h[m] - 0.5;   /* NaN only under no data */
	struct ss_relax_options *p = ss_option_object_create(&ss_relax_option_table);
	CHECK(p && ss_option_object_set(p, "threads", "1") == SS_OK, "threads");
	CHECK(ss_relax_heights(p, NX, NY, 0.5, 0.5, h, rock, got, NULL, 0) == SS_OK, "%s",
	      ss_error_last_message());
	double below = 0.0;
	for (int m = 0; m < NX * NY; m++)
		if (!isnan(h[m]))
			below = fmax(below, rock[m] - got[m]);
	CHECK(below <= 1e-12, "sand %g m below the bedrock", below);
	rock[2] = NAN;
	CHECK(ss_relax_heights(p, NX, NY, 0.5, 0.5, h, rock, got, NULL, 0) == SS_ERR_INPUT,
	      "NaN bedrock under sand refused");
	ss_option_object_destroy(p);
}

static void run_options_and_a_case(void)
{
	struct ss_run_options *o = ss_option_object_create(&ss_run_option_table);
	CHECK(o != NULL, "create");
	if (!o)
		return;
	check_write_file(check_file("tiny.ini"), "[grid]\nnx = 12\nny = 10\ndx = 0.1\n\n[model]\n"
	           "closure = coulomb\nrepose_angle = 35\nnu = 0.1\n\n[time]\nend = 1\n"
	           "output_every = 0.5\n\n[boundary]\nwest = wall\neast = open\nsouth = wall\n"
	           "north = wall\n\n[initial]\ntype = flat\nheight = 0.2\n");
	CHECK(ss_option_object_set(o, "case", check_file("tiny.ini")) == SS_OK, "case");
	CHECK(ss_option_object_set(o, "output", check_file("tiny.h5")) == SS_OK, "output");
	for (int k = 0; k < 20; k++)    /* more than the first allocation */
		CHECK(ss_option_object_set(o, "set", k % 2 ? "time.end=0.5" : "time.end=2") == SS_OK,
		      "set %d", k);
	CHECK(o->overrides.count == 20 && !strcmp(o->overrides.items[19], "time.end=0.5"), "overrides");
	CHECK(ss_option_object_set(o, "tile", "8x4") == SS_OK && o->job.tile[0] == 8 &&
	      o->job.tile[1] == 4, "tile");
	CHECK(ss_option_object_set(o, "set", "time.end") == SS_ERR_INPUT, "a set without '='");
	CHECK(ss_option_object_set(o, "unset", "time.end=1") == SS_ERR_INPUT, "an unset with '='");
	CHECK(o->overrides.count == 20, "refused overrides are not kept");
	CHECK(ss_option_object_set(o, "tile", "8by4") == SS_ERR_INPUT, "bad tile");
	CHECK(!strcmp(ss_error_last_message(), "tile '8by4': expected NXxNY, e.g. 256x64"), "%s",
	      ss_error_last_message());
	CHECK(ss_option_object_set(o, "deflate", "10") == SS_ERR_INPUT, "deflate 10");
	CHECK(ss_option_object_set(o, "threads", "1") == SS_OK && o->job.threads == 1, "threads");
	CHECK(ss_option_object_set(o, "reference_kernel", "1") == SS_OK && o->reference_kernel,
	      "reference-kernel");
	char json[8192];
	CHECK(ss_run_case_json(o, json, sizeof json) == SS_OK, "%s", ss_error_last_message());
	CHECK(!strcmp(field(json, "end"), "\"done\"") && !strcmp(field(json, "time"), "0.5") &&
	      !strcmp(field(json, "snapshots"), "2"), "%s", json);
	CHECK(ss_run_case_json(o, json, sizeof json) == SS_ERR_INPUT, "an existing output");
	CHECK(ss_option_object_set(o, "force", "1") == SS_OK &&
	      ss_run_case_json(o, json, sizeof json) == SS_OK, "--force");
	ss_option_object_destroy(o);
	ss_option_object_destroy(NULL);
	remove(check_file("tiny.h5"));
	remove(check_file("tiny.xmf"));
	remove(check_file("tiny.h5.aux.xml"));   /* GDAL's sidecar */
	remove(check_file("tiny.ini"));
}

int main(void)
{
	if (check_scratch_make("ss_test_api"))
		return 2;
	ss_error_set_quiet(1);   /* the checks read ss_error_last_message() */
	RUN(relax_options_are_checked_as_the_cli_checks_them);
	RUN(report_json_fits_or_says_so);
	RUN(relax_heights_gives_the_bits_of_a_relaxed_file);
	RUN(bedrock_in_memory_holds_the_sand);
	RUN(run_options_and_a_case);
	rmdir(check_scratch());
	return check_report();
}
