/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_case.c - the command line's overrides of a case (case.h): an
 * override wins, a key of the file it makes redundant is dropped with a
 * note, the same conflict inside the file (or between two overrides) is an
 * error naming where, and --unset removes keys and sections.
 */
#include "check.h"

#include <math.h>
#include <string.h>

#include "sandslide/case.h"
#include "sandslide/error.h"

static const char steady_cone[] =
	"[grid]\nnx = 20\nny = 20\ndx = 0.1\n"
	"[model]\nrepose_angle = 35\nnu = 0.1\n"
	"[time]\nend = steady\noutput_every = 10\nmax_time = 600\n"
	"[initial]\ntype = cone\ncenter = 1 1\nradius = 0.5\nangle = 50\n"
	"[source pour]\nrect = 0.2 0.2 0.6 0.6\nrate = 1e-3\nstop = 5\n";

static const char bingham_layer[] =
	"[grid]\nnx = 20\nny = 20\ndx = 0.1\n"
	"[model]\nclosure = bingham\nrepose_angle = 35\ndelta = 0.01\ndensity = 1600\n"
	"viscosity = 0.1\n"
	"[time]\nend = 10\noutput_every = 1\n";

static int parse(struct ss_case *c, const char *text, const char *const *sets, int n)
{
	return ss_case_parse(c, "dir/case.ini", text, sets, n);
}

/* some note of c holds every one of the words */
static int noted(const struct ss_case *c, const char *a, const char *b)
{
	for (int k = 0; k < c->note_count; k++)
		if (strstr(c->notes[k], a) && strstr(c->notes[k], b))
			return 1;
	return 0;
}

static void an_end_drops_the_files_max_time(void)
{
	struct ss_case c;
	const char *set[] = {"time.end=5"};
	CHECK(parse(&c, steady_cone, set, 1) == SS_OK, "%s", ss_error_last_message());
	CHECK(!c.steady && c.end == 5.0 && isnan(c.model.max_time), "end %g, max_time %g", c.end,
	      c.model.max_time);
	CHECK(c.note_count == 1 && noted(&c, "max_time (dir/case.ini:11)", "--set time.end=5"),
	      "the note names the key, its line and the override: %s", c.notes[0]);
	ss_case_release(&c);

	/* the same conflict in the file is the file's mistake */
	static const char both[] = "[grid]\nnx = 4\nny = 4\ndx = 1\n[model]\nrepose_angle = 35\n"
	                           "nu = 1\n[time]\nend = 10\noutput_every = 1\nmax_time = 5\n";
	CHECK(parse(&c, both, NULL, 0) == SS_ERR_INPUT &&
	      strstr(ss_error_last_message(), "dir/case.ini:11: [time] max_time applies"),
	      "%s", ss_error_last_message());
	ss_case_release(&c);

	/* and an override that adds the conflict is blamed, not the file */
	const char *max[] = {"time.end=10", "time.max_time=5"};
	CHECK(parse(&c, steady_cone, max, 2) == SS_ERR_INPUT &&
	      strstr(ss_error_last_message(), "--set time.max_time=5: [time] max_time applies"),
	      "%s", ss_error_last_message());
	ss_case_release(&c);
}

static void nu_and_the_sliding_layer_replace_each_other(void)
{
	struct ss_case c;
	const char *nu[] = {"model.nu=0.25"};
	CHECK(parse(&c, bingham_layer, nu, 1) == SS_OK, "%s", ss_error_last_message());
	CHECK(c.model.nu == 0.25 && isnan(c.model.layer.delta) && isnan(c.model.layer.viscosity), "nu %g, delta %g",
	      c.model.nu, c.model.layer.delta);
	CHECK(c.note_count == 3 && noted(&c, "delta", "--set model.nu=0.25") &&
	      noted(&c, "density", "gives nu") && noted(&c, "viscosity", "gives nu"),
	      "%d notes: %s", c.note_count, c.notes[0]);
	ss_case_release(&c);

	static const char with_nu[] = "[grid]\nnx = 4\nny = 4\ndx = 1\n[model]\nclosure = casson\n"
	                              "repose_angle = 35\nnu = 1\n[time]\nend = 1\n"
	                              "output_every = 1\n";
	const char *layer[] = {"model.delta=0.01", "model.density=1600", "model.viscosity=0.1"};
	CHECK(parse(&c, with_nu, layer, 3) == SS_OK, "%s", ss_error_last_message());
	const double tau = 1600 * 9.81 * 0.01 * sin(35 * M_PI / 180);
	CHECK_REL(c.model.nu, tau * 1e-4 / (30 * 0.1), 1e-15, "casson's nu from the layer");
	CHECK(c.note_count == 1 && noted(&c, "[model] nu (dir/case.ini:8)", "--set model.delta"),
	      "%s", c.notes[0]);
	ss_case_release(&c);

	/* both in the file: an error, as before */
	static const char both[] = "[grid]\nnx = 4\nny = 4\ndx = 1\n[model]\nclosure = casson\n"
	                           "repose_angle = 35\nnu = 1\ndelta = 0.01\n[time]\nend = 1\n"
	                           "output_every = 1\n";
	CHECK(parse(&c, both, NULL, 0) == SS_ERR_INPUT &&
	      strstr(ss_error_last_message(), "gives both nu and delta"), "%s",
	      ss_error_last_message());
	ss_case_release(&c);
}

static void a_closure_drops_the_other_law(void)
{
	struct ss_case c;
	const char *hb[] = {"model.closure=herschel-bulkley", "model.consistency=0.2"};
	CHECK(parse(&c, bingham_layer, hb, 2) == SS_OK, "%s", ss_error_last_message());
	const struct ss_sliding_layer *l = &c.model.layer;
	CHECK(isnan(l->viscosity) && l->consistency == 0.2 && c.model.gamma == 1.0,
	      "viscosity %g, consistency %g, gamma %g (its one default)", l->viscosity,
	      l->consistency, c.model.gamma);
	CHECK(noted(&c, "viscosity", "--set model.closure=herschel-bulkley"), "%s", c.notes[0]);
	ss_case_release(&c);

	const char *coulomb[] = {"model.closure=coulomb"};
	CHECK(parse(&c, bingham_layer, coulomb, 1) == SS_ERR_INPUT &&
	      strstr(ss_error_last_message(), "--set model.closure=coulomb") &&
	      strstr(ss_error_last_message(), "give model.nu too"), "%s", ss_error_last_message());
	ss_case_release(&c);
}

static void a_type_drops_the_other_types_keys(void)
{
	struct ss_case c;
	const char *flat[] = {"initial.type=flat"};
	CHECK(parse(&c, steady_cone, flat, 1) == SS_OK, "%s", ss_error_last_message());
	CHECK(c.initial == SS_INITIAL_FLAT && c.note_count == 3 &&
	      noted(&c, "center", "applies to type = cone"), "%d notes", c.note_count);
	ss_case_release(&c);
}

static void unset_keys_and_sections(void)
{
	struct ss_case c;
	const char *no_max[] = {"time.max_time"};
	CHECK(parse(&c, steady_cone, no_max, 1) == SS_OK && isnan(c.model.max_time) &&
	      c.note_count == 0, "--unset time.max_time: %s", ss_error_last_message());
	ss_case_release(&c);

	const char *no_source[] = {"source pour"};
	CHECK(parse(&c, steady_cone, no_source, 1) == SS_OK && c.region_count == 0,
	      "--unset 'source pour': %d regions", c.region_count);
	ss_case_release(&c);

	const char *no_stop[] = {"source pour.stop"};
	CHECK(parse(&c, steady_cone, no_stop, 1) == SS_OK && isinf(c.regions[0].stop),
	      "--unset 'source pour.stop': %s", ss_error_last_message());
	ss_case_release(&c);

	const char *no_nu[] = {"model.nu"};
	CHECK(parse(&c, steady_cone, no_nu, 1) == SS_ERR_INPUT &&
	      strstr(ss_error_last_message(), "missing 'nu'"), "%s", ss_error_last_message());
	ss_case_release(&c);

	const char *no_cfl[] = {"time.cfl"};
	CHECK(parse(&c, steady_cone, no_cfl, 1) == SS_OK && c.model.cfl == 0.9,
	      "an unset key takes its default");
	ss_case_release(&c);

	const char *bad[][1] = {{"grid"}, {"model.bogus"}, {"source nosuch"}, {"wall x.rate"}};
	const char *says[] = {"cannot be removed", "unknown key 'bogus' in [model]",
	                      "has no [source nosuch]", "has no [wall x]"};
	for (int k = 0; k < 4; k++) {
		CHECK(parse(&c, steady_cone, bad[k], 1) == SS_ERR_INPUT &&
		      strstr(ss_error_last_message(), "--unset ") &&
		      strstr(ss_error_last_message(), says[k]), "--unset %s: %s", bad[k][0],
		      ss_error_last_message());
		ss_case_release(&c);
	}

	/* the order counts: a key unset, then set again */
	const char *again[] = {"time.max_time", "time.max_time=50"};
	CHECK(parse(&c, steady_cone, again, 2) == SS_OK && c.model.max_time == 50.0,
	      "unset then set: %g", c.model.max_time);
	ss_case_release(&c);
}

int main(void)
{
	ss_error_set_quiet(1);
	RUN(an_end_drops_the_files_max_time);
	RUN(nu_and_the_sliding_layer_replace_each_other);
	RUN(a_closure_drops_the_other_law);
	RUN(a_type_drops_the_other_types_keys);
	RUN(unset_keys_and_sections);
	return check_report();
}
