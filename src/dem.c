/*
 * dem.c - raster readers (see dem.h).
 */
#include "sandslide/dem.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "sandslide/error.h"
#include "sandslide/snapshot.h"

void ss_raster_release(struct ss_raster *r)
{
	ss_free(r->values);
	ss_free(r->nodata);
	memset(r, 0, sizeof *r);
}

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

static int to_double(const char *t, double *v)
{
	char *end;
	errno = 0;
	*v = strtod(t, &end);
	return end != t && *end == '\0' && errno != ERANGE ? 0 : -1;
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

static int read_asc(const char *path, const char *context, struct ss_raster *r)
{
	int err = SS_OK;
	char *text = read_text(path, context, &err);
	if (!text)
		return err;
	struct scan sc = {text, 1};
	char tok[128];
	double ncols = NAN, nrows = NAN, cell = NAN, x = NAN, y = NAN, nodata = NAN;
	int x_center = 0, y_center = 0, have_nodata = 0;

	/* header: "key value" pairs until the first number */
	const char *mark = sc.s;
	int mark_line = sc.line;
	while (next_token(&sc, tok, sizeof tok)) {
		double v;
		if (!isalpha((unsigned char)tok[0]) || !strcasecmp(tok, "nan") ||
		    !strcasecmp(tok, "inf") || !strcasecmp(tok, "infinity")) {
			sc.s = mark;   /* the first value: rewind */
			sc.line = mark_line;
			break;
		}
		char key[128];
		snprintf(key, sizeof key, "%s", tok);
		int key_line = sc.line;
		if (!next_token(&sc, tok, sizeof tok) || to_double(tok, &v)) {
			err = ss_error_input_at(context, "%s:%d: header key '%s' has no numeric value", path,
			                     key_line, key);
			goto out;
		}
		if (!strcasecmp(key, "ncols"))
			ncols = v;
		else if (!strcasecmp(key, "nrows"))
			nrows = v;
		else if (!strcasecmp(key, "cellsize"))
			cell = v;
		else if (!strcasecmp(key, "xllcorner") || !strcasecmp(key, "xllcenter"))
			x = v, x_center = !strcasecmp(key, "xllcenter");
		else if (!strcasecmp(key, "yllcorner") || !strcasecmp(key, "yllcenter"))
			y = v, y_center = !strcasecmp(key, "yllcenter");
		else if (!strcasecmp(key, "nodata_value"))
			nodata = v, have_nodata = 1;
		else {
			err = ss_error_input_at(context, "%s:%d: unknown header key '%s': expected ncols, nrows, "
			                     "xllcorner, yllcorner, cellsize, NODATA_value", path,
			                     key_line, key);
			goto out;
		}
		mark = sc.s;
		mark_line = sc.line;
	}
	if (!(ncols >= 1 && ncols <= 1 << 30 && ncols == floor(ncols)) ||
	    !(nrows >= 1 && nrows <= 1 << 30 && nrows == floor(nrows))) {
		err = ss_error_input_at(context, "%s: ESRI ASCII header needs ncols and nrows, integers >= 1",
		                     path);
		goto out;
	}
	if (!(cell > 0.0)) {
		err = ss_error_input_at(context, "%s: ESRI ASCII header needs cellsize > 0", path);
		goto out;
	}
	r->nx = (int)ncols;
	r->ny = (int)nrows;
	r->cellsize = cell;
	r->x0 = x_center ? x - 0.5 * cell : x;
	r->y0 = y_center ? y - 0.5 * cell : y;
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	r->values = ss_alloc(n, sizeof(double), "raster heights");
	if (!r->values) {
		err = SS_ERR_FAIL;
		goto out;
	}
	for (int row = 0; row < r->ny; row++) {   /* north row first in the file */
		const int j = r->ny - 1 - row;
		for (int i = 0; i < r->nx; i++) {
			double v;
			if (!next_token(&sc, tok, sizeof tok)) {
				err = ss_error_input_at(context, "%s: ends after %d of %d x %d values", path,
				                     row * r->nx + i, r->nx, r->ny);
				goto out;
			}
			if (to_double(tok, &v)) {
				err = ss_error_input_at(context, "%s:%d: '%s' (row %d, column %d) is not a number",
				                     path, sc.line, tok, row + 1, i + 1);
				goto out;
			}
			if (have_nodata && v == nodata) {
				if (!r->nodata && !(r->nodata = ss_alloc(n, 1, "nodata flags"))) {
					err = SS_ERR_FAIL;
					goto out;
				}
				r->nodata[(size_t)j * r->nx + i] = 1;
				v = 0.0;
			} else if (!isfinite(v)) {
				err = ss_error_input_at(context, "%s:%d: height '%s' (row %d, column %d) is not "
				                     "finite: heights must be finite numbers (mark "
				                     "missing cells with NODATA_value)", path, sc.line,
				                     tok, row + 1, i + 1);
				goto out;
			}
			r->values[(size_t)j * r->nx + i] = v;
		}
	}
	if (next_token(&sc, tok, sizeof tok))
		err = ss_error_input_at(context, "%s:%d: more values than ncols x nrows = %d x %d", path,
		                     sc.line, r->nx, r->ny);
out:
	free(text);
	return err;
}

static int read_h5(const char *spec, const char *context, struct ss_raster *r)
{
	/* "file.h5" or "file.h5:/dataset" */
	char path[4096];
	const char *dataset = NULL;
	const char *colon = strstr(spec, ".h5:");
	if (colon) {
		size_t n = (size_t)(colon - spec) + 3;
		snprintf(path, sizeof path, "%.*s", (int)n, spec);
		dataset = colon + 4;
	} else {
		snprintf(path, sizeof path, "%s", spec);
	}
	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_input_at(context, "cannot open '%s': %s", path, strerror(errno));
	fclose(f);
	int err = ss_snapshot_read_field(path, dataset, -1, &r->nx, &r->ny, &r->values);
	if (err)
		return err;
	r->cellsize = r->x0 = r->y0 = NAN;
	const size_t n = (size_t)r->nx * (size_t)r->ny;
	for (size_t k = 0; k < n; k++) {
		if (!isfinite(r->values[k]))
			return ss_error_input_at(context, "%s: height %g at column %zu, row %zu (from the south) "
			                      "is not finite: heights must be finite numbers", spec,
			                      r->values[k], k % (size_t)r->nx + 1,
			                      k / (size_t)r->nx + 1);
	}
	return SS_OK;
}

static int has_suffix(const char *s, const char *suffix)
{
	size_t a = strlen(s), b = strlen(suffix);
	return a >= b && strcasecmp(s + a - b, suffix) == 0;
}

int ss_dem_read(const char *spec, const char *context, struct ss_raster *r)
{
	memset(r, 0, sizeof *r);
	if (has_suffix(spec, ".asc"))
		return read_asc(spec, context, r);
	if (has_suffix(spec, ".h5") || strstr(spec, ".h5:"))
		return read_h5(spec, context, r);
	return ss_error_input_at(context, "'%s': unknown raster format: expected an ESRI ASCII grid "
	                      "(.asc) or a sandslide HDF5 file (.h5 or .h5:/dataset)", spec);
}
