/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * dem_asc.c - ESRI ASCII grids (see dem.h).
 *
 * Header "key value" lines (any case, any order): ncols, nrows, xllcorner or
 * xllcenter, yllcorner or yllcenter, cellsize (or dx and dy, GDAL's form for
 * rectangular cells), optional NODATA_value; then nrows rows of ncols
 * values, north row first.  Values are written with "%.17g" (header
 * numbers with the fewest digits that read back the same), which strtod
 * reads back to the same double, so a grid read and written again keeps
 * every bit.
 */
#include "io/dem_internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "sandslide/error.h"

/* A cursor over a file that knows its line: the text is streamed through
 * stdio's buffer, never held whole, so that a rank reads its window of a
 * grid of any size in bounded memory.  A token read ahead (the header's
 * end is the first number) is kept in `ahead`. */
struct scan {
	FILE *f;
	int line;
	char ahead[128];
	int has_ahead;
};

/* Next white-space separated token into buf (cut at size - 1 characters);
 * 0 at the end of the file. */
static int next_token(struct scan *sc, char *buf, size_t size)
{
	if (sc->has_ahead) {
		snprintf(buf, size, "%s", sc->ahead);
		sc->has_ahead = 0;
		return 1;
	}
	int c;
	while ((c = getc_unlocked(sc->f)) != EOF && isspace(c)) {
		if (c == '\n')
			sc->line++;
	}
	if (c == EOF)
		return 0;
	size_t n = 0;
	do {
		if (n + 1 < size)
			buf[n++] = (char)c;
	} while ((c = getc_unlocked(sc->f)) != EOF && !isspace(c));
	if (c == '\n')
		ungetc(c, sc->f);   /* counted by the next call */
	buf[n] = '\0';
	return 1;
}

/* Skip n tokens (rows outside the window: not converted, not checked);
 * the number skipped, fewer at the end of the file. */
static size_t skip_tokens(struct scan *sc, size_t n)
{
	size_t done = 0;
	if (n > 0 && sc->has_ahead) {
		sc->has_ahead = 0;
		done++;
	}
	int c = ' ';
	while (done < n) {
		while ((c = getc_unlocked(sc->f)) != EOF && isspace(c))
			sc->line += c == '\n';
		if (c == EOF)
			break;
		while ((c = getc_unlocked(sc->f)) != EOF && !isspace(c)) {
		}
		sc->line += c == '\n';
		done++;
	}
	return done;
}

static int to_double(const char *t, double *v)
{
	char *end;
	errno = 0;
	*v = strtod(t, &end);
	/* ERANGE on underflow still gives the nearest double: only overflow
	 * (an infinite result from finite digits) is refused */
	return end != t && *end == '\0' && !(errno == ERANGE && isinf(*v)) ? 0 : -1;
}

/* Header keys; the two spellings of a corner share a slot. */
enum { K_NCOLS, K_NROWS, K_XLL, K_YLL, K_CELL, K_DX, K_DY, K_NODATA, K_COUNT };

static int header_key(const char *name, int *center)
{
	static const char *const names[] = {"ncols", "nrows", "xllcorner", "yllcorner", "cellsize",
	                                    "dx", "dy", "nodata_value"};
	*center = 0;
	if (!strcasecmp(name, "xllcenter") || !strcasecmp(name, "yllcenter")) {
		*center = 1;
		return tolower((unsigned char)name[0]) == 'x' ? K_XLL : K_YLL;
	}
	for (int k = 0; k < K_COUNT; k++) {
		if (!strcasecmp(name, names[k]))
			return k;
	}
	return -1;
}

/* The header as read: a value per key, where it was set, which corner. */
struct asc_header {
	double val[K_COUNT];
	int seen[K_COUNT], line[K_COUNT], center[K_COUNT];
};

/* The "key value" pairs before the first number; sc is left at it. */
static int read_header(struct scan *sc, const char *path, const char *context,
                       struct asc_header *h)
{
	char tok[128], key[128];
	memset(h, 0, sizeof *h);
	for (int k = 0; k < K_COUNT; k++)
		h->val[k] = NAN;
	while (next_token(sc, tok, sizeof tok)) {
		if (!isalpha((unsigned char)tok[0]) || !strcasecmp(tok, "nan") ||
		    !strcasecmp(tok, "inf") || !strcasecmp(tok, "infinity")) {
			/* the first value: kept for read_values */
			snprintf(sc->ahead, sizeof sc->ahead, "%s", tok);
			sc->has_ahead = 1;
			break;
		}
		snprintf(key, sizeof key, "%s", tok);
		const int key_line = sc->line;
		int is_center;
		const int k = header_key(key, &is_center);
		double v;
		if (k < 0)
			return ss_error_input_at(context, "%s:%d: unknown header key '%s': expected "
			                         "ncols, nrows, xllcorner or xllcenter, yllcorner or "
			                         "yllcenter, cellsize (or dx and dy), NODATA_value",
			                         path, key_line, key);
		if (h->seen[k])
			return ss_error_input_at(context, "%s:%d: header key '%s' repeats line %d", path,
			                         key_line, key, h->line[k]);
		if (!next_token(sc, tok, sizeof tok) || to_double(tok, &v))
			return ss_error_input_at(context, "%s:%d: header key '%s' has no numeric value",
			                         path, key_line, key);
		h->seen[k] = 1;
		h->line[k] = key_line;
		h->center[k] = is_center;
		h->val[k] = v;
	}
	return SS_OK;
}

/* The header's size, corner, cell size and nodata value into r, checked. */
static int apply_header(const struct asc_header *h, const char *path, const char *context,
                        struct ss_raster *r)
{
	for (int k = K_NCOLS; k <= K_NROWS; k++)
		if (!h->seen[k] || !(h->val[k] >= 1 && h->val[k] <= 1 << 30 &&
		                     h->val[k] == floor(h->val[k])))
			return ss_error_input_at(context, "%s: ESRI ASCII header needs ncols and nrows, "
			                         "integers from 1 to 2^30", path);
	if (!h->seen[K_XLL] || !h->seen[K_YLL] || !isfinite(h->val[K_XLL]) ||
	    !isfinite(h->val[K_YLL]))
		return ss_error_input_at(context, "%s: ESRI ASCII header needs the lower-left "
		                         "corner: xllcorner and yllcorner (or xllcenter and "
		                         "yllcenter), finite numbers", path);
	if (h->center[K_XLL] != h->center[K_YLL])
		return ss_error_input_at(context, "%s:%d: mixes a corner and a centre: expected "
		                         "xllcorner with yllcorner, or xllcenter with yllcenter",
		                         path, h->line[K_YLL]);
	const int square = h->seen[K_CELL] && !h->seen[K_DX] && !h->seen[K_DY];
	if (!square && !(!h->seen[K_CELL] && h->seen[K_DX] && h->seen[K_DY]))
		return ss_error_input_at(context, "%s: ESRI ASCII header needs cellsize, or dx and "
		                         "dy (not both forms)", path);
	const double dx = square ? h->val[K_CELL] : h->val[K_DX];
	const double dy = square ? h->val[K_CELL] : h->val[K_DY];
	if (!(dx > 0.0 && dy > 0.0 && isfinite(dx) && isfinite(dy)))
		return ss_error_input_at(context, "%s: ESRI ASCII cell size %g x %g: expected "
		                         "numbers > 0", path, dx, dy);
	r->nx = (int)h->val[K_NCOLS];
	r->ny = (int)h->val[K_NROWS];
	r->cellsize = dx;
	r->cellsize_y = dy;
	r->asc_center = h->center[K_XLL];
	r->x0 = r->asc_center ? h->val[K_XLL] - 0.5 * dx : h->val[K_XLL];
	r->y0 = r->asc_center ? h->val[K_YLL] - 0.5 * dy : h->val[K_YLL];
	r->has_nodata_value = h->seen[K_NODATA];
	r->nodata_value = h->seen[K_NODATA] ? h->val[K_NODATA] : NAN;
	return SS_OK;
}

/* One value of the grid, file row `row` (north first), column i, into r
 * (whose window holds that row); a NODATA_value marks the cell. */
static int store_value(struct ss_raster *r, const char *tok, int line, int row, int i,
                       const char *path, const char *context)
{
	const size_t m = (size_t)(r->ny - 1 - row - r->row_first) * r->nx + i;
	const double nodata = r->nodata_value;
	double v;
	if (to_double(tok, &v))
		return ss_error_input_at(context, "%s:%d: '%s' (%s) is not a number", path, line, tok,
		                         SS_RASTER_CELL(r, i, r->ny - 1 - row));
	if (r->has_nodata_value && (v == nodata || (isnan(v) && isnan(nodata)))) {
		if (!r->nodata && !(r->nodata = ss_alloc(ss_raster_cells(r), 1, "nodata flags")))
			return SS_ERR_FAIL;
		r->nodata[m] = 1;
		v = 0.0;
	} else if (!isfinite(v)) {
		return ss_error_input_at(context, "%s:%d: height '%s' (%s) is not finite: heights "
		                         "must be finite numbers (mark missing cells with "
		                         "NODATA_value)", path, line, tok,
		                         SS_RASTER_CELL(r, i, r->ny - 1 - row));
	}
	r->values[m] = v;
	return SS_OK;
}

/* The values after the header, north row first: the window's rows kept,
 * the rows north of it skipped, the file read no further than the window
 * unless it ends at the south row, when exactly nrows x ncols values must
 * follow. */
static int read_values(struct scan *sc, off_t file_bytes, const char *path,
                       const char *context, struct ss_raster *r)
{
	char tok[128];
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	/* a header of a few bytes must not claim gigabytes: n values need at
	 * least 2 n - 1 bytes, and a shorter file is counted (it is small)
	 * and refused before the heights are allocated */
	if ((double)file_bytes < 2.0 * (double)n - 1.0) {
		const size_t given = skip_tokens(sc, n);
		return ss_error_input_at(context, "%s: ends after %zu of %d x %d values", path, given,
		                         r->nx, r->ny);
	}
	if (!(r->values = ss_alloc(ss_raster_cells(r) ? ss_raster_cells(r) : 1, sizeof(double),
	                           "raster heights")))
		return SS_ERR_FAIL;
	const int north = r->ny - r->row_first - r->rows;   /* file rows before the window */
	size_t given = skip_tokens(sc, (size_t)north * r->nx);
	const size_t window_end = (size_t)(north + r->rows) * r->nx;
	for (size_t k = (size_t)north * r->nx; given == k && k < window_end; k++) {
		if (!next_token(sc, tok, sizeof tok))
			break;
		given++;
		const int err = store_value(r, tok, sc->line, (int)(k / r->nx), (int)(k % r->nx),
		                            path, context);
		if (err)
			return err;
	}
	if (r->row_first > 0 && given == window_end)
		return SS_OK;   /* the window ends north of the last row: the rank
		                   holding the south rows checks the file's end */
	if (given < n) {
		given += skip_tokens(sc, n - given);
		return ss_error_input_at(context, "%s: ends after %zu of %d x %d values", path, given,
		                         r->nx, r->ny);
	}
	if (next_token(sc, tok, sizeof tok))
		return ss_error_input_at(context, "%s:%d: more values than ncols x nrows = %d x %d",
		                         path, sc->line, r->nx, r->ny);
	return SS_OK;
}

int ss_dem_read_asc(const char *path, const char *context, const struct ss_dem_read_options *opt,
                    struct ss_raster *r)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_input_at(context, "cannot open '%s': %s", path, strerror(errno));
	struct stat sb;
	const off_t bytes = fstat(fileno(f), &sb) == 0 ? sb.st_size : 0;
	struct scan sc = {.f = f, .line = 1};
	struct asc_header h;
	int err = read_header(&sc, path, context, &h);
	if (!err)
		err = apply_header(&h, path, context, r);
	if (!err)
		err = ss_dem_window(opt, path, context, r);
	if (!err && r->rows > 0)
		err = read_values(&sc, bytes, path, context, r);
	if (!err && ferror(f))
		err = ss_error_input_at(context, "cannot read '%s': %s", path, strerror(errno));
	fclose(f);
	return err;
}

/* The shortest of %.15g, %.16g, %.17g that reads back as x, so that a
 * header says "cellsize 0.3", not 0.29999999999999999. */
static const char *exact(double x, char buf[32])
{
	for (int digits = 15; digits < 17; digits++) {
		snprintf(buf, 32, "%.*g", digits, x);
		if (strtod(buf, NULL) == x)
			return buf;
	}
	snprintf(buf, 32, "%.17g", x);
	return buf;
}

int ss_dem_asc_begin(struct ss_dem_writer *w)
{
	const struct ss_raster *r = w->head;
	FILE *f = w->f;
	const double dx = r->cellsize, dy = ss_dem_dy(r);
	if (!(dx > 0.0 && dy > 0.0))
		return ss_error_input("cannot write '%s' as an ESRI ASCII grid: the cell size is "
		                      "unknown (the input did not give one)", w->path);
	/* an unknown corner is written as the origin */
	const double x0 = isnan(r->x0) ? 0.0 : r->x0, y0 = isnan(r->y0) ? 0.0 : r->y0;
	char u[32], v[32];
	fprintf(f, "ncols %d\nnrows %d\n", r->nx, r->ny);
	if (r->asc_center)
		fprintf(f, "xllcenter %s\nyllcenter %s\n", exact(x0 + 0.5 * dx, u),
		        exact(y0 + 0.5 * dy, v));
	else
		fprintf(f, "xllcorner %s\nyllcorner %s\n", exact(x0, u), exact(y0, v));
	if (dx == dy)
		fprintf(f, "cellsize %s\n", exact(dx, u));
	else
		fprintf(f, "dx %s\ndy %s\n", exact(dx, u), exact(dy, v));
	if (w->has_nodata)
		fprintf(f, "NODATA_value %s\n", exact(w->nodata, u));
	if (ferror(f))
		return ss_error_fail("cannot write '%s': %s", w->path, strerror(errno));
	return SS_OK;
}

int ss_dem_asc_rows(struct ss_dem_writer *w, const double *values, int rows)
{
	const int nx = w->head->nx;
	for (int k = 0; k < rows; k++) {
		const double *row = values + (size_t)k * nx;
		for (int i = 0; i < nx; i++)
			fprintf(w->f, i ? " %.17g" : "%.17g", row[i]);
		if (putc('\n', w->f) == EOF)
			break;
	}
	if (ferror(w->f))
		return ss_error_fail("cannot write '%s': %s", w->path, strerror(errno));
	return SS_OK;
}
