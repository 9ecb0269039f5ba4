/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * relax_dem.c - a program a user writes against the installed library:
 * built by tests/cli/test_install.py with `pkg-config --cflags --libs
 * sandslide` from a DESTDIR tree, so that it sees only the installed
 * headers and library.
 *
 *     relax_dem VERSION DEM OUT.asc
 *
 * Checks that ss_version() is VERSION, then relaxes DEM to OUT.asc and
 * checks the physics: steady, no sand face steeper than the 35 deg repose
 * angle, flow volume conserved (the DEM given has no open cells or sides).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sandslide/sandslide.h>

static const double pi = 3.14159265358979323846;

static int passed, failed;

static void check(int ok, const char *what)
{
	if (ok) {
		passed++;
	} else {
		failed++;
		printf("FAILED: %s\n", what);
	}
}

int main(int argc, char **argv)
{
	if (argc != 4) {
		fprintf(stderr, "usage: relax_dem VERSION DEM OUT.asc\n");
		return 2;
	}
	printf("sandslide library %s\n", ss_version());
	check(strcmp(ss_version(), argv[1]) == 0, "ss_version() is the version installed");

	struct ss_relax_options o;
	ss_relax_options_init(&o);
	o.dem = argv[2];
	o.job.output = argv[3];
	o.job.threads = 1;
	o.job.force = 1;
	struct ss_relax_report r;
	const int err = ss_relax_run(&o, &r);
	check(err == SS_OK, "ss_relax_run returns SS_OK");
	if (err == SS_OK) {
		printf("relaxed %d x %d cells: %lld steps, steepest face %.4f -> %.4f deg\n", r.nx,
		       r.ny, r.steps, r.max_slope_before_deg, r.max_slope_after_deg);
		check(r.steady, "the surface is steady");
		check(tan(r.max_slope_after_deg * pi / 180) <= tan(35 * pi / 180) + 1e-6,
		      "no sand face steeper than the repose angle");
		check(r.max_slope_before_deg > 40, "the DEM had faces steeper than 35 deg");
		check(fabs(r.volume_after - r.volume_before) <= 1e-9 * r.volume_before,
		      "the flow volume is conserved");
	}
	printf("%d passed, %d failed\n", passed, failed);
	return failed ? 1 : 0;
}
