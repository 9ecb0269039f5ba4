/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_dem.c - raster input and output (dem.h): round trips keep what each
 * format can hold, malformed files are refused with messages that name the
 * place, and writes are atomic and never touch the input.
 *
 * Everything happens in a mkdtemp folder that is removed at the end.  In a
 * build without GDAL the GeoTIFF test checks that .tif is refused clearly
 * and skips the round trip, saying so (the closing line counts the skip).
 */
#include "check.h"

#include <dirent.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <png.h>

#include "sandslide/dem.h"
#include "sandslide/error.h"

/* Whole file into a malloc'd buffer; *size its length. */
static char *slurp(const char *path, size_t *size)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *b = malloc((size_t)n + 1);
	if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
		free(b);
		b = NULL;
	}
	if (b)
		b[n] = '\0';
	fclose(f);
	*size = (size_t)n;
	return b;
}

/* Files in the scratch folder whose name starts with '.': leftover temporaries. */
static int hidden_files(void)
{
	DIR *d = opendir(check_scratch());
	int n = 0;
	for (struct dirent *e; d && (e = readdir(d));)
		n += e->d_name[0] == '.' && strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
	if (d)
		closedir(d);
	return n;
}

static int exists(const char *path)
{
	return access(path, F_OK) == 0;
}

/* stderr into a file while a call is expected to fail, so the messages
 * can be checked (and do not clutter the test output). */
static int saved_stderr = -1;

static void capture_begin(void)
{
	fflush(stderr);
	saved_stderr = dup(2);
	int fd = open(check_file("stderr.txt"), O_WRONLY | O_CREAT | O_TRUNC, 0600);
	dup2(fd, 2);
	close(fd);
}

static char captured[4096];

static const char *capture_end(void)
{
	fflush(stderr);
	dup2(saved_stderr, 2);
	close(saved_stderr);
	size_t n;
	char *b = slurp(check_file("stderr.txt"), &n);
	snprintf(captured, sizeof captured, "%s", b ? b : "");
	free(b);
	unlink(check_file("stderr.txt"));
	return captured;
}

/* A raster of random heights with a few nodata cells. */
static void random_raster(struct ss_raster *r, int nx, int ny, struct rng *g, int with_nodata)
{
	if (ss_raster_init(r, nx, ny))
		exit(2);
	r->cellsize = r->cellsize_y = 0.25;
	r->x0 = -3.125;
	r->y0 = 1e5 + 0.1;
	for (int k = 0; k < nx * ny; k++)
		r->values[k] = 10.0 * rng_uniform(g) - 2.0;
	if (with_nodata) {
		r->nodata = calloc((size_t)nx * ny, 1);
		for (int a = 0; a < nx * ny / 10 + 1; a++) {
			const int k = rng_int(g, nx * ny);
			r->nodata[k] = 1;
			r->values[k] = 0.0;
		}
	}
}

static int same_flags(const struct ss_raster *a, const struct ss_raster *b)
{
	const size_t n = (size_t)a->nx * a->ny;
	for (size_t k = 0; k < n; k++) {
		if ((a->nodata && a->nodata[k]) != (b->nodata && b->nodata[k]))
			return 0;
	}
	return 1;
}

static int same_values(const struct ss_raster *a, const struct ss_raster *b)
{
	return a->nx == b->nx && a->ny == b->ny &&
	       memcmp(a->values, b->values, sizeof(double) * a->nx * a->ny) == 0;
}

/* ------------------------------------------------------------------ */

static void format_from_path(void)
{
	static const struct {
		const char *path;
		enum ss_dem_format f;
	} ok[] = {
		{"a.asc", SS_DEM_ASC}, {"dir.x/B.ASC", SS_DEM_ASC}, {"a.png", SS_DEM_PNG},
		{"a.tif", SS_DEM_GDAL}, {"a.TIFF", SS_DEM_GDAL}, {"out/run.h5", SS_DEM_H5},
		{"run.h5:/height", SS_DEM_H5},
	};
	for (size_t a = 0; a < sizeof ok / sizeof *ok; a++) {
		enum ss_dem_format f = SS_DEM_AUTO;
		CHECK(ss_dem_format_from_path(ok[a].path, NULL, &f) == SS_OK && f == ok[a].f,
		      "%s: format %d, expected %d", ok[a].path, (int)f, (int)ok[a].f);
	}
	enum ss_dem_format f;
	capture_begin();
	int err = ss_dem_format_from_path("heights.jpg", "case.ini:3", &f);
	const char *msg = capture_end();
	CHECK(err == SS_ERR_INPUT, "unknown extension gives %d", err);
	CHECK(strstr(msg, "case.ini:3") && strstr(msg, "heights.jpg") && strstr(msg, ".asc") &&
	      strstr(msg, ".png") && strstr(msg, ".tif") && strstr(msg, ".h5"),
	      "the message names the place, the file and every accepted extension: %s", msg);
}

static void asc_round_trip_is_bit_exact(void)
{
	struct rng g = {20240605};
	const int nx = 13, ny = 7;
	/* a file as another program writes it: odd corner, NODATA cells */
	FILE *f = fopen(check_file("in.asc"), "w");
	fprintf(f, "NCOLS %d\nnrows %d\nxllcorner 612345.67\nyllcorner -4200.125\n"
	           "cellsize 0.3\nNODATA_value -9999\n", nx, ny);
	double expect[13 * 7];
	uint8_t hole[13 * 7] = {0};
	for (int row = 0; row < ny; row++) {
		for (int i = 0; i < nx; i++) {
			const int k = (ny - 1 - row) * nx + i;   /* south row first */
			expect[k] = (rng_uniform(&g) - 0.5) * pow(10.0, rng_int(&g, 9) - 4);
			hole[k] = rng_int(&g, 8) == 0;
			if (hole[k])
				fprintf(f, " -9999");
			else
				fprintf(f, " %.17g", expect[k]);
		}
		fputc('\n', f);
	}
	fclose(f);

	struct ss_raster a, b;
	int err = ss_dem_read(check_file("in.asc"), NULL, NULL, &a);
	CHECK(err == SS_OK, "read in.asc: %d", err);
	CHECK(a.nx == nx && a.ny == ny, "size %d x %d", a.nx, a.ny);
	CHECK(a.format == SS_DEM_ASC && a.cellsize == 0.3 && a.cellsize_y == 0.3 &&
	      a.x0 == 612345.67 && a.y0 == -4200.125, "geometry %g %g %g", a.cellsize, a.x0, a.y0);
	CHECK(a.has_nodata_value && a.nodata_value == -9999.0 && a.nodata, "nodata value kept");
	int values_ok = 1, flags_ok = 1;
	for (int k = 0; k < nx * ny; k++) {
		flags_ok &= a.nodata[k] == hole[k];
		values_ok &= hole[k] ? a.values[k] == 0.0 : a.values[k] == expect[k];
	}
	CHECK(flags_ok, "nodata flags where the file has -9999, south row first");
	CHECK(values_ok, "every value read exactly (0 at nodata cells)");

	err = ss_dem_write(check_file("out.asc"), SS_DEM_AUTO, &a);
	CHECK(err == SS_OK, "write out.asc: %d", err);
	err = ss_dem_read(check_file("out.asc"), NULL, NULL, &b);
	CHECK(err == SS_OK, "read out.asc: %d", err);
	CHECK(same_values(&a, &b), "values bit-identical after write and read");
	CHECK(same_flags(&a, &b), "nodata flags identical");
	CHECK(b.cellsize == a.cellsize && b.x0 == a.x0 && b.y0 == a.y0 &&
	      b.nodata_value == -9999.0, "corner, cell size and NODATA_value kept");
	CHECK(hidden_files() == 0, "no temporary file left");
	size_t n;
	char *text = slurp(check_file("out.asc"), &n);
	CHECK(text && strstr(text, "xllcorner 612345.67\n") && strstr(text, "NODATA_value -9999\n"),
	      "header written as corner and NODATA_value");
	free(text);
	ss_raster_release(&a);
	ss_raster_release(&b);
}

static void asc_keeps_centre_and_rectangular_cells(void)
{
	check_write_file(check_file("c.asc"), "ncols 3\nnrows 2\nxllcenter 10\nyllcenter 20\ndx 2\ndy 4\n"
	                        "1 2 3\n4 5 6\n");
	struct ss_raster a, b;
	int err = ss_dem_read(check_file("c.asc"), NULL, NULL, &a);
	CHECK(err == SS_OK, "read c.asc: %d", err);
	CHECK(a.x0 == 9.0 && a.y0 == 18.0 && a.asc_center, "centre %g %g gives the corner", a.x0, a.y0);
	CHECK(a.cellsize == 2.0 && a.cellsize_y == 4.0, "dx, dy %g %g", a.cellsize, a.cellsize_y);
	CHECK(a.values[0] == 4.0 && a.values[5] == 3.0, "south row first: %g %g", a.values[0],
	      a.values[5]);
	CHECK(!a.nodata && !a.has_nodata_value, "no nodata without NODATA_value");
	err = ss_dem_write(check_file("c2.asc"), SS_DEM_ASC, &a);
	size_t n;
	char *text = slurp(check_file("c2.asc"), &n);
	CHECK(err == SS_OK && text && strstr(text, "xllcenter 10\nyllcenter 20\ndx 2\ndy 4\n") &&
	      !strstr(text, "NODATA"), "written back with xllcenter, dx, dy and no NODATA: %s",
	      text ? text : "(none)");
	free(text);
	CHECK(ss_dem_read(check_file("c2.asc"), NULL, NULL, &b) == SS_OK && same_values(&a, &b),
	      "values kept");
	ss_raster_release(&a);
	ss_raster_release(&b);
}

/* Each malformed file is SS_ERR_INPUT and the message has every word. */
static void asc_malformed_is_refused(void)
{
	static const struct {
		const char *text;
		const char *words[3];
	} bad[] = {
		{"nrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n", {"ncols", "nrows"}},
		{"ncols 2\nnrows 2\nyllcorner 0\ncellsize 1\n1 2\n3 4\n", {"xllcorner", "corner"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2\n3 4\n", {"cellsize"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize -1\n1 2\n3 4\n", {"> 0"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3\n", {"ends after 3 of"}},
		/* refused before allocating 2^63 bytes (fuzz_asc) */
		{"ncols 1073741824\nnrows 1073741824\nxllcorner 0\nyllcorner 0\ncellsize 1\n1\n",
		 {"ends after 1 of 1073741824 x 1073741824"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\nnan 4\n",
		 {"bad.asc:7", "(cell (0, 0) at x = 0.5 m, y = 0.5 m)", "finite"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 inf\n3 4\n",
		 {"bad.asc:6", "(cell (1, 1) at x = 1.5 m, y = 1.5 m)", "finite"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 four\n",
		 {"bad.asc:7", "'four'", "not a number"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n5\n",
		 {"bad.asc:8", "more values"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\ncolour 3\n1 2\n3 4\n",
		 {"bad.asc:6", "'colour'", "NODATA_value"}},
		{"ncols 2\nnrows 2\nncols 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n",
		 {"bad.asc:3", "repeats line 1"}},
		{"ncols 2\nnrows 2\nxllcorner 0\nyllcenter 0\ncellsize 1\n1 2\n3 4\n", {"centre"}},
		/* the far corner, or a centre's corner, beyond the doubles (fuzz_asc) */
		{"ncols 2\nnrows 1\nxllcorner 1e308\nyllcorner 0\ncellsize 1e308\n1 2\n",
		 {"2 x 1 cells of 1e+308 x 1e+308 m from (1e+308, 0)", "finite extent"}},
		{"ncols 1\nnrows 1\nxllcenter 0\nyllcenter -1.7e308\ncellsize 1.7e308\n1\n",
		 {"from (-8.5e+307, -inf)", "finite extent"}},
	};
	for (size_t a = 0; a < sizeof bad / sizeof *bad; a++) {
		check_write_file(check_file("bad.asc"), bad[a].text);
		struct ss_raster r;
		capture_begin();
		int err = ss_dem_read(check_file("bad.asc"), "case.ini:9", NULL, &r);
		const char *msg = capture_end();
		ss_raster_release(&r);
		CHECK(err == SS_ERR_INPUT, "case %zu: status %d", a, err);
		CHECK(strstr(msg, "case.ini:9") != NULL, "case %zu names where the file was given: %s",
		      a, msg);
		for (int w = 0; w < 3 && bad[a].words[w]; w++)
			CHECK(strstr(msg, bad[a].words[w]) != NULL, "case %zu: '%s' in: %s", a,
			      bad[a].words[w], msg);
		CHECK(strchr(msg, '\n') == msg + strlen(msg) - 1, "case %zu: one message: %s", a, msg);
	}
}

static void cellsize_option_must_agree(void)
{
	check_write_file(check_file("g.asc"), "ncols 1\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 0.5\n7\n");
	struct ss_dem_read_options o;
	ss_dem_read_options_init(&o);
	struct ss_raster r;
	o.cellsize = 0.5;
	CHECK(ss_dem_read(check_file("g.asc"), NULL, &o, &r) == SS_OK, "agreeing cell size accepted");
	ss_raster_release(&r);
	o.cellsize = 0.25;
	capture_begin();
	int err = ss_dem_read(check_file("g.asc"), NULL, &o, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "0.25") && strstr(msg, "0.5"),
	      "a disagreeing cell size is refused naming both: %s", msg);
	ss_dem_read_options_init(&o);
	o.zscale = 0.1;
	capture_begin();
	err = ss_dem_read(check_file("g.asc"), NULL, &o, &r);
	msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "PNG"), "zscale on an .asc is refused: %s", msg);
}

/* The largest |a - b| over cells with data. */
static double max_diff(const struct ss_raster *a, const struct ss_raster *b)
{
	double d = 0.0;
	for (int k = 0; k < a->nx * a->ny; k++) {
		if (!a->nodata || !a->nodata[k])
			d = fmax(d, fabs(a->values[k] - b->values[k]));
	}
	return d;
}

static void png16_round_trip(void)
{
	struct rng g = {7};
	struct ss_raster a, b, c;
	random_raster(&a, 37, 23, &g, 1);
	double lo = INFINITY, hi = -INFINITY;
	int klo = 0, khi = 0;
	for (int k = 0; k < a.nx * a.ny; k++) {
		if (a.nodata[k])
			continue;
		if (a.values[k] < lo)
			lo = a.values[k], klo = k;
		if (a.values[k] > hi)
			hi = a.values[k], khi = k;
	}
	int err = ss_dem_write(check_file("h.png"), SS_DEM_AUTO, &a);
	CHECK(err == SS_OK, "write h.png: %d", err);
	err = ss_dem_read(check_file("h.png"), NULL, NULL, &b);
	CHECK(err == SS_OK, "read h.png: %d", err);
	CHECK(b.nx == a.nx && b.ny == a.ny && b.format == SS_DEM_PNG, "size %d x %d", b.nx, b.ny);
	CHECK(b.png_zmin == lo && b.png_zmax == hi, "range from the text chunks exact: %.17g %.17g",
	      b.png_zmin, b.png_zmax);
	CHECK(b.values[klo] == lo && b.values[khi] == hi, "lowest and highest cells exact");
	const double step = (hi - lo) / 65534.0;
	CHECK_NEAR(max_diff(&a, &b), 0.0, 0.5 * step * (1 + 1e-9), "within half a grey level");
	CHECK(same_flags(&a, &b), "nodata cells are grey 0 and come back flagged");
	CHECK(b.cellsize == a.cellsize && b.x0 == a.x0 && b.y0 == a.y0,
	      "cell size and corner from dx_m, x0_m, y0_m");
	/* a heightmap read and written again keeps every bit */
	CHECK(ss_dem_write(check_file("h2.png"), SS_DEM_PNG, &b) == SS_OK, "write h2.png");
	CHECK(ss_dem_read(check_file("h2.png"), NULL, NULL, &c) == SS_OK && same_values(&b, &c) &&
	      same_flags(&b, &c), "second round trip bit-identical");
	CHECK(hidden_files() == 0, "no temporary file left");

	/* north row first in the file: the top row of the picture is row ny-1 */
	png_image im;
	memset(&im, 0, sizeof im);
	im.version = PNG_IMAGE_VERSION;
	uint16_t *px = NULL;
	if (png_image_begin_read_from_file(&im, check_file("h.png"))) {
		im.format = PNG_FORMAT_LINEAR_Y;
		px = malloc(PNG_IMAGE_SIZE(im));
		png_image_finish_read(&im, NULL, px, 0, NULL);
	}
	CHECK(px && (px[0] == 0) == (a.nodata[(size_t)(a.ny - 1) * a.nx] != 0),
	      "top-left pixel is the north-west cell");
	free(px);
	ss_raster_release(&a);
	ss_raster_release(&b);
	ss_raster_release(&c);
}

/* Write a 16-bit grey PNG with libpng: greys north row first, optional
 * text chunks "key=value" and optional tRNS grey. */
static void write_gray16(const char *path, int w, int h, const uint16_t *grey,
                         const char *const *texts, int ntext, int trns)
{
	FILE *f = fopen(path, "wb");
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png_create_info_struct(png);
	if (setjmp(png_jmpbuf(png))) {
		fprintf(stderr, "libpng failed writing %s\n", path);
		exit(2);
	}
	png_init_io(png, f);
	png_set_IHDR(png, info, w, h, 16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
	             PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	png_text t[8];
	char kv[8][64];
	memset(t, 0, sizeof t);
	for (int a = 0; a < ntext; a++) {
		snprintf(kv[a], sizeof kv[a], "%s", texts[a]);
		char *eq = strchr(kv[a], '=');
		*eq = '\0';
		t[a].compression = PNG_TEXT_COMPRESSION_NONE;
		t[a].key = kv[a];
		t[a].text = eq + 1;
	}
	if (ntext)
		png_set_text(png, info, t, ntext);
	if (trns >= 0) {
		png_color_16 c = {0};
		c.gray = (png_uint_16)trns;
		png_set_tRNS(png, info, NULL, 0, &c);
	}
	png_write_info(png, info);
	uint8_t *row = malloc(2 * (size_t)w);
	for (int y = 0; y < h; y++) {
		for (int x = 0; x < w; x++) {
			row[2 * x] = grey[y * w + x] >> 8;
			row[2 * x + 1] = grey[y * w + x] & 0xff;
		}
		png_write_row(png, row);
	}
	png_write_end(png, NULL);
	png_destroy_write_struct(&png, &info);
	free(row);
	fclose(f);
}

/* A gray16 picture as the renderer writes it. */
static void png_from_renderer_convention(void)
{
	const uint16_t grey[6] = {0, 1, 2, 65535, 32768, 65534};   /* north row first */
	const char *const texts[] = {"style=gray16", "zmin_m=-1.5", "zmax_m=2.5"};
	write_gray16(check_file("r.png"), 3, 2, grey, texts, 3, 0);
	struct ss_raster r;
	int err = ss_dem_read(check_file("r.png"), NULL, NULL, &r);
	CHECK(err == SS_OK, "read r.png: %d", err);
	const double step = 4.0 / 65534.0;
	/* south row first: (65535, 32768, 65534) then (0, 1, 2) */
	CHECK(r.nodata && r.nodata[3] && !r.nodata[4] && !r.nodata[0], "grey 0 is no data");
	CHECK(r.values[4] == -1.5 && r.values[0] == 2.5, "grey 1 is zmin, 65535 is zmax: %g %g",
	      r.values[4], r.values[0]);
	CHECK_NEAR(r.values[5], -1.5 + step, 1e-15, "grey 2");
	CHECK_NEAR(r.values[1], -1.5 + 32767 * step, 1e-15, "grey 32768");
	CHECK(isnan(r.cellsize), "no dx_m: cell size unknown");
	ss_raster_release(&r);
}

static void png_with_explicit_scale(void)
{
	const uint16_t grey[4] = {0, 10, 1000, 65535};
	write_gray16(check_file("plain.png"), 2, 2, grey, NULL, 0, -1);
	struct ss_raster r;
	capture_begin();
	int err = ss_dem_read(check_file("plain.png"), "relax", NULL, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "plain.png") && strstr(msg, "zscale") &&
	      strstr(msg, "zmin_m"), "no range and no zscale is refused: %s", msg);

	struct ss_dem_read_options o;
	ss_dem_read_options_init(&o);
	o.zscale = 0.01;
	o.zoffset = 5.0;
	o.cellsize = 2.0;
	err = ss_dem_read(check_file("plain.png"), NULL, &o, &r);
	CHECK(err == SS_OK, "read with zscale: %d", err);
	CHECK(!r.nodata, "grey 0 is a height without tRNS or a gray16 range");
	CHECK(r.values[2] == 5.0 && r.values[0] == 5.0 + 0.01 * 1000 &&
	      r.values[1] == 5.0 + 0.01 * 65535, "height = zoffset + zscale grey: %g %g %g",
	      r.values[2], r.values[0], r.values[1]);
	CHECK(r.cellsize == 2.0 && r.cellsize_y == 2.0, "cell size from the options");
	ss_raster_release(&r);

	write_gray16(check_file("trns.png"), 2, 2, grey, NULL, 0, 10);
	err = ss_dem_read(check_file("trns.png"), NULL, &o, &r);
	CHECK(err == SS_OK && r.nodata && r.nodata[3] && !r.nodata[2],
	      "the tRNS grey marks no data");
	ss_raster_release(&r);

	ss_dem_read_options_init(&o);
	o.zoffset = 1.0;
	capture_begin();
	err = ss_dem_read(check_file("plain.png"), NULL, &o, &r);
	msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "zoffset"), "zoffset alone is refused: %s", msg);
}

static void png_not_gray16_is_refused(void)
{
	/* an 8-bit grey picture, as a mask would be */
	uint8_t px[12] = {0, 50, 100, 150, 200, 250, 0, 50, 100, 150, 200, 250};
	png_image im;
	memset(&im, 0, sizeof im);
	im.version = PNG_IMAGE_VERSION;
	im.width = 4;
	im.height = 3;
	im.format = PNG_FORMAT_GRAY;
	CHECK(png_image_write_to_file(&im, check_file("eight.png"), 0, px, 0, NULL), "write eight.png");
	struct ss_raster r;
	capture_begin();
	int err = ss_dem_read(check_file("eight.png"), NULL, NULL, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "eight.png") && strstr(msg, "8-bit") &&
	      strstr(msg, "16-bit greyscale"), "8-bit PNG refused: %s", msg);

	memset(&im, 0, sizeof im);
	im.version = PNG_IMAGE_VERSION;
	im.width = 2;
	im.height = 2;
	im.format = PNG_FORMAT_RGB;
	CHECK(png_image_write_to_file(&im, check_file("rgb.png"), 0, px, 0, NULL), "write rgb.png");
	capture_begin();
	err = ss_dem_read(check_file("rgb.png"), NULL, NULL, &r);
	msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "RGB"), "RGB PNG refused: %s", msg);

	check_write_file(check_file("fake.png"), "GIF89a not a png at all");
	capture_begin();
	err = ss_dem_read(check_file("fake.png"), NULL, NULL, &r);
	msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "not a PNG"), "non-PNG refused: %s", msg);
}

/* CRC-32 of PNG chunks (ISO 3309), for the patched headers below. */
static uint32_t png_crc(const unsigned char *p, size_t n)
{
	uint32_t c = 0xffffffffu;
	for (size_t k = 0; k < n; k++) {
		c ^= p[k];
		for (int b = 0; b < 8; b++)
			c = c & 1 ? 0xedb88320u ^ (c >> 1) : c >> 1;
	}
	return c ^ 0xffffffffu;
}

/* A 4 x 4 heightmap whose header claims 10^6 x 10^6 pixels is refused
 * before 2 TB are allocated (fuzz_png). */
static void png_too_short_for_its_size_is_refused(void)
{
	const uint16_t grey[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
	const char *const texts[] = {"zmin_m=0", "zmax_m=1"};
	write_gray16(check_file("claims.png"), 4, 4, grey, texts, 2, -1);
	size_t size;
	unsigned char *b = (unsigned char *)slurp(check_file("claims.png"), &size);
	CHECK(b && size > 33 && memcmp(b + 12, "IHDR", 4) == 0, "claims.png starts with IHDR");
	if (!b || size <= 33) {
		free(b);
		return;
	}
	const unsigned char million[4] = {0x00, 0x0f, 0x42, 0x40};
	memcpy(b + 16, million, 4);   /* width */
	memcpy(b + 20, million, 4);   /* height */
	const uint32_t crc = png_crc(b + 12, 17);
	const unsigned char be[4] = {crc >> 24, crc >> 16 & 0xff, crc >> 8 & 0xff, crc & 0xff};
	memcpy(b + 29, be, 4);
	FILE *f = fopen(check_file("claims.png"), "wb");
	fwrite(b, 1, size, f);
	fclose(f);
	free(b);
	struct ss_raster r;
	capture_begin();
	int err = ss_dem_read(check_file("claims.png"), NULL, NULL, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "cannot hold 1000000 x 1000000") &&
	      strstr(msg, "truncated"), "status %d: %s", err, msg);
}

/* A text chunk that claims 1.7 GB, in a file of 120 bytes, is refused
 * before libpng allocates it (fuzz_png). */
static void png_chunk_longer_than_file_is_refused(void)
{
	const uint16_t grey[4] = {1, 2, 3, 4};
	const char *const texts[] = {"zmin_m=0", "zmax_m=1"};
	write_gray16(check_file("long.png"), 2, 2, grey, texts, 2, -1);
	size_t size;
	unsigned char *b = (unsigned char *)slurp(check_file("long.png"), &size);
	unsigned char *t = NULL;
	for (size_t k = 0; b && !t && k + 4 <= size; k++)
		if (memcmp(b + k, "tEXt", 4) == 0)
			t = b + k;
	CHECK(t && t - b >= 12, "long.png has a tEXt chunk");
	if (!t || t - b < 12) {
		free(b);
		return;
	}
	memcpy(t - 4, "\x64\x78\x5f\x6d", 4);   /* length 1685610349 */
	FILE *f = fopen(check_file("long.png"), "wb");
	fwrite(b, 1, size, f);
	fclose(f);
	free(b);
	struct ss_raster r;
	capture_begin();
	int err = ss_dem_read(check_file("long.png"), NULL, NULL, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "chunk tEXt claims 1685610349 bytes") &&
	      strstr(msg, "corrupt"), "status %d: %s", err, msg);
}

static void writes_are_atomic_and_spare_the_input(void)
{
	struct rng g = {99};
	struct ss_raster a, b;
	random_raster(&a, 5, 4, &g, 0);
	CHECK(ss_dem_write(check_file("src.asc"), SS_DEM_AUTO, &a) == SS_OK, "write src.asc");
	ss_raster_release(&a);
	CHECK(ss_dem_read(check_file("src.asc"), NULL, NULL, &b) == SS_OK, "read src.asc");
	size_t n0, n1;
	char *before = slurp(check_file("src.asc"), &n0);

	/* writing over the file it came from (even by another name) */
	capture_begin();
	int err = ss_dem_write(check_file("src.asc"), SS_DEM_AUTO, &b);
	const char *msg = capture_end();
	CHECK(err == SS_ERR_INPUT && strstr(msg, "read from"), "overwriting the input refused: %s",
	      msg);
	CHECK(symlink("src.asc", check_file("alias.asc")) == 0, "symlink");
	capture_begin();
	err = ss_dem_write(check_file("alias.asc"), SS_DEM_AUTO, &b);
	capture_end();
	CHECK(err == SS_ERR_INPUT, "overwriting the input through a link refused");
	unlink(check_file("alias.asc"));

	/* a failed write leaves an existing output whole */
	check_write_file(check_file("old.asc"), "keep me\n");
	b.values[3] = NAN;
	capture_begin();
	err = ss_dem_write(check_file("old.asc"), SS_DEM_AUTO, &b);
	msg = capture_end();
	CHECK(err == SS_ERR_FAIL && strstr(msg, "height nan of cell (3, 0) at x = -2.25 m, y = 100000.225 m is not finite"), "a NaN height is not written: %s",
	      msg);
	char *old = slurp(check_file("old.asc"), &n1);
	CHECK(old && !strcmp(old, "keep me\n"), "the earlier file is untouched");
	free(old);
	b.values[3] = 1.0;

	/* unwritable places and formats */
	capture_begin();
	err = ss_dem_write(check_file("no/such/dir/x.asc"), SS_DEM_AUTO, &b);
	msg = capture_end();
	CHECK(err == SS_ERR_INPUT && strstr(msg, "x.asc") && strstr(msg, "No such file"),
	      "missing folder: %s", msg);
	capture_begin();
	err = ss_dem_write(check_file("x.h5"), SS_DEM_AUTO, &b);
	msg = capture_end();
	CHECK(err == SS_ERR_INPUT && strstr(msg, "HDF5"), "HDF5 is not written here: %s", msg);
	b.cellsize = b.cellsize_y = NAN;
	capture_begin();
	err = ss_dem_write(check_file("nocell.asc"), SS_DEM_AUTO, &b);
	msg = capture_end();
	CHECK(err == SS_ERR_INPUT && strstr(msg, "cell size"), "asc needs a cell size: %s", msg);
	CHECK(access(check_file("nocell.asc"), F_OK) != 0, "and nothing was written");

	char *after = slurp(check_file("src.asc"), &n1);
	CHECK(before && after && n0 == n1 && !memcmp(before, after, n0), "the input is unchanged");
	CHECK(hidden_files() == 0, "no temporary file left after failures");
	free(before);
	free(after);
	ss_raster_release(&b);
}

static void nodata_value_avoids_real_heights(void)
{
	struct ss_raster a, b;
	ss_raster_init(&a, 3, 1);
	a.cellsize = a.cellsize_y = 1.0;
	a.x0 = a.y0 = 0.0;
	a.values[0] = -9999.0;   /* a real height equal to the usual marker */
	a.nodata = calloc(3, 1);
	a.nodata[2] = 1;
	CHECK(ss_dem_write(check_file("nd.asc"), SS_DEM_AUTO, &a) == SS_OK, "write nd.asc");
	CHECK(ss_dem_read(check_file("nd.asc"), NULL, NULL, &b) == SS_OK, "read nd.asc");
	CHECK(b.nodata_value == -99999.0 && b.values[0] == -9999.0 && same_flags(&a, &b),
	      "another marker is chosen, %g, and the height survives", b.nodata_value);
	ss_raster_release(&a);
	ss_raster_release(&b);
}

static const char utm33n[] =
	"PROJCS[\"WGS 84 / UTM zone 33N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\","
	"SPHEROID[\"WGS 84\",6378137,298.257223563]],PRIMEM[\"Greenwich\",0],"
	"UNIT[\"degree\",0.0174532925199433]],PROJECTION[\"Transverse_Mercator\"],"
	"PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\",15],"
	"PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],"
	"PARAMETER[\"false_northing\",0],UNIT[\"metre\",1],AUTHORITY[\"EPSG\",\"32633\"]]";

static void geotiff_round_trip(void)
{
	struct rng g = {31337};
	struct ss_raster a, b, c;
	random_raster(&a, 17, 11, &g, 1);
	if (!ss_dem_gdal_available()) {
		capture_begin();
		int err = ss_dem_write(check_file("g.tif"), SS_DEM_AUTO, &a);
		const char *msg = capture_end();
		CHECK(err == SS_ERR_INPUT && strstr(msg, "unavailable in this build"),
		      "without GDAL a .tif is refused clearly: %s", msg);
		check_write_file(check_file("g.tif"), "II*");
		capture_begin();
		err = ss_dem_read(check_file("g.tif"), NULL, NULL, &b);
		msg = capture_end();
		ss_raster_release(&b);
		CHECK(err == SS_ERR_INPUT && strstr(msg, "unavailable in this build") &&
		      strstr(msg, ".asc"), "reading too: %s", msg);
		CHECK_SKIP("the GeoTIFF round trip: this build has no GDAL (made with GDAL=0 or "
		           "MPI=1, or without Debian package libgdal-dev)");
		ss_raster_release(&a);
		return;
	}
	a.cellsize = 30.0;
	a.cellsize_y = 20.0;   /* rectangular pixels */
	a.x0 = 500000.0;
	a.y0 = 4649776.22482;
	a.crs_wkt = strdup(utm33n);
	a.has_nodata_value = 1;
	a.nodata_value = -32768.0;
	int err = ss_dem_write(check_file("g.tif"), SS_DEM_AUTO, &a);
	CHECK(err == SS_OK, "write g.tif: %d", err);
	err = ss_dem_read(check_file("g.tif"), NULL, NULL, &b);
	CHECK(err == SS_OK, "read g.tif: %d", err);
	CHECK(b.format == SS_DEM_GDAL && same_values(&a, &b) && same_flags(&a, &b),
	      "values bit-identical, nodata flags kept");
	CHECK(b.has_geotransform && b.geotransform[0] == 500000.0 && b.geotransform[1] == 30.0 &&
	      b.geotransform[2] == 0.0 && b.geotransform[3] == a.y0 + 11 * 20.0 &&
	      b.geotransform[4] == 0.0 && b.geotransform[5] == -20.0,
	      "geotransform %.17g %g %g %.17g %g %g", b.geotransform[0], b.geotransform[1],
	      b.geotransform[2], b.geotransform[3], b.geotransform[4], b.geotransform[5]);
	CHECK(b.cellsize == 30.0 && b.cellsize_y == 20.0 && b.x0 == 500000.0 &&
	      fabs(b.y0 - a.y0) <= 1e-9, "cell size and corner");
	CHECK(b.has_nodata_value && b.nodata_value == -32768.0, "nodata value %g", b.nodata_value);
	CHECK(b.crs_wkt && strstr(b.crs_wkt, "UTM zone 33N") && strstr(b.crs_wkt, "32633"),
	      "CRS kept: %s", b.crs_wkt ? b.crs_wkt : "(none)");

	/* again from what was read: geotransform and CRS exactly as read */
	err = ss_dem_write(check_file("g2.tif"), SS_DEM_GDAL, &b);
	CHECK(err == SS_OK && ss_dem_read(check_file("g2.tif"), NULL, NULL, &c) == SS_OK, "g2.tif");
	CHECK(same_values(&b, &c) && same_flags(&b, &c) &&
	      !memcmp(b.geotransform, c.geotransform, sizeof b.geotransform) &&
	      c.crs_wkt && !strcmp(b.crs_wkt, c.crs_wkt), "second round trip identical");
	ss_raster_release(&c);

	/* a GeoTIFF to .asc keeps the corner and nodata */
	b.cellsize_y = b.cellsize = 30.0;
	b.has_geotransform = 0;
	err = ss_dem_write(check_file("g.asc"), SS_DEM_AUTO, &b);
	CHECK(err == SS_OK && ss_dem_read(check_file("g.asc"), NULL, NULL, &c) == SS_OK &&
	      same_values(&b, &c) && same_flags(&b, &c) && c.nodata_value == -32768.0 &&
	      c.x0 == 500000.0, "GeoTIFF to .asc");
	CHECK(c.crs_wkt && strstr(c.crs_wkt, "UTM zone 33N") && exists(check_file("g.prj")),
	      "and its CRS in g.prj: %s", c.crs_wkt ? c.crs_wkt : "(none)");
	ss_raster_release(&c);

	/* a rotated geotransform is refused */
	const double rotated[6] = {0, 1, 0.5, 0, 0.5, -1};
	memcpy(b.geotransform, rotated, sizeof rotated);
	b.has_geotransform = 1;
	CHECK(ss_dem_write(check_file("rot.tif"), SS_DEM_AUTO, &b) == SS_OK, "write rot.tif");
	capture_begin();
	err = ss_dem_read(check_file("rot.tif"), NULL, NULL, &c);
	const char *msg = capture_end();
	ss_raster_release(&c);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "rotated") && strstr(msg, "north-up"),
	      "rotated refused: %s", msg);

	/* something that is no raster */
	check_write_file(check_file("junk.tif"), "II*\0 this is not a TIFF");
	capture_begin();
	err = ss_dem_read(check_file("junk.tif"), "case.ini:4", NULL, &c);
	msg = capture_end();
	ss_raster_release(&c);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "case.ini:4") && strstr(msg, "junk.tif") &&
	      strstr(msg, ".asc"), "a broken TIFF: %s", msg);
	CHECK(hidden_files() == 0, "no temporary file left");
	ss_raster_release(&a);
	ss_raster_release(&b);
}

/* ------------------------------------------------------------------ */
/* the CRS of an .asc: the .prj beside it                               */

/* What GDAL 3.6 writes as dem.prj for EPSG:32633 (gdal_translate -of AAIGrid). */
static const char utm33n_esri[] =
	"PROJCS[\"WGS_1984_UTM_Zone_33N\",GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\","
	"SPHEROID[\"WGS_1984\",6378137.0,298.257223563]],PRIMEM[\"Greenwich\",0.0],"
	"UNIT[\"Degree\",0.0174532925199433]],PROJECTION[\"Transverse_Mercator\"],"
	"PARAMETER[\"False_Easting\",500000.0],PARAMETER[\"False_Northing\",0.0],"
	"PARAMETER[\"Central_Meridian\",15.0],PARAMETER[\"Scale_Factor\",0.9996],"
	"PARAMETER[\"Latitude_Of_Origin\",0.0],UNIT[\"Meter\",1.0]]";

static const char small_asc[] =
	"ncols 3\nnrows 2\nxllcorner 500000\nyllcorner 5200000\ncellsize 2\n1 2 3\n4 5 6\n";

static void asc_prj_round_trip(void)
{
	check_write_file(check_file("p.asc"), small_asc);
	check_write_file(check_file("p.prj"), utm33n_esri);
	struct ss_raster a, b;
	int err = ss_dem_read(check_file("p.asc"), NULL, NULL, &a);
	CHECK(err == SS_OK, "read p.asc with p.prj: %d", err);
	/* with GDAL the OGC WKT gdalinfo shows (importFromESRI); without, as read */
	if (ss_dem_gdal_available())
		CHECK(a.crs_wkt && strstr(a.crs_wkt, "PROJCS[\"WGS 84 / UTM zone 33N\"") &&
		      strstr(a.crs_wkt, "\"central_meridian\",15"), "CRS as OGC WKT: %s",
		      a.crs_wkt ? a.crs_wkt : "(none)");
	else
		CHECK(a.crs_wkt && !strcmp(a.crs_wkt, utm33n_esri), "CRS as read: %s",
		      a.crs_wkt ? a.crs_wkt : "(none)");

	err = ss_dem_write(check_file("q.asc"), SS_DEM_AUTO, &a);
	CHECK(err == SS_OK, "write q.asc: %d", err);
	size_t n;
	char *text = slurp(check_file("q.prj"), &n);
	CHECK(text && !strcmp(text, utm33n_esri), "q.prj in ESRI WKT, the text GDAL writes: %s",
	      text ? text : "(none)");
	free(text);
	CHECK(ss_dem_read(check_file("q.asc"), NULL, NULL, &b) == SS_OK && b.crs_wkt &&
	      a.crs_wkt && !strcmp(a.crs_wkt, b.crs_wkt), "the same CRS read back");
	CHECK(same_values(&a, &b), "and the same heights");
	ss_raster_release(&b);

	/* GDAL's other spelling, X.PRJ, when there is no X.prj */
	check_write_file(check_file("u.asc"), small_asc);
	check_write_file(check_file("u.PRJ"), utm33n_esri);
	CHECK(ss_dem_read(check_file("u.asc"), NULL, NULL, &b) == SS_OK && b.crs_wkt &&
	      !strcmp(a.crs_wkt, b.crs_wkt), "u.PRJ read as u.asc's CRS");
	ss_raster_release(&b);

	/* the input's .prj is never replaced, even through another name */
	capture_begin();
	err = ss_dem_write(check_file("p.ASC"), SS_DEM_ASC, &a);
	const char *msg = capture_end();
	CHECK(err == SS_ERR_INPUT && strstr(msg, "p.prj") && strstr(msg, "never modified"),
	      "writing p.ASC over p.asc's p.prj refused: %s", msg);
	capture_begin();
	err = ss_dem_check_not_source(check_file("p.ASC"), &a);
	capture_end();
	CHECK(err == SS_ERR_INPUT, "and so ss_dem_check_not_source says, before any work");
	CHECK(!exists(check_file("p.ASC")), "nothing written");
	text = slurp(check_file("p.prj"), &n);
	CHECK(text && !strcmp(text, utm33n_esri), "p.prj untouched");
	free(text);
	CHECK(hidden_files() == 0, "no temporary file left");
	ss_raster_release(&a);
}

static void asc_without_crs_has_no_prj(void)
{
	check_write_file(check_file("n.asc"), small_asc);
	struct ss_raster a, b;
	CHECK(ss_dem_read(check_file("n.asc"), NULL, NULL, &a) == SS_OK && !a.crs_wkt,
	      "no .prj: no CRS");
	CHECK(ss_dem_write(check_file("m.asc"), SS_DEM_AUTO, &a) == SS_OK, "write m.asc");
	CHECK(!exists(check_file("m.prj")) && !exists(check_file("m.PRJ")), "and no m.prj");

	/* a .prj left by an earlier m.asc would claim a CRS for this one */
	check_write_file(check_file("m.prj"), utm33n_esri);
	check_write_file(check_file("m.PRJ"), utm33n_esri);
	CHECK(ss_dem_write(check_file("m.asc"), SS_DEM_AUTO, &a) == SS_OK, "write m.asc again");
	CHECK(!exists(check_file("m.prj")) && !exists(check_file("m.PRJ")),
	      "the stale m.prj and m.PRJ removed");
	CHECK(ss_dem_read(check_file("m.asc"), NULL, NULL, &b) == SS_OK && !b.crs_wkt,
	      "m.asc reads without a CRS");
	ss_raster_release(&b);

	/* a failed write leaves an earlier grid's .prj with it */
	check_write_file(check_file("m.prj"), utm33n_esri);
	a.values[1] = NAN;
	capture_begin();
	const int err = ss_dem_write(check_file("m.asc"), SS_DEM_AUTO, &a);
	capture_end();
	CHECK(err == SS_ERR_FAIL && exists(check_file("m.prj")), "a failed write keeps m.prj");
	unlink(check_file("m.prj"));
	CHECK(hidden_files() == 0, "no temporary file left");
	ss_raster_release(&a);
}

/* A .prj that is there but is no CRS is refused naming it, rather than
 * read as none. */
static void asc_bad_prj_is_refused(void)
{
	static const struct {
		const char *text;
		const char *words[3];
	} bad[] = {
		{"", {"b.prj", "b.asc", "empty"}},
		{"  \n\n", {"b.prj", "empty"}},
		{"this is not a CRS\n", {"b.prj", "b.asc", "fix or remove it"}},
		{"PROJCS[\"cut short\",GEOGCS[", {"b.prj", "fix or remove it"}},
		/* a geographic CRS: degrees, refused as a GeoTIFF in degrees is */
		{"GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137.0,"
		 "298.257223563]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]",
		 {"b.asc", "degrees, not metres", "gdalwarp -t_srs EPSG:32632"}},
	};
	/* around 8.5 E, 47.4 N: UTM zone 32 north */
	check_write_file(check_file("b.asc"), "ncols 2\nnrows 2\nxllcorner 8.5\nyllcorner 47.4\n"
	                                      "cellsize 0.001\n1 2\n3 4\n");
	for (size_t a = 0; a < sizeof bad / sizeof *bad; a++) {
		check_write_file(check_file("b.prj"), bad[a].text);
		struct ss_raster r;
		capture_begin();
		int err = ss_dem_read(check_file("b.asc"), "case.ini:3", NULL, &r);
		const char *msg = capture_end();
		ss_raster_release(&r);
		CHECK(err == SS_ERR_INPUT, "case %zu: status %d", a, err);
		CHECK(strstr(msg, "case.ini:3") != NULL, "case %zu names where: %s", a, msg);
		for (int w = 0; w < 3 && bad[a].words[w]; w++)
			CHECK(strstr(msg, bad[a].words[w]) != NULL, "case %zu: '%s' in: %s", a,
			      bad[a].words[w], msg);
		CHECK(strchr(msg, '\n') == msg + strlen(msg) - 1, "case %zu: one message: %s", a, msg);
	}
	/* one that cannot be read: a folder of that name */
	unlink(check_file("b.prj"));
	CHECK(mkdir(check_file("b.prj"), 0700) == 0, "mkdir b.prj");
	struct ss_raster r;
	capture_begin();
	int err = ss_dem_read(check_file("b.asc"), NULL, NULL, &r);
	const char *msg = capture_end();
	ss_raster_release(&r);
	CHECK(err == SS_ERR_INPUT && strstr(msg, "b.prj") && strstr(msg, "b.asc"),
	      "an unreadable .prj: %s", msg);
	rmdir(check_file("b.prj"));
}

/* A window (dem.h) holds exactly the whole raster's rows row_first ..
 * row_first + rows - 1, with their nodata flags, in every format a rank
 * reads; rows = 0 is the header alone; a window past the rows is refused. */
static void windows_are_the_whole_rasters_rows(void)
{
	struct rng g = {4242};
	struct ss_raster a;
	random_raster(&a, 13, 9, &g, 1);
	a.png_zmin = -2.0;
	a.png_zmax = 8.0;
	const char *names[] = {"w.asc", "w.png", "w.tif"};
	const int windows[][2] = {{0, 9}, {0, 1}, {3, 4}, {8, 1}, {2, 0}};
	for (int f = 0; f < 3; f++) {
		if (f == 2 && !ss_dem_gdal_available())
			continue;
		CHECK(ss_dem_write(check_file(names[f]), SS_DEM_AUTO, &a) == SS_OK, "%s written",
		      names[f]);
		struct ss_raster whole, w;
		CHECK(ss_dem_read(check_file(names[f]), NULL, NULL, &whole) == SS_OK, "%s read",
		      names[f]);
		for (size_t k = 0; k < sizeof windows / sizeof *windows; k++) {
			struct ss_dem_read_options o;
			ss_dem_read_options_init(&o);
			o.row_first = windows[k][0];
			o.rows = windows[k][1];
			const int err = ss_dem_read(check_file(names[f]), NULL, &o, &w);
			const size_t n = (size_t)w.nx * (size_t)o.rows;
			const size_t at = (size_t)o.row_first * (size_t)whole.nx;
			int same = err == SS_OK && w.nx == whole.nx && w.ny == whole.ny &&
			           w.row_first == o.row_first && w.rows == o.rows &&
			           (n == 0 || memcmp(w.values, whole.values + at, n * sizeof(double)) == 0);
			for (size_t m = 0; same && m < n; m++)
				same = (w.nodata && w.nodata[m]) == (whole.nodata && whole.nodata[at + m]);
			CHECK(same, "%s: the window of rows %d + %d is not those rows of the whole "
			      "raster (%d)", names[f], o.row_first, o.rows, err);
			ss_raster_release(&w);
		}
		struct ss_dem_read_options past;
		ss_dem_read_options_init(&past);
		past.row_first = 7;
		past.rows = 3;
		capture_begin();
		const int err = ss_dem_read(check_file(names[f]), NULL, &past, &w);
		const char *msg = capture_end();
		CHECK(err == SS_ERR_INPUT && strstr(msg, "has 9 rows"),
		      "%s: rows 7 to 9 of 9 are refused naming the rows: %s", names[f], msg);
		ss_raster_release(&w);
		ss_raster_release(&whole);
		unlink(check_file(names[f]));
	}
	ss_raster_release(&a);
}

int main(void)
{
	if (check_scratch_make("test_dem"))
		return 2;
	RUN(format_from_path);
	RUN(asc_round_trip_is_bit_exact);
	RUN(asc_keeps_centre_and_rectangular_cells);
	RUN(asc_malformed_is_refused);
	RUN(cellsize_option_must_agree);
	RUN(png16_round_trip);
	RUN(png_from_renderer_convention);
	RUN(png_with_explicit_scale);
	RUN(png_not_gray16_is_refused);
	RUN(png_too_short_for_its_size_is_refused);
	RUN(png_chunk_longer_than_file_is_refused);
	RUN(writes_are_atomic_and_spare_the_input);
	RUN(nodata_value_avoids_real_heights);
	RUN(geotiff_round_trip);
	RUN(windows_are_the_whole_rasters_rows);
	RUN(asc_prj_round_trip);
	RUN(asc_without_crs_has_no_prj);
	RUN(asc_bad_prj_is_refused);
	check_scratch_remove();
	return check_report();
}
