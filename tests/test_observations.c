/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_observations.c - the observations `sandslide fit` reads
 * (src/io/observations.h): each kind is read with the right values, and
 * every refusal is SS_ERR_INPUT with one message naming the file (and the
 * line of a CSV).
 *
 * Inputs are written to a mkdtemp folder, removed at the end: CSVs and
 * .asc rasters as text, HDF5 series as real sandslide outputs through the
 * public writer (snapshot.h), as tests may not include <hdf5.h>.  HDF5
 * files of another program's layout (only /time and /height, /x of the
 * wrong length, ...) cannot be written without it: they are not covered
 * here.  TEST_OBSERVATIONS_SHOW=1 prints each refusal's message, to read
 * them.
 */
#include "check.h"

#include <stdarg.h>
#include <string.h>
#include <unistd.h>

#include "io/observations.h"
#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/snapshot.h"

/* ss_observations_read of a file that must be refused: SS_ERR_INPUT, a
 * released struct, and a message holding each of the strings given
 * (NULL-terminated). */
static void refused(const char *path, ...)
{
	struct ss_observations o;
	const int err = ss_observations_read(&o, path);
	const char *msg = ss_error_last_message();
	if (getenv("TEST_OBSERVATIONS_SHOW"))
		printf("  %s\n", msg);
	CHECK(err == SS_ERR_INPUT, "'%s': status %d, not SS_ERR_INPUT (%s)", path, err, msg);
	CHECK(o.path == NULL && o.time == NULL && o.height == NULL && o.point_x == NULL &&
	      o.first_point == NULL, "'%s': refused but not released", path);
	CHECK(strstr(msg, path) != NULL, "'%s': the message does not name the file: %s", path,
	      msg);
	va_list ap;
	va_start(ap, path);
	for (const char *want; (want = va_arg(ap, const char *));)
		CHECK(strstr(msg, want) != NULL, "'%s': the message lacks '%s': %s", path, want, msg);
	va_end(ap);
	ss_observations_release(&o);
}

/* A CSV in the scratch folder, refused with a message holding "NAME:LINE:"
 * and what. */
static void csv_refused(const char *name, const char *text, int line, const char *what)
{
	const char *path = check_file(name);
	check_write_file(path, text);
	char where[600];
	snprintf(where, sizeof where, "%s:%d:", path, line);
	refused(path, where, what, (const char *)NULL);
}

/* ---- the HDF5 series ------------------------------------------------- */

enum { NX = 5, NY = 4 };

/* Height of cell (i, j) at time k of the series written below. */
static double h_of(int i, int j, int k)
{
	return 0.01 * (100 * k + 10 * j + i);
}

/*
 * A sandslide output of NX x NY cells of 0.5 m from the corner (-2, 10):
 * a wall at cell (0, 0), the times given, heights h_of, NaN in cell
 * (4, 3) at every time; every height NaN when all_nan is 1, none but
 * the wall's when 2, and with all_nan < 0 cell (2, 1) infinite at the
 * last time.
 */
static int write_series(const char *path, const double *times, int count, int all_nan)
{
	struct ss_grid g;
	if (ss_grid_init(&g, NX, NY, 0.5, 0.5, -2.0, 10.0))
		return -1;
	const size_t cells = ss_grid_storage_cells(&g);
	uint8_t *types = calloc(ss_cell_types_bytes(cells), 1);
	double *h = calloc(cells, sizeof *h);
	if (!types || !h)
		exit(2);
	ss_cell_type_set(types, ss_grid_index(&g, 0, 0), SS_CELL_WALL);
	struct ss_model_options model;
	ss_model_options_init(&model);
	model.angle_deg = 33.0;
	model.nu = 0.1;
	struct ss_snapshot_meta meta = {
		.title = "test", .history = "test_observations", .case_text = "", .model = &model,
	};
	struct ss_snapshot *s = NULL;
	int err = ss_snapshot_create(&s, path, &g, types, &meta);
	for (int k = 0; k < count && !err; k++) {
		for (int j = 0; j < NY; j++)
			for (int i = 0; i < NX; i++)
				h[ss_grid_index(&g, i, j)] =
					all_nan == 1 || (all_nan != 2 && i == 4 && j == 3) ? NAN
					                                                   : h_of(i, j, k);
		if (all_nan < 0 && k == count - 1)
			h[ss_grid_index(&g, 2, 1)] = INFINITY;
		struct ss_diagnostics d;
		memset(&d, 0, sizeof d);
		err = ss_snapshot_append(s, times[k], h, types, NULL, &d, NULL);
	}
	if (s && ss_snapshot_destroy(s))
		err = -1;
	free(types);
	free(h);
	return err;
}

static void hdf5_series_is_read(void)
{
	const double times[3] = {0.0, 0.5, 2.0};
	const char *path = check_file("run.h5");
	CHECK(write_series(path, times, 3, 0) == SS_OK, "writing: %s", ss_error_last_message());
	struct ss_observations o;
	const int err = ss_observations_read(&o, path);
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (err)
		return;
	CHECK(o.kind == SS_OBSERVED_HEIGHTS, "kind %d", o.kind);
	CHECK(!strcmp(o.path, path), "path %s", o.path);
	CHECK(o.times == 3 && o.nx == NX && o.ny == NY, "%lld times of %d x %d", o.times, o.nx,
	      o.ny);
	for (int k = 0; k < 3 && o.times == 3; k++)
		CHECK(o.time[k] == times[k], "time %d is %g, not %g", k, o.time[k], times[k]);
	CHECK_NEAR(o.dx, 0.5, 1e-12, "dx from /x");
	CHECK_NEAR(o.dy, 0.5, 1e-12, "dy from /y");
	CHECK_NEAR(o.origin_x, -2.0, 1e-12, "the corner from /x");
	CHECK_NEAR(o.origin_y, 10.0, 1e-12, "the corner from /y");
	if (o.times != 3 || o.nx != NX || o.ny != NY)
		goto out;
	/* south row first: row j of time k at (k * ny + j) * nx */
	CHECK(o.height[(2 * NY + 1) * NX + 3] == h_of(3, 1, 2), "cell (3, 1) at t = 2: %g",
	      o.height[(2 * NY + 1) * NX + 3]);
	CHECK(o.height[(0 * NY + 3) * NX + 0] == h_of(0, 3, 0), "cell (0, 3) at t = 0: %g",
	      o.height[3 * NX]);
	CHECK(o.height[(1 * NY + 0) * NX + 1] == h_of(1, 0, 1), "cell (1, 0) at t = 0.5: %g",
	      o.height[(NY + 0) * NX + 1]);
	for (int k = 0; k < 3; k++) {
		CHECK(isnan(o.height[(size_t)k * NX * NY]), "the wall (0, 0) at time %d is %g, not "
		      "NaN", k, o.height[(size_t)k * NX * NY]);
		CHECK(isnan(o.height[((size_t)k * NY + 3) * NX + 4]), "(4, 3) at time %d is not NaN",
		      k);
	}
	CHECK(o.observed == 3 * (NX * NY - 2), "observed %lld, not %d", o.observed,
	      3 * (NX * NY - 2));
	CHECK(o.points == 0 && o.point_x == NULL && o.first_point == NULL, "front fields set");
out:
	ss_observations_release(&o);
	CHECK(o.path == NULL && o.height == NULL && o.times == 0, "released");
}

static void hdf5_refusals(void)
{
	const double bad_order[3] = {0.0, 5.0, 4.0};
	CHECK(write_series(check_file("order.h5"), bad_order, 3, 0) == SS_OK, "writing order.h5");
	refused(check_file("order.h5"), "times must increase: 4 after 5", "/time[2]",
	        (const char *)NULL);
	const double negative[2] = {-1.0, 1.0};
	CHECK(write_series(check_file("negative.h5"), negative, 2, 0) == SS_OK, "writing");
	refused(check_file("negative.h5"), "/time[0] is -1", ">= 0", (const char *)NULL);
	const double nan_time[2] = {0.0, NAN};
	CHECK(write_series(check_file("nantime.h5"), nan_time, 2, 0) == SS_OK, "writing");
	refused(check_file("nantime.h5"), "/time[1] is nan", "finite", (const char *)NULL);
	const double ok[2] = {0.0, 1.0};
	CHECK(write_series(check_file("allnan.h5"), ok, 2, 1) == SS_OK, "writing allnan.h5");
	refused(check_file("allnan.h5"), "no observed value", (const char *)NULL);
	CHECK(write_series(check_file("inf.h5"), ok, 2, -1) == SS_OK, "writing inf.h5");
	refused(check_file("inf.h5"), "infinite at time 1 s, cell (2, 1) at x = -0.75 m, y = 10.75 m:", (const char *)NULL);

	/* not HDF5 under an HDF5 name, and an HDF5 file cut short */
	check_write_file(check_file("text.h5"), "time,path\n0,a.asc\n");
	refused(check_file("text.h5"), "not an HDF5 file", (const char *)NULL);
	CHECK(write_series(check_file("cut.h5"), ok, 2, 0) == SS_OK, "writing cut.h5");
	CHECK(truncate(check_file("cut.h5"), 3000) == 0, "truncate");
	refused(check_file("cut.h5"), "damaged", (const char *)NULL);
	/* HDF5 by its signature, whatever its name */
	CHECK(write_series(check_file("series.dat"), ok, 2, 0) == SS_OK, "writing series.dat");
	struct ss_observations o;
	CHECK(ss_observations_read(&o, check_file("series.dat")) == SS_OK &&
	      o.kind == SS_OBSERVED_HEIGHTS && o.times == 2, "HDF5 by its bytes: %s",
	      ss_error_last_message());
	ss_observations_release(&o);
}

/* ---- a CSV of rasters ------------------------------------------------- */

/* An ESRI ASCII grid of 3 x 2 cells of 0.25 m from (1, 2), north row
 * first in the file, with a nodata cell (column 2 of the north row). */
static void write_asc(const char *name, double base)
{
	char text[512];
	snprintf(text, sizeof text,
	         "ncols 3\nnrows 2\nxllcorner 1\nyllcorner 2\ncellsize 0.25\nNODATA_value -9999\n"
	         "%g %g -9999\n%g %g %g\n",
	         base + 3, base + 4, base + 0, base + 1, base + 2);
	check_write_file(check_file(name), text);
}

static void raster_csv_is_read(void)
{
	write_asc("a.asc", 10.0);
	write_asc("b.asc", 20.0);
	/* BOM, upper case, spaces, CRLF, a comment and a blank line; b.asc by an
	 * absolute path */
	char text[1024];
	snprintf(text, sizeof text, "\xEF\xBB\xBF Time , Path \r\n# the first\r\n0.5, a.asc\r\n\r\n"
	         "1.5 ,%s\r\n", check_file("b.asc"));
	check_write_file(check_file("rasters.csv"), text);
	struct ss_observations o;
	const int err = ss_observations_read(&o, check_file("rasters.csv"));
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (err)
		return;
	CHECK(o.kind == SS_OBSERVED_HEIGHTS && o.times == 2 && o.nx == 3 && o.ny == 2,
	      "kind %d, %lld times of %d x %d", o.kind, o.times, o.nx, o.ny);
	if (o.times == 2 && o.nx == 3 && o.ny == 2) {
		CHECK(o.time[0] == 0.5 && o.time[1] == 1.5, "times %g %g", o.time[0], o.time[1]);
		CHECK(o.dx == 0.25 && o.dy == 0.25 && o.origin_x == 1.0 && o.origin_y == 2.0,
		      "geometry %g %g %g %g", o.dx, o.dy, o.origin_x, o.origin_y);
		/* south row first: the file's last row is row 0 */
		for (int k = 0; k < 2; k++) {
			const double *h = o.height + 6 * k, base = 10.0 * (k + 1);
			CHECK(h[0] == base && h[1] == base + 1 && h[2] == base + 2 && h[3] == base + 3 &&
			      h[4] == base + 4, "time %d: %g %g %g %g %g", k, h[0], h[1], h[2], h[3],
			      h[4]);
			CHECK(isnan(h[5]), "nodata at time %d is %g, not NaN", k, h[5]);
		}
		CHECK(o.observed == 10, "observed %lld", o.observed);
	}
	ss_observations_release(&o);
}

/* Rasters of another format by relative paths: the last snapshot of a
 * sandslide output (FILE.h5:/height would be /height's raw values, NaN
 * at walls, which a DEM may not have). */
static void raster_csv_of_hdf5(void)
{
	const double times[2] = {0.0, 1.0};
	/* a NaN height that is not a wall's is no DEM (dem.h): its message,
	 * after the CSV's line */
	CHECK(write_series(check_file("last.h5"), times, 2, 0) == SS_OK, "writing last.h5");
	csv_refused("h5nan.csv", "time,path\n3,last.h5\n", 2, "last.h5: height nan of cell (4, 3) at x = 0.25 m, y = 11.75 m is not finite");
	CHECK(write_series(check_file("last.h5"), times, 2, 2) == SS_OK, "writing last.h5");
	check_write_file(check_file("h5.csv"), "time,path\n3,last.h5\n4,last.h5\n");
	struct ss_observations o;
	const int err = ss_observations_read(&o, check_file("h5.csv"));
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (err)
		return;
	CHECK(o.times == 2 && o.nx == NX && o.ny == NY, "%lld times of %d x %d", o.times, o.nx,
	      o.ny);
	if (o.times == 2 && o.nx == NX && o.ny == NY) {
		CHECK(o.dx == 0.5 && o.origin_x == -2.0 && o.origin_y == 10.0,
		      "the geometry of the first raster: %g %g %g", o.dx, o.origin_x, o.origin_y);
		for (int k = 0; k < 2; k++) {
			CHECK(o.height[((size_t)k * NY + 2) * NX + 1] == h_of(1, 2, 1),
			      "cell (1, 2) of raster %d is %g", k, o.height[((size_t)k * NY + 2) * NX + 1]);
			CHECK(o.height[((size_t)k * NY + 3) * NX + 4] == h_of(4, 3, 1),
			      "cell (4, 3) of raster %d is %g", k, o.height[((size_t)k * NY + 3) * NX + 4]);
		}
		/* the wall, as a DEM of the file has it (dem.h): 0 m, observed */
		CHECK(o.height[0] == 0.0 && o.observed == 2 * NX * NY, "the wall is %g, observed %lld",
		      o.height[0], o.observed);
	}
	ss_observations_release(&o);
}

static void raster_csv_refusals(void)
{
	write_asc("a.asc", 10.0);
	check_write_file(check_file("small.asc"),
	                 "ncols 2\nnrows 2\nxllcorner 1\nyllcorner 2\ncellsize 0.25\n1 2\n3 4\n");
	check_write_file(check_file("coarse.asc"), "ncols 3\nnrows 2\nxllcorner 1\nyllcorner 2\n"
	                 "cellsize 0.5\n1 2 3\n4 5 6\n");
	check_write_file(check_file("empty.asc"), "ncols 3\nnrows 2\nxllcorner 1\nyllcorner 2\n"
	                 "cellsize 0.25\nNODATA_value -1\n-1 -1 -1\n-1 -1 -1\n");
	csv_refused("r_order.csv", "time,path\n0,a.asc\n5.0,a.asc\n4.0,a.asc\n", 4,
	            "times must increase: 4 after 5");
	csv_refused("r_same.csv", "time,path\n0,a.asc\n0,a.asc\n", 3, "times must increase");
	csv_refused("r_negative.csv", "time,path\n-1,a.asc\n", 2, "negative");
	csv_refused("r_inf.csv", "time,path\ninf,a.asc\n", 2, "not finite");
	csv_refused("r_word.csv", "time,path\n\n# c\nsoon,a.asc\n", 4, "'soon' is not a number");
	csv_refused("r_fields.csv", "time,path\n0,a.asc,extra\n", 2, "3 fields: expected 2");
	csv_refused("r_nopath.csv", "time,path\n0,\n", 2, "no raster path");
	csv_refused("r_size.csv", "time,path\n0,a.asc\n1,small.asc\n", 3,
	            "every raster must have the first one's size");
	csv_refused("r_grid.csv", "time,path\n0,a.asc\n1,coarse.asc\n", 3,
	            "the first one's grid");
	csv_refused("r_missing.csv", "time,path\n0,a.asc\n1,nothere.asc\n", 3, "nothere.asc");
	check_write_file(check_file("r_none.csv"), "time,path\n0,empty.asc\n");
	refused(check_file("r_none.csv"), "no observed value", (const char *)NULL);
	/* a raster too large for memory, refused from its header before
	 * anything of its size is allocated or read */
	check_write_file(check_file("huge.asc"), "ncols 1000000\nnrows 1000000\nxllcorner 0\n"
	                 "yllcorner 0\ncellsize 1\n");
	check_write_file(check_file("r_huge.csv"), "time,path\n0,huge.asc\n1,huge.asc\n");
	refused(check_file("r_huge.csv"), "1000000 x 1000000 cells", "of memory",
	        (const char *)NULL);
	check_write_file(check_file("r_header.csv"), "time,path\n");
	refused(check_file("r_header.csv"), "no observations", (const char *)NULL);
}

/* ---- the front --------------------------------------------------------- */

static void front_csv_is_read(void)
{
	check_write_file(check_file("front.csv"),
	                 "time,x,y\n0,0,0\n0,1,0\n0,0,1\n"
	                 "2.5,-1,-1\n2.5,2,-1\n2.5,2,2\n2.5,-1,2\n");
	struct ss_observations o;
	const int err = ss_observations_read(&o, check_file("front.csv"));
	CHECK(err == SS_OK, "%s", ss_error_last_message());
	if (err)
		return;
	CHECK(o.kind == SS_OBSERVED_FRONT && o.times == 2 && o.points == 7, "kind %d, %lld times, "
	      "%lld points", o.kind, o.times, o.points);
	if (o.times == 2 && o.points == 7) {
		CHECK(o.time[0] == 0.0 && o.time[1] == 2.5, "times %g %g", o.time[0], o.time[1]);
		CHECK(o.first_point[0] == 0 && o.first_point[1] == 3 && o.first_point[2] == 7,
		      "first points %lld %lld %lld", o.first_point[0], o.first_point[1],
		      o.first_point[2]);
		CHECK(o.point_x[1] == 1.0 && o.point_y[2] == 1.0 && o.point_x[3] == -1.0 &&
		      o.point_y[6] == 2.0, "points in the file's order");
	}
	CHECK(o.height == NULL && o.nx == 0 && isnan(o.dx), "height fields set for a front");
	ss_observations_release(&o);
}

static void front_csv_refusals(void)
{
	csv_refused("f_two.csv", "time,x,y\n0,0,0\n0,1,0\n1,0,0\n1,1,0\n1,1,1\n", 2,
	            "time 0 has 2 points: a front needs at least 3");
	csv_refused("f_last.csv", "time,x,y\n0,0,0\n0,1,0\n0,1,1\n1,5,5\n", 5, "has 1 point:");
	csv_refused("f_order.csv", "time,x,y\n0,0,0\n0,1,0\n0,1,1\n2,0,0\n2,1,0\n2,1,1\n1,0,0\n",
	            8, "rows of one time together");
	csv_refused("f_back.csv", "time,x,y\n5.0,0,0\n5,1,0\n5,1,1\n4.0,0,0\n", 5,
	            "times must increase: 4 after 5");
	csv_refused("f_fields.csv", "time,x,y\n0,0\n", 2, "2 fields: expected 3 (time,x,y)");
	csv_refused("f_x.csv", "time,x,y\n0,1e999,0\n", 2, "x '1e999' is not finite");
	csv_refused("f_y.csv", "time,x,y\n0,0,north\n", 2, "y 'north' is not a number");
	check_write_file(check_file("f_header.csv"), "time,x,y\n# nothing\n");
	refused(check_file("f_header.csv"), "no observations", (const char *)NULL);
}

/* ---- the kind of a file ---------------------------------------------- */

static void unknown_files(void)
{
	csv_refused("unknown.csv", "t,h\n0,1\n", 1, "unknown header 't,h': expected");
	check_write_file(check_file("empty.csv"), "");
	refused(check_file("empty.csv"), "empty: no observations", (const char *)NULL);
	check_write_file(check_file("blank.csv"), "\n  \n");
	refused(check_file("blank.csv"), "no observations", (const char *)NULL);
	check_write_file(check_file("notes.txt"), "some notes\n");
	refused(check_file("notes.txt"), "header time,path", "header time,x,y", ".h5",
	        (const char *)NULL);
	check_write_file(check_file("picture.bin"), "\x89PNG\r\n\x1a\n\x01\x02");
	refused(check_file("picture.bin"), "not an observation file", "time,x,y",
	        (const char *)NULL);
	refused(check_file("nowhere.csv"), "cannot open", (const char *)NULL);
	refused(check_scratch(), "is a folder", (const char *)NULL);

	struct ss_observations zero;
	memset(&zero, 0, sizeof zero);
	ss_observations_release(&zero);
	ss_observations_release(&zero);
	CHECK(zero.path == NULL && zero.times == 0, "release of a zeroed struct is a no-op");
}

int main(void)
{
	if (check_scratch_make("test_observations"))
		return 2;
	ss_snapshot_library_init();
	ss_error_set_quiet(1);
	RUN(hdf5_series_is_read);
	RUN(hdf5_refusals);
	RUN(raster_csv_is_read);
	RUN(raster_csv_of_hdf5);
	RUN(raster_csv_refusals);
	RUN(front_csv_is_read);
	RUN(front_csv_refusals);
	RUN(unknown_files);
	check_scratch_remove();
	return check_report();
}
