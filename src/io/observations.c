/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * observations.c - the observations `sandslide fit` reads (observations.h):
 * the kind from the file, then one reader per kind, each checking what the
 * fit will rely on (times in order, one grid, something observed, enough
 * points to make a boundary) so that the fit never has to.
 *
 * A CSV is read line by line; its lines are numbered as an editor numbers
 * them, blank and comment lines included, so that "obs.csv:7" is the line
 * to look at.  Rasters are read one at a time into the series, which is
 * allocated once the first raster has given the size and the memory it
 * needs has been checked.
 */
#include "io/observations.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/strings.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"
#include "sandslide/snapshot.h"

/* What every refusal of an unknown file or header lists. */
#define ACCEPTED "an HDF5 height series (.h5, .nc, .hdf5: /time in s and /height (time, y, " \
	"x) in m), a CSV of rasters (header time,path) or a CSV of front points (header " \
	"time,x,y)"

void ss_observations_release(struct ss_observations *o)
{
	free(o->path);
	free(o->time);
	ss_free(o->height);
	free(o->point_x);
	free(o->point_y);
	free(o->first_point);
	memset(o, 0, sizeof *o);
}

/* ---- helpers ----------------------------------------------------------- */

/* Room for need elements of size bytes in p (capacity *cap, doubled as
 * it fills): p or where it moved; NULL after a message when memory runs
 * out (p then unchanged, still the caller's). */
static void *grow(void *p, long long *cap, long long need, size_t size, const char *what)
{
	if (need <= *cap)
		return p;
	long long n = *cap ? *cap : 64;
	while (n < need)
		n *= 2;
	void *q = (size_t)n <= SIZE_MAX / size ? realloc(p, (size_t)n * size) : NULL;
	if (!q) {
		ss_error_fail("cannot allocate %s: %lld of %zu bytes", what, n, size);
		return NULL;
	}
	*cap = n;
	return q;
}

/* grow() on an array lvalue: SS_OK, or SS_ERR_FAIL with the array kept;
 * moved is a void * of the caller's. */
#define GROW(array, cap, need, what, moved)                                            \
	(((moved) = grow((array), &(cap), (need), sizeof *(array), (what))) != NULL        \
	         ? ((array) = (moved), SS_OK)                                              \
	         : SS_ERR_FAIL)

/* The series' heights (times x cells of 8 bytes), and `held` more
 * arrays of a time's cells held while reading, fit in the memory this
 * machine has available; SS_ERR_INPUT naming the file otherwise. */
static int check_memory(const char *path, long long times, int held, int nx, int ny)
{
	const double need = 8.0 * (double)(times + held) * (double)nx * (double)ny;
	const double have = ss_memory_available_bytes();
	if (need <= (double)SIZE_MAX / 2 && (have <= 0.0 || need <= have))
		return SS_OK;
	char b[32], a[32];
	return ss_error_input("'%s' holds %lld times of %d x %d cells: they need %s of memory, "
	                      "more than the %s available", path, times, nx, ny,
	                      ss_format_bytes(need, b), ss_format_bytes(have, a));
}

/* path ends in ext, any case */
static int has_extension(const char *path, const char *ext)
{
	const size_t n = strlen(path), e = strlen(ext);
	return n > e && !strcasecmp(path + n - e, ext);
}

/* ---- a CSV, line by line ------------------------------------------------- */

struct csv {
	FILE *f;
	const char *path;           /* as given */
	long line;                  /* of the last line read, from 1 */
	char *buf;                  /* getline's */
	size_t cap;
	char where[600];            /* "path:line" of the last line */
};

/* The next line that is not blank or a comment into *text, its end of
 * line and surrounding spaces removed (and a UTF-8 byte order mark on the
 * first line): 1, or 0 at the end of the file; SS_ERR_INPUT if it cannot
 * be read. */
static int csv_next(struct csv *c, char **text)
{
	for (;;) {
		errno = 0;
		const ssize_t n = getline(&c->buf, &c->cap, c->f);
		if (n < 0) {
			if (ferror(c->f))
				return ss_error_input("cannot read '%s': %s", c->path,
				                      strerror(errno ? errno : EIO));
			return 0;
		}
		char *s = c->buf;
		if (++c->line == 1 && !strncmp(s, "\xEF\xBB\xBF", 3))
			s += 3;
		size_t len = strlen(s);
		while (len > 0 && isspace((unsigned char)s[len - 1]))
			s[--len] = '\0';
		while (isspace((unsigned char)*s))
			s++;
		snprintf(c->where, sizeof c->where, "%s:%ld", c->path, c->line);
		if (*s && *s != '#') {
			*text = s;
			return 1;
		}
	}
}

/* Split s at commas into at most max fields, spaces around each removed:
 * the number of fields s has (which may be more than max). */
static int split(char *s, char **field, int max)
{
	int n = 0;
	for (;;) {
		char *comma = strchr(s, ',');
		if (comma)
			*comma = '\0';
		char *end = s + strlen(s);
		while (end > s && isspace((unsigned char)end[-1]))
			*--end = '\0';
		while (isspace((unsigned char)*s))
			s++;
		if (n < max)
			field[n] = s;
		n++;
		if (!comma)
			return n;
		s = comma + 1;
	}
}

/* A line of got fields has the want of its header: SS_ERR_INPUT if not. */
static int check_fields(const struct csv *c, int got, int want, const char *header)
{
	if (got == want)
		return SS_OK;
	return ss_error_input_at(c->where, "%d field%s: expected %d (%s)", got, got == 1 ? "" : "s",
	                         want, header);
}

/* A coordinate or time named what from its field. */
static int parse_number(const struct csv *c, const char *what, const char *text, double *v)
{
	if (!ss_parse_real(text, -DBL_MAX, DBL_MAX, v))
		return SS_OK;
	char *end;
	const double x = strtod(text, &end);
	if (end != text && !*end && !isfinite(x))
		return ss_error_input_at(c->where, "%s '%s' is not finite: expected a finite number",
		                         what, text);
	return ss_error_input_at(c->where, "%s '%s' is not a number", what, text);
}

/* The time of a line, >= 0, after prev (the time before it, NAN for the
 * first); equal allowed when same_ok (a front's rows of one time). */
static int parse_time(const struct csv *c, const char *text, double prev, int same_ok,
                      double *t)
{
	int err = parse_number(c, "time", text, t);
	if (err)
		return err;
	if (*t < 0.0)
		return ss_error_input_at(c->where, "time %s is negative: expected s since the "
		                         "experiment's start, >= 0", text);
	if (!isnan(prev) && (*t < prev || (*t == prev && !same_ok)))
		return ss_error_input_at(c->where, "times must increase: %s after %s%s", SS_REAL(*t),
		                         SS_REAL(prev),
		                         same_ok ? " (the rows of one time together, times in "
		                                   "increasing order)"
		                                 : "");
	return SS_OK;
}

/* ---- heights from an HDF5 series --------------------------------------- */

/* The centre of cell k along an axis from edge x0 (0 when unknown) in steps
 * of d, as the raster readers name cells (NaN without d: no coordinates). */
#define CENTRE(x0, d, k) ((isnan(x0) ? 0.0 : (x0)) + ((double)(k) + 0.5) * (d))

/* The series' values checked, and counted into o->observed; none says
 * in a message that nothing is observed. */
static int check_heights(struct ss_observations *o, const char *none)
{
	const size_t cells = (size_t)o->nx * (size_t)o->ny;
	o->observed = 0;
	for (long long k = 0; k < o->times; k++) {
		const double *h = o->height + (size_t)k * cells;
		for (size_t m = 0; m < cells; m++) {
			if (isinf(h[m]))
				return ss_error_input("'%s': a height is infinite at time %s s, %s: expected "
				                      "heights in m, NaN where not observed", o->path,
				                      SS_REAL(o->time[k]),
				                      SS_CELL((long long)(m % (size_t)o->nx),
				                              (long long)(m / (size_t)o->nx),
				                              CENTRE(o->origin_x, o->dx, m % (size_t)o->nx),
				                              CENTRE(o->origin_y, o->dy, m / (size_t)o->nx)));
			o->observed += !isnan(h[m]);
		}
	}
	if (o->observed == 0)
		return ss_error_input("'%s': no observed value: %s", o->path, none);
	return SS_OK;
}

static int read_hdf5(struct ss_observations *o)
{
	struct ss_height_series s;
	int err = ss_snapshot_read_height_series(o->path, &s);
	if (err)
		return err;
	o->times = s.count;
	o->time = malloc((size_t)(s.count ? s.count : 1) * sizeof *o->time);
	if (!o->time) {
		ss_height_series_release(&s);
		return ss_error_fail("out of memory");
	}
	if (s.count > 0)            /* s.time is NULL for an empty series */
		memcpy(o->time, s.time, (size_t)s.count * sizeof *o->time);
	o->nx = s.nx;
	o->ny = s.ny;
	o->dx = s.dx;
	o->dy = s.dy;
	o->origin_x = s.origin_x;
	o->origin_y = s.origin_y;
	o->height = s.height;       /* o owns it now */
	s.height = NULL;
	ss_height_series_release(&s);
	if (o->times == 0)
		return ss_error_input("'%s': no observations: /height has no snapshot", o->path);
	for (long long k = 0; k < o->times; k++) {
		const double t = o->time[k];
		if (!isfinite(t) || t < 0.0)
			return ss_error_input("'%s': /time[%lld] is %s: expected s since the "
			                      "experiment's start, finite and >= 0", o->path, k,
			                      SS_REAL(t));
		if (k > 0 && !(t > o->time[k - 1]))
			return ss_error_input("'%s': /time[%lld]: times must increase: %s after %s",
			                      o->path, k, SS_REAL(t), SS_REAL(o->time[k - 1]));
	}
	return check_heights(o, "/height is NaN (not observed) in every cell at every time, or "
	                        "a wall (/cell_type 1)");
}

/* ---- heights from rasters ---------------------------------------------- */

/* The lines of a CSV of rasters: a time and a path each. */
struct raster_list {
	long long n, cap_path, cap_line;
	char **path;                /* resolved against the CSV's folder (owned) */
	long *line;                 /* of the CSV, for messages */
};

static void raster_list_release(struct raster_list *l)
{
	for (long long k = 0; k < l->n; k++)
		free(l->path[k]);
	free(l->path);
	free(l->line);
}

/* p relative to the CSV's folder, unless absolute, as a new string. */
static char *resolve(const char *csv, const char *p)
{
	const char *slash = strrchr(csv, '/');
	const size_t dir = p[0] == '/' || !slash ? 0 : (size_t)(slash - csv) + 1;
	char *out = malloc(dir + strlen(p) + 1);
	if (out) {
		memcpy(out, csv, dir);
		strcpy(out + dir, p);
	}
	return out;
}

/* Both known and different: a raster of another geometry than the first. */
static int differ(double a, double b, double scale)
{
	return isfinite(a) && isfinite(b) && fabs(a - b) > 1e-9 * (fabs(a) + fabs(b) + scale);
}

/* Raster k of the list (read into r) into the series at k. */
static int take_raster(struct ss_observations *o, const struct raster_list *l, long long k,
                       const struct ss_raster *r)
{
	char where[600];
	snprintf(where, sizeof where, "%s:%ld", o->path, l->line[k]);
	if (r->nx != o->nx || r->ny != o->ny)
		return ss_error_input_at(where, "'%s' is %d x %d cells, the first raster (line %ld) "
		                         "%d x %d: every raster must have the first one's size",
		                         l->path[k], r->nx, r->ny, l->line[0], o->nx, o->ny);
	const double scale = isfinite(o->dx) ? o->dx : 0.0;
	if (differ(r->cellsize, o->dx, 0.0) || differ(r->cellsize_y, o->dy, 0.0) ||
	    differ(r->x0, o->origin_x, scale) || differ(r->y0, o->origin_y, scale))
		return ss_error_input_at(where, "'%s' has cells of %s x %s m from (%s, %s), the "
		                         "first raster (line %ld) %s x %s m from (%s, %s): every "
		                         "raster must lie on the first one's grid", l->path[k],
		                         SS_REAL(r->cellsize), SS_REAL(r->cellsize_y),
		                         SS_REAL(r->x0), SS_REAL(r->y0), l->line[0],
		                         SS_REAL(o->dx), SS_REAL(o->dy), SS_REAL(o->origin_x),
		                         SS_REAL(o->origin_y));
	const size_t cells = (size_t)o->nx * (size_t)o->ny;
	double *h = o->height + (size_t)k * cells;
	for (size_t m = 0; m < cells; m++)
		h[m] = r->nodata && r->nodata[m] ? NAN : r->values[m];
	return SS_OK;
}

/* The first raster's header: the size and geometry of the series, and
 * the memory for it (and for the one raster read at a time) checked
 * before a value is read. */
static int first_header(struct ss_observations *o, const struct raster_list *l,
                        const char *where)
{
	struct ss_dem_read_options opt;
	ss_dem_read_options_init(&opt);
	opt.rows = 0;
	struct ss_raster r;
	int err = ss_dem_read(l->path[0], where, &opt, &r);
	if (!err) {
		o->nx = r.nx;
		o->ny = r.ny;
		o->dx = r.cellsize;
		o->dy = r.cellsize_y;
		o->origin_x = r.x0;
		o->origin_y = r.y0;
		err = check_memory(o->path, o->times, 1, o->nx, o->ny);
	}
	ss_raster_release(&r);
	if (!err && !(o->height = ss_alloc((size_t)o->times * (size_t)o->nx * (size_t)o->ny,
	                                   sizeof *o->height, "observed heights")))
		err = SS_ERR_FAIL;
	return err;
}

/* Every raster of the list, read one at a time. */
static int read_rasters(struct ss_observations *o, const struct raster_list *l)
{
	int err = SS_OK;
	for (long long k = 0; k < l->n && !err; k++) {
		char where[600];
		snprintf(where, sizeof where, "%s:%ld", o->path, l->line[k]);
		if (k == 0 && (err = first_header(o, l, where)))
			break;
		struct ss_raster r;
		err = ss_dem_read(l->path[k], where, NULL, &r);
		if (!err)
			err = take_raster(o, l, k, &r);
		ss_raster_release(&r);
	}
	return err ? err : check_heights(o, "every cell of every raster is nodata");
}

static int read_raster_csv(struct ss_observations *o, struct csv *c)
{
	struct raster_list l = {0};
	long long cap = 0;
	void *moved;
	int err = SS_OK, more = 0;
	char *text, *field[2];
	while (!err && (more = csv_next(c, &text)) == 1) {
		const int n = split(text, field, 2);
		double t;
		if ((err = check_fields(c, n, 2, "time,path")) ||
		    (err = parse_time(c, field[0], l.n ? o->time[l.n - 1] : NAN, 0, &t)))
			break;
		if (!*field[1]) {
			err = ss_error_input_at(c->where, "no raster path: expected one a line, relative "
			                        "to the CSV's folder (.asc, .tif, .png, FILE.h5[:/dataset])");
			break;
		}
		if ((err = GROW(o->time, cap, l.n + 1, "observation times", moved)) ||
		    (err = GROW(l.path, l.cap_path, l.n + 1, "raster paths", moved)) ||
		    (err = GROW(l.line, l.cap_line, l.n + 1, "raster lines", moved)))
			break;
		if (!(l.path[l.n] = resolve(o->path, field[1]))) {
			err = ss_error_fail("out of memory");
			break;
		}
		o->time[l.n] = t;
		l.line[l.n++] = c->line;
	}
	if (!err && more < 0)
		err = more;
	o->times = l.n;
	if (!err && l.n == 0)
		err = ss_error_input("'%s': no observations: a header time,path and no line after "
		                     "it (expected a time in s and a raster's path a line)", o->path);
	if (!err)
		err = read_rasters(o, &l);
	raster_list_release(&l);
	return err;
}

/* ---- the front ------------------------------------------------------------ */

/* The points of time k (o->times - 1, the last begun) are enough for a
 * boundary; first_line is where they begin. */
static int close_front_time(struct ss_observations *o, long first_line)
{
	const long long k = o->times - 1, n = o->points - o->first_point[k];
	if (n >= 3)
		return SS_OK;
	return ss_error_input("%s:%ld: time %s has %lld point%s: a front needs at least 3 a "
	                      "time (the boundary of the sand)", o->path, first_line,
	                      SS_REAL(o->time[k]), n, n == 1 ? "" : "s");
}

static int read_front_csv(struct ss_observations *o, struct csv *c)
{
	long long cap_time = 0, cap_first = 0, cap_x = 0, cap_y = 0;
	void *moved;
	long first_line = 0;        /* of the current time's points */
	int err = SS_OK, more = 0;
	char *text, *field[3];
	while (!err && (more = csv_next(c, &text)) == 1) {
		const int n = split(text, field, 3);
		double t, x, y;
		const double prev = o->times ? o->time[o->times - 1] : NAN;
		if ((err = check_fields(c, n, 3, "time,x,y")) ||
		    (err = parse_time(c, field[0], prev, 1, &t)) ||
		    (err = parse_number(c, "x", field[1], &x)) ||
		    (err = parse_number(c, "y", field[2], &y)))
			break;
		if (!o->times || t > prev) {
			if (o->times && (err = close_front_time(o, first_line)))
				break;
			if ((err = GROW(o->time, cap_time, o->times + 1, "observation times", moved)) ||
			    (err = GROW(o->first_point, cap_first, o->times + 2, "front times", moved)))
				break;
			o->time[o->times] = t;
			o->first_point[o->times++] = o->points;
			first_line = c->line;
		}
		if ((err = GROW(o->point_x, cap_x, o->points + 1, "front points", moved)) ||
		    (err = GROW(o->point_y, cap_y, o->points + 1, "front points", moved)))
			break;
		o->point_x[o->points] = x;
		o->point_y[o->points++] = y;
	}
	if (!err && more < 0)
		err = more;
	if (!err && o->times == 0)
		err = ss_error_input("'%s': no observations: a header time,x,y and no line after it "
		                     "(expected a time in s and a front point's x, y in m a line)",
		                     o->path);
	if (!err)
		err = close_front_time(o, first_line);
	if (!err)
		o->first_point[o->times] = o->points;
	return err;
}

/* ---- the kind of a file ----------------------------------------------------- */

/* A header for messages: printable, cut at 60 characters. */
static const char *header_text(const char *s, char out[64])
{
	size_t n = 0;
	for (; s[n] && n < 60; n++)
		out[n] = isprint((unsigned char)s[n]) ? s[n] : '?';
	out[n] = '\0';
	return out;
}

/* A CSV: its header says which. */
static int read_csv(struct ss_observations *o, FILE *f)
{
	struct csv c = {.f = f, .path = o->path};
	char *text;
	int err = csv_next(&c, &text);
	if (err == 0)
		err = ss_error_input("'%s' is empty: no observations (expected %s)", o->path,
		                     ACCEPTED);
	if (err < 0)
		goto out;
	/* the header without its spaces, in lower case */
	char key[64], shown[64];
	size_t n = 0;
	for (const char *s = text; *s && n + 1 < sizeof key; s++)
		if (!isspace((unsigned char)*s))
			key[n++] = (char)tolower((unsigned char)*s);
	key[n] = '\0';
	if (!strcmp(key, "time,path")) {
		o->kind = SS_OBSERVED_HEIGHTS;
		err = read_raster_csv(o, &c);
	} else if (!strcmp(key, "time,x,y")) {
		o->kind = SS_OBSERVED_FRONT;
		o->dx = o->dy = o->origin_x = o->origin_y = NAN;
		err = read_front_csv(o, &c);
	} else if (has_extension(o->path, ".csv") || has_extension(o->path, ".txt")) {
		err = ss_error_input_at(c.where, "unknown header '%s': expected %s",
		                        header_text(text, shown), ACCEPTED);
	} else {
		err = ss_error_input("'%s' is not an observation file: expected %s", o->path,
		                     ACCEPTED);
	}
out:
	free(c.buf);
	return err;
}

/* An HDF5 file by its name or its first bytes (HDF5's signature). */
static int is_hdf5(const char *path, FILE *f)
{
	static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
	unsigned char head[8];
	if (has_extension(path, ".h5") || has_extension(path, ".hdf5") ||
	    has_extension(path, ".nc") || has_extension(path, ".nc4") ||
	    has_extension(path, ".hdf"))
		return 1;
	const int yes = fread(head, 1, sizeof head, f) == sizeof head && !memcmp(head, sig, 8);
	rewind(f);
	return yes;
}

int ss_observations_read(struct ss_observations *o, const char *path)
{
	memset(o, 0, sizeof *o);
	if (!(o->path = strdup(path)))
		return ss_error_fail("out of memory");
	o->dx = o->dy = o->origin_x = o->origin_y = NAN;
	struct stat sb;
	FILE *f = fopen(path, "rb");
	int err;
	if (!f || fstat(fileno(f), &sb) != 0)
		err = ss_error_input("cannot open '%s': %s", path, strerror(errno));
	else if (S_ISDIR(sb.st_mode))
		err = ss_error_input("'%s' is a folder: expected %s", path, ACCEPTED);
	else if (is_hdf5(path, f)) {
		o->kind = SS_OBSERVED_HEIGHTS;
		fclose(f);
		f = NULL;
		err = read_hdf5(o);
	} else
		err = read_csv(o, f);
	if (f)
		fclose(f);
	if (err)
		ss_observations_release(o);
	return err;
}
