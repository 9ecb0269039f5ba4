/*
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

#include "sandslide/error.h"

/* A cursor over text that knows its line. */
struct scan {
	const char *s;
	int line;
};

/* Next white-space separated token into buf; 0 at the end of the text. */
static int next_token(struct scan *sc, char *buf, size_t size)
{
	while (*sc->s && isspace((unsigned char)*sc->s)) {
		if (*sc->s == '\n')
			sc->line++;
		sc->s++;
	}
	if (!*sc->s)
		return 0;
	size_t n = 0;
	while (*sc->s && !isspace((unsigned char)*sc->s)) {
		if (n + 1 < size)
			buf[n++] = *sc->s;
		sc->s++;
	}
	buf[n] = '\0';
	return 1;
}

/* White-space separated tokens from s on, counting up to limit. */
static size_t count_tokens(const char *s, size_t limit)
{
	size_t n = 0;
	while (n < limit) {
		while (*s && isspace((unsigned char)*s))
			s++;
		if (!*s)
			break;
		n++;
		while (*s && !isspace((unsigned char)*s))
			s++;
	}
	return n;
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

static char *read_text(const char *path, const char *context, int *err)
{
	FILE *f = fopen(path, "rb");
	if (!f) {
		*err = ss_error_input_at(context, "cannot open '%s': %s", path, strerror(errno));
		return NULL;
	}
	char *text = NULL;
	size_t size = 0, cap = 0;
	for (;;) {
		if (cap - size < 65536) {
			cap = cap ? 2 * cap : 1 << 20;
			char *grown = realloc(text, cap);
			if (!grown) {
				free(text);
				fclose(f);
				*err = ss_error_fail("out of memory reading '%s'", path);
				return NULL;
			}
			text = grown;
		}
		size_t got = fread(text + size, 1, cap - size - 1, f);
		size += got;
		if (got == 0)
			break;
	}
	int bad = ferror(f);
	fclose(f);
	if (bad) {
		free(text);
		*err = ss_error_input_at(context, "cannot read '%s'", path);
		return NULL;
	}
	text[size] = '\0';
	return text;
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
	const char *mark = sc->s;
	int mark_line = sc->line;
	while (next_token(sc, tok, sizeof tok)) {
		if (!isalpha((unsigned char)tok[0]) || !strcasecmp(tok, "nan") ||
		    !strcasecmp(tok, "inf") || !strcasecmp(tok, "infinity")) {
			sc->s = mark;   /* the first value: rewind */
			sc->line = mark_line;
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
		mark = sc->s;
		mark_line = sc->line;
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

/* One value of the grid, file row `row` (north first), column i, into r;
 * a NODATA_value marks the cell. */
static int store_value(struct ss_raster *r, const char *tok, int line, int row, int i,
                       const char *path, const char *context)
{
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	const size_t m = (size_t)(r->ny - 1 - row) * r->nx + i;
	const double nodata = r->nodata_value;
	double v;
	if (to_double(tok, &v))
		return ss_error_input_at(context, "%s:%d: '%s' (row %d, column %d) is not a number",
		                         path, line, tok, row + 1, i + 1);
	if (r->has_nodata_value && (v == nodata || (isnan(v) && isnan(nodata)))) {
		if (!r->nodata && !(r->nodata = ss_alloc(n, 1, "nodata flags")))
			return SS_ERR_FAIL;
		r->nodata[m] = 1;
		v = 0.0;
	} else if (!isfinite(v)) {
		return ss_error_input_at(context, "%s:%d: height '%s' (row %d, column %d) is not "
		                         "finite: heights must be finite numbers (mark missing "
		                         "cells with NODATA_value)", path, line, tok, row + 1, i + 1);
	}
	r->values[m] = v;
	return SS_OK;
}

/* The nrows x ncols values after the header, north row first; exactly
 * that many. */
static int read_values(struct scan *sc, const char *path, const char *context,
                       struct ss_raster *r)
{
	char tok[128];
	/* a short file is refused before the heights are allocated: a header
	 * of a few bytes must not claim gigabytes */
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	const size_t given = count_tokens(sc->s, n);
	if (given < n)
		return ss_error_input_at(context, "%s: ends after %zu of %d x %d values", path, given,
		                         r->nx, r->ny);
	if (!(r->values = ss_alloc(n, sizeof(double), "raster heights")))
		return SS_ERR_FAIL;
	for (int row = 0; row < r->ny; row++) {
		for (int i = 0; i < r->nx; i++) {
			next_token(sc, tok, sizeof tok);   /* counted above */
			const int err = store_value(r, tok, sc->line, row, i, path, context);
			if (err)
				return err;
		}
	}
	if (next_token(sc, tok, sizeof tok))
		return ss_error_input_at(context, "%s:%d: more values than ncols x nrows = %d x %d",
		                         path, sc->line, r->nx, r->ny);
	return SS_OK;
}

int ss_dem_read_asc(const char *path, const char *context, const struct ss_dem_read_options *opt,
                    struct ss_raster *r)
{
	(void)opt;   /* the cell size option is checked by dem.c */
	int err = SS_OK;
	char *text = read_text(path, context, &err);
	if (!text)
		return err;
	struct scan sc = {text, 1};
	struct asc_header h;
	if (!(err = read_header(&sc, path, context, &h)) &&
	    !(err = apply_header(&h, path, context, r)))
		err = read_values(&sc, path, context, r);
	free(text);
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

int ss_dem_write_asc(FILE *f, const char *path, const struct ss_raster *r)
{
	const double dx = r->cellsize, dy = ss_dem_dy(r);
	if (!(dx > 0.0 && dy > 0.0))
		return ss_error_input("cannot write '%s' as an ESRI ASCII grid: the cell size is "
		                      "unknown (the input did not give one)", path);
	int has_nodata;
	double nodata;
	int err = ss_dem_pick_nodata(r, path, 0, &has_nodata, &nodata);
	if (err)
		return err;
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
	if (has_nodata)
		fprintf(f, "NODATA_value %s\n", exact(nodata, u));
	for (int j = r->ny - 1; j >= 0; j--) {
		const double *row = r->values + (size_t)j * r->nx;
		const uint8_t *flag = r->nodata ? r->nodata + (size_t)j * r->nx : NULL;
		for (int i = 0; i < r->nx; i++)
			fprintf(f, i ? " %.17g" : "%.17g", flag && flag[i] ? nodata : row[i]);
		if (putc('\n', f) == EOF)
			break;
	}
	if (ferror(f))
		return ss_error_fail("cannot write '%s': %s", path, strerror(errno));
	return SS_OK;
}
