/*
 * case.c - case file parser (see case.h; every key is documented in
 * cases/reference.ini).
 *
 * inih does the INI syntax; a reader callback counts lines so that each
 * message names file:line (Debian's inih is built without line numbers in
 * the handler).  A first pass over the text checks what inih would accept
 * silently: section names, repeated sections, over-long lines, lines that
 * are neither a section, a key nor a comment.  Keys of the fixed sections
 * are described by one table, so parsing, defaults and messages agree.
 */
#include "sandslide/case.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ini.h>

#include "sandslide/error.h"

enum value_type {
	V_COUNT,      /* integer >= 1 */
	V_POSITIVE,   /* finite > 0 */
	V_NONNEG,     /* finite >= 0 */
	V_REAL,       /* finite */
	V_ANGLE,      /* degrees in (0, 90) */
	V_CFL,        /* (0, 1] */
	V_CLOSURE,
	V_SIDE,
	V_END,        /* > 0 or "steady" */
	V_INITIAL,
	V_PAIR,       /* two finite numbers */
	V_PATH,
	V_INTEGRATOR,
	V_STAGES,     /* integer >= 2 */
};

static const char *const accepted[] = {
	[V_COUNT] = "an integer >= 1",
	[V_POSITIVE] = "a finite number > 0",
	[V_NONNEG] = "a finite number >= 0",
	[V_REAL] = "a finite number",
	[V_ANGLE] = "an angle in degrees in (0, 90)",
	[V_CFL] = "a number in (0, 1]",
	[V_CLOSURE] = SS_CLOSURE_NAMES,
	[V_SIDE] = "wall, open or periodic",
	[V_END] = "a time in s > 0, or steady",
	[V_INITIAL] = "flat, cone or file",
	[V_PAIR] = "two finite numbers 'X Y'",
	[V_PATH] = "a file name",
	[V_INTEGRATOR] = SS_INTEGRATOR_NAMES,
	[V_STAGES] = "an integer >= 2",
};

struct key_spec {
	const char *section, *key;
	enum value_type type;
	size_t offset;
};

#define KEY(sec, name, type, field) {sec, name, type, offsetof(struct ss_case, field)}
static const struct key_spec keys[] = {
	KEY("grid", "nx", V_COUNT, nx),
	KEY("grid", "ny", V_COUNT, ny),
	KEY("grid", "dx", V_POSITIVE, dx),
	KEY("grid", "dy", V_POSITIVE, dy),
	KEY("grid", "origin", V_PAIR, origin_x),
	KEY("model", "closure", V_CLOSURE, closure),
	KEY("model", "repose_angle", V_ANGLE, repose_angle_deg),
	KEY("model", "nu", V_POSITIVE, nu),
	KEY("model", "gamma", V_POSITIVE, gamma),
	KEY("model", "delta", V_POSITIVE, delta),
	KEY("model", "density", V_POSITIVE, density),
	KEY("model", "gravity", V_POSITIVE, gravity),
	KEY("model", "viscosity", V_POSITIVE, viscosity),
	KEY("model", "consistency", V_POSITIVE, consistency),
	KEY("time", "end", V_END, end),
	KEY("time", "output_every", V_POSITIVE, output_every),
	KEY("time", "cfl", V_CFL, cfl),
	KEY("time", "steady_tol", V_POSITIVE, steady_tol),
	KEY("time", "max_time", V_POSITIVE, max_time),
	KEY("time", "steady_slope_tol", V_POSITIVE, steady_slope_tol),
	KEY("time", "integrator", V_INTEGRATOR, integrator),
	KEY("time", "rkl2_max_stages", V_STAGES, rkl2_max_stages),
	KEY("time", "rkl2_tol", V_POSITIVE, rkl2_tol),
	KEY("boundary", "west", V_SIDE, boundary.side[SS_WEST]),
	KEY("boundary", "east", V_SIDE, boundary.side[SS_EAST]),
	KEY("boundary", "south", V_SIDE, boundary.side[SS_SOUTH]),
	KEY("boundary", "north", V_SIDE, boundary.side[SS_NORTH]),
	KEY("boundary", "open_level", V_REAL, boundary.open_level),
	KEY("initial", "type", V_INITIAL, initial),
	KEY("initial", "height", V_REAL, initial_height),
	KEY("initial", "center", V_PAIR, cone_x),
	KEY("initial", "radius", V_POSITIVE, cone_radius),
	KEY("initial", "angle", V_ANGLE, cone_angle_deg),
	KEY("initial", "file", V_PATH, initial_file),
	KEY("initial", "bedrock", V_PATH, bedrock_file),
};
#undef KEY
enum { KEY_COUNT = sizeof keys / sizeof *keys };

static const char *const fixed_sections[] = {"grid", "model", "time", "boundary", "initial"};
static const char *const region_prefix[] = {
	[SS_REGION_WALL] = "wall", [SS_REGION_OPEN] = "open", [SS_REGION_SOURCE] = "source",
};
#define SECTIONS_ACCEPTED "grid, model, time, boundary, initial, wall NAME, open NAME, source NAME"
#define MAX_REGIONS 256

struct parse {
	struct ss_case *c;
	const char *path;          /* for messages */
	const char *text, *cursor; /* reader state */
	int line;                  /* line inih is handling */
	int continuation;          /* that line starts with white space */
	int overriding;            /* applying --set: later values replace */
	int failed;
	char where[SS_CASE_WHERE_SIZE];           /* location of the value being applied */
	int key_set[KEY_COUNT];
	char key_where[KEY_COUNT][SS_CASE_WHERE_SIZE];
	char last_region_key[16];  /* for polygon continuation lines */
};

/* An error in the value being applied: named by its location, and the
 * first error is the only one reported. */
#define fail_at(p, ...) ((p)->failed = 1, ss_error_input_at((p)->where, __VA_ARGS__))

/* ---- values ---------------------------------------------------------- */

static int parse_double(const char *s, double *out)
{
	char *end;
	errno = 0;
	double v = strtod(s, &end);
	if (end == s || errno == ERANGE)
		return -1;
	while (isspace((unsigned char)*end))
		end++;
	if (*end || !isfinite(v))
		return -1;
	*out = v;
	return 0;
}

/* Up to max finite numbers separated by white space; returns the count or
 * -1 when something is not a number. */
static int parse_numbers(const char *s, double *out, int max)
{
	int n = 0;
	for (;;) {
		while (isspace((unsigned char)*s))
			s++;
		if (!*s)
			return n;
		char *end;
		errno = 0;
		double v = strtod(s, &end);
		if (end == s || errno == ERANGE || !isfinite(v) ||
		    (*end && !isspace((unsigned char)*end)))
			return -1;
		if (n < max)
			out[n] = v;
		n++;
		s = end;
	}
}

static char *dup_string(const char *s)
{
	size_t n = strlen(s) + 1;
	char *d = malloc(n);
	if (d)
		memcpy(d, s, n);
	return d;
}

/* Resolve a file name given in the case against the case file's folder. */
static char *resolve_path(const char *case_path, const char *name)
{
	if (name[0] == '/' || !strchr(case_path, '/'))
		return dup_string(name);
	size_t dir = (size_t)(strrchr(case_path, '/') - case_path) + 1;
	char *out = malloc(dir + strlen(name) + 1);
	if (!out)
		return NULL;
	memcpy(out, case_path, dir);
	strcpy(out + dir, name);
	return out;
}

static int store_value(struct parse *p, const struct key_spec *k, const char *value)
{
	void *field = (char *)p->c + k->offset;
	double v[3];
	switch (k->type) {
	case V_COUNT:
	case V_STAGES: {
		char *end;
		errno = 0;
		long n = strtol(value, &end, 10);
		while (isspace((unsigned char)*end))
			end++;
		if (end == value || *end || errno || n < (k->type == V_STAGES ? 2 : 1) ||
		    n > INT_MAX / 4)
			goto bad;
		*(int *)field = (int)n;
		return SS_OK;
	}
	case V_POSITIVE:
	case V_NONNEG:
	case V_REAL:
	case V_ANGLE:
	case V_CFL:
		if (parse_double(value, v))
			goto bad;
		if ((k->type == V_POSITIVE && !(v[0] > 0.0)) ||
		    (k->type == V_NONNEG && !(v[0] >= 0.0)) ||
		    (k->type == V_ANGLE && !(v[0] > 0.0 && v[0] < 90.0)) ||
		    (k->type == V_CFL && !(v[0] > 0.0 && v[0] <= 1.0)))
			goto bad;
		*(double *)field = v[0];
		return SS_OK;
	case V_PAIR:
		if (parse_numbers(value, v, 3) != 2)
			goto bad;
		((double *)field)[0] = v[0];
		((double *)field)[1] = v[1];
		return SS_OK;
	case V_CLOSURE:
		if (ss_closure_parse(value, (enum ss_closure_kind *)field))
			goto bad;
		return SS_OK;
	case V_SIDE:
		if (ss_side_kind_parse(value, (enum ss_side_kind *)field))
			goto bad;
		return SS_OK;
	case V_END:
		if (strcmp(value, "steady") == 0) {
			p->c->steady = 1;
			*(double *)field = INFINITY;
			return SS_OK;
		}
		if (parse_double(value, v) || !(v[0] > 0.0))
			goto bad;
		p->c->steady = 0;
		*(double *)field = v[0];
		return SS_OK;
	case V_INTEGRATOR:
		if (ss_integrator_parse(value, (enum ss_integrator *)field))
			goto bad;
		return SS_OK;
	case V_INITIAL: {
		static const char *const names[] = {"flat", "cone", "file"};
		for (int m = 0; m < 3; m++) {
			if (strcmp(value, names[m]) == 0) {
				*(enum ss_initial_type *)field = (enum ss_initial_type)m;
				return SS_OK;
			}
		}
		goto bad;
	}
	case V_PATH: {
		if (!*value)
			goto bad;
		char *s = resolve_path(p->path, value);
		if (!s)
			return ss_error_fail("out of memory reading '%s'", p->path);
		free(*(char **)field);
		*(char **)field = s;
		char *where = field == &p->c->bedrock_file ? p->c->bedrock_where
		                                           : p->c->initial_where;
		snprintf(where, SS_CASE_WHERE_SIZE, "%s", p->where);
		return SS_OK;
	}
	}
bad:
	return fail_at(p, "[%s] %s = '%s' is not valid: expected %s", k->section,
	               k->key, value, accepted[k->type]);
}

/* ---- regions --------------------------------------------------------- */

/* "wall NAME" -> role and name; returns 0, or -1 if not a region section. */
static int region_section(const char *section, enum ss_region_role *role,
                          const char **name)
{
	for (int r = 0; r < 3; r++) {
		size_t n = strlen(region_prefix[r]);
		if (strncmp(section, region_prefix[r], n) == 0 && section[n] == ' ') {
			const char *s = section + n;
			while (*s == ' ')
				s++;
			if (!*s)
				return -1;
			for (const char *q = s; *q; q++)
				if (!isalnum((unsigned char)*q) && *q != '_' && *q != '-')
					return -1;
			*role = (enum ss_region_role)r;
			*name = s;
			return 0;
		}
	}
	return -1;
}

static struct ss_region *region_find(struct parse *p, enum ss_region_role role,
                                     const char *name, int create)
{
	struct ss_case *c = p->c;
	for (int k = 0; k < c->region_count; k++)
		if (c->regions[k].role == role && strcmp(c->regions[k].name, name) == 0)
			return &c->regions[k];
	if (!create)
		return NULL;
	if (c->region_count >= MAX_REGIONS) {
		fail_at(p, "more than %d wall, open and source sections", MAX_REGIONS);
		return NULL;
	}
	if (!c->regions) {
		c->regions = calloc(MAX_REGIONS, sizeof *c->regions);
		if (!c->regions) {
			ss_error_fail("out of memory reading '%s'", p->path);
			p->failed = 1;
			return NULL;
		}
	}
	struct ss_region *r = &c->regions[c->region_count++];
	memset(r, 0, sizeof *r);
	r->role = role;
	snprintf(r->name, sizeof r->name, "%s", name);
	snprintf(r->where, sizeof r->where, "%s", p->where);
	r->start = 0.0;
	r->stop = INFINITY;
	return r;
}

static int region_shape(struct parse *p, struct ss_region *r, const char *key,
                        const char *value, const char *section)
{
	struct ss_shape *sh = &r->shape;
	int polygon_more = p->continuation && strcmp(key, "polygon") == 0 &&
	                   sh->kind == SS_SHAPE_POLYGON &&
	                   strcmp(p->last_region_key, "polygon") == 0;
	if (p->overriding && !polygon_more) {
		free(sh->polygon);
		free(sh->mask_path);
		memset(sh, 0, sizeof *sh);
	}
	if (sh->kind != SS_SHAPE_NONE && !polygon_more)
		return fail_at(p, "[%s] has two shapes (the first is at %s): give one of "
		               "rect, disk, polygon, mask", section, sh->where);
	if (!polygon_more)
		snprintf(sh->where, sizeof sh->where, "%s", p->where);

	if (strcmp(key, "mask") == 0) {
		if (!*value)
			return fail_at(p, "[%s] mask = '': expected a PNG file name", section);
		sh->kind = SS_SHAPE_MASK;
		sh->mask_path = resolve_path(p->path, value);
		if (!sh->mask_path)
			return ss_error_fail("out of memory");
		return SS_OK;
	}

	int count = parse_numbers(value, NULL, 0);
	if (strcmp(key, "rect") == 0) {
		if (count != 4 || parse_numbers(value, sh->v, 4) != 4 ||
		    !(sh->v[0] < sh->v[2] && sh->v[1] < sh->v[3]))
			return fail_at(p, "[%s] rect = '%s': expected 'X0 Y0 X1 Y1' in m "
			               "with X0 < X1 and Y0 < Y1", section, value);
		sh->kind = SS_SHAPE_RECT;
		return SS_OK;
	}
	if (strcmp(key, "disk") == 0) {
		if (count != 3 || parse_numbers(value, sh->v, 3) != 3 || !(sh->v[2] > 0.0))
			return fail_at(p, "[%s] disk = '%s': expected 'X Y R' in m with R > 0",
			               section, value);
		sh->kind = SS_SHAPE_DISK;
		return SS_OK;
	}
	/* polygon, possibly continued on indented lines */
	if (count < 0 || count % 2)
		return fail_at(p, "[%s] polygon = '%s': expected pairs of numbers 'X Y X Y ...' in m",
		               section, value);
	double *pts = realloc(sh->polygon, (size_t)(2 * sh->polygon_points + count) * sizeof *pts);
	if (!pts)
		return ss_error_fail("out of memory");
	sh->polygon = pts;
	parse_numbers(value, pts + 2 * sh->polygon_points, count);
	sh->polygon_points += count / 2;
	sh->kind = SS_SHAPE_POLYGON;
	return SS_OK;
}

/* "the case has no [source nosuch]: its source sections are room, pour" */
static int no_such_region(struct parse *p, enum ss_region_role role, const char *name)
{
	const struct ss_case *c = p->c;
	char names[512] = "";
	size_t used = 0;
	int found = 0;
	for (int k = 0; k < c->region_count; k++) {
		if (c->regions[k].role != role)
			continue;
		const int n = snprintf(names + used, sizeof names - used, "%s%s", found ? ", " : "",
		                       c->regions[k].name);
		if (n < 0 || (size_t)n >= sizeof names - used)
			break;
		used += (size_t)n;
		found++;
	}
	if (!found)
		return fail_at(p, "the case has no [%s %s], and no %s section at all",
		               region_prefix[role], name, region_prefix[role]);
	return fail_at(p, "the case has no [%s %s]: its %s sections are %s", region_prefix[role],
	               name, region_prefix[role], names);
}

static int apply_region_key(struct parse *p, const char *section, const char *key,
                            const char *value)
{
	enum ss_region_role role;
	const char *name;
	if (region_section(section, &role, &name))
		return fail_at(p, "unknown section [%s]: expected " SECTIONS_ACCEPTED, section);
	/* --set changes a section of the case; it does not make one up (an
	 * --set of a misspelt name said the new section "has no shape") */
	struct ss_region *r = region_find(p, role, name, !p->overriding);
	if (!r && p->overriding && !p->failed)
		return no_such_region(p, role, name);
	if (!r)
		return SS_ERR_INPUT;

	int err;
	if (!strcmp(key, "rect") || !strcmp(key, "disk") || !strcmp(key, "polygon") ||
	    !strcmp(key, "mask")) {
		err = region_shape(p, r, key, value, section);
	} else if (role == SS_REGION_SOURCE &&
	           (!strcmp(key, "rate") || !strcmp(key, "start") || !strcmp(key, "stop"))) {
		const int is_rate = key[0] == 'r', is_start = key[2] == 'a';
		char *where = is_rate ? r->rate_where : is_start ? r->start_where : r->stop_where;
		double v;
		if (where[0] && !p->overriding)
			return fail_at(p, "[%s] %s is set twice (first at %s)", section, key, where);
		if (parse_double(value, &v) || (is_rate ? !(v > 0.0) : !(v >= 0.0)))
			return fail_at(p, "[%s] %s = '%s': expected %s", section, key, value,
			               is_rate ? "a finite number > 0 (m/s)" : "a time in s >= 0");
		*(is_rate ? &r->rate : is_start ? &r->start : &r->stop) = v;
		snprintf(where, SS_CASE_WHERE_SIZE, "%s", p->where);
		err = SS_OK;
	} else {
		return fail_at(p, "unknown key '%s' in [%s]: expected %s", key, section,
		               role == SS_REGION_SOURCE
		               ? "rect, disk, polygon or mask, and rate, start, stop"
		               : "one of rect, disk, polygon, mask");
	}
	snprintf(p->last_region_key, sizeof p->last_region_key, "%s", key);
	return err;
}

/* ---- one key = value ------------------------------------------------- */

static int apply(struct parse *p, const char *section, const char *key,
                 const char *value)
{
	int fixed = 0;
	for (size_t s = 0; s < sizeof fixed_sections / sizeof *fixed_sections; s++)
		fixed |= strcmp(section, fixed_sections[s]) == 0;
	if (!fixed) {
		if (p->continuation && strcmp(key, "polygon") != 0)
			return fail_at(p, "only polygon values may continue on an indented line");
		return apply_region_key(p, section, key, value);
	}
	if (p->continuation)
		return fail_at(p, "[%s] %s continues on an indented line: only polygon "
		               "values may", section, key);

	for (int k = 0; k < KEY_COUNT; k++) {
		if (strcmp(keys[k].section, section) || strcmp(keys[k].key, key))
			continue;
		if (p->key_set[k] && !p->overriding)
			return fail_at(p, "[%s] %s is set twice (first at %s)", section, key,
			               p->key_where[k]);
		int err = store_value(p, &keys[k], value);
		if (err)
			return err;
		p->key_set[k] = 1;
		snprintf(p->key_where[k], sizeof p->key_where[k], "%s", p->where);
		return SS_OK;
	}
	char known[512] = "";
	for (int k = 0; k < KEY_COUNT; k++) {
		if (strcmp(keys[k].section, section))
			continue;
		if (known[0])
			strncat(known, ", ", sizeof known - strlen(known) - 1);
		strncat(known, keys[k].key, sizeof known - strlen(known) - 1);
	}
	return fail_at(p, "unknown key '%s' in [%s]: expected one of %s", key, section, known);
}

/* ---- inih glue ------------------------------------------------------- */

static char *reader(char *str, int num, void *stream)
{
	struct parse *p = stream;
	if (!*p->cursor)
		return NULL;
	int n = 0;
	while (n < num - 1 && p->cursor[n] && p->cursor[n] != '\n')
		n++;
	if (p->cursor[n] == '\n' && n < num - 1)
		n++;
	memcpy(str, p->cursor, (size_t)n);
	str[n] = '\0';
	p->continuation = n > 0 && (str[0] == ' ' || str[0] == '\t') &&
	                  str[strspn(str, " \t\r\n")] != '\0';
	p->cursor += n;
	p->line++;
	return str;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
	struct parse *p = user;
	if (p->failed)
		return 1;   /* report the first error only */
	snprintf(p->where, sizeof p->where, "%s:%d", p->path, p->line);
	if (!p->continuation)
		return apply(p, section, name, value) == SS_OK;
	/* inih leaves inline comments on continuation lines: cut them as it
	 * does on "key = value" lines (';' after white space) */
	char buf[256];
	snprintf(buf, sizeof buf, "%s", value);
	for (char *q = buf + 1; *q; q++) {
		if (*q == ';' && isspace((unsigned char)q[-1])) {
			*q = '\0';
			break;
		}
	}
	size_t n = strlen(buf);
	while (n && isspace((unsigned char)buf[n - 1]))
		buf[--n] = '\0';
	return apply(p, section, name, buf) == SS_OK;
}

/* What inih would skip or misread: checked first, with line numbers. */
static int prescan(struct parse *p)
{
	const int max_line = 199;   /* inih's INI_MAX_LINE - 1 */
	int line = 0;
	int seen_section = 0;
	struct { char name[200]; int line; } *seen = NULL;
	int seen_count = 0, err = SS_OK;

	for (const char *s = p->text; *s && !err;) {
		const char *eol = strchr(s, '\n');
		size_t len = eol ? (size_t)(eol - s) : strlen(s);
		line++;
		snprintf(p->where, sizeof p->where, "%s:%d", p->path, line);
		char buf[256];
		if (len > (size_t)max_line) {
			err = fail_at(p, "line is longer than %d characters (continue a polygon "
			              "on indented lines)", max_line);
			break;
		}
		memcpy(buf, s, len);
		buf[len] = '\0';
		char *t = buf + strspn(buf, " \t\r");
		t[strcspn(t, "\r")] = '\0';
		if (*t == '\0' || *t == ';' || *t == '#') {
			/* blank or comment */
		} else if (*t == '[') {
			char *close = strchr(t, ']');
			if (!close) {
				err = fail_at(p, "section header without ']'");
				break;
			}
			*close = '\0';
			const char *name = t + 1;
			int ok = 0;
			for (size_t k = 0; k < sizeof fixed_sections / sizeof *fixed_sections; k++)
				ok |= strcmp(name, fixed_sections[k]) == 0;
			enum ss_region_role role;
			const char *rname;
			if (!ok && region_section(name, &role, &rname) == 0)
				ok = 1;
			if (!ok) {
				err = fail_at(p, "unknown section [%s]: expected " SECTIONS_ACCEPTED
				              " (NAME of letters, digits, _ or -)", name);
				break;
			}
			for (int k = 0; k < seen_count; k++) {
				if (strcmp(seen[k].name, name) == 0) {
					err = fail_at(p, "section [%s] appears twice (first at line %d)",
					              name, seen[k].line);
					break;
				}
			}
			if (err)
				break;
			void *grown = realloc(seen, (size_t)(seen_count + 1) * sizeof *seen);
			if (!grown) {
				err = ss_error_fail("out of memory");
				break;
			}
			seen = grown;
			snprintf(seen[seen_count].name, sizeof seen[seen_count].name, "%s", name);
			seen[seen_count++].line = line;
			seen_section = 1;
			/* regions exist from their header on, so an empty one is
			 * reported (it has no shape) */
			if (region_section(name, &role, &rname) == 0 &&
			    !region_find(p, role, rname, 1)) {
				err = SS_ERR_INPUT;
				break;
			}
		} else if (t != buf && seen_section) {
			/* an indented line continues the previous value */
		} else if (!strchr(t, '=')) {
			err = fail_at(p, "expected 'key = value', '[section]' or a comment");
		} else if (!seen_section) {
			err = fail_at(p, "key outside any section: start with [grid]");
		}
		s = eol ? eol + 1 : s + len;
	}
	free(seen);
	return err;
}

/* ---- checks across keys ---------------------------------------------- */

static int key_index(const char *section, const char *key)
{
	for (int k = 0; k < KEY_COUNT; k++)
		if (!strcmp(keys[k].section, section) && !strcmp(keys[k].key, key))
			return k;
	SS_BUG("no key [%s] %s", section, key);
}

static int require(struct parse *p, const char *section, const char *key,
                   const char *meaning)
{
	if (p->key_set[key_index(section, key)])
		return SS_OK;
	return ss_error_input("%s: [%s] is missing '%s' (%s)", p->path, section, key, meaning);
}

static int is_set(struct parse *p, const char *section, const char *key)
{
	return p->key_set[key_index(section, key)];
}

static const char *where_of(struct parse *p, const char *section, const char *key)
{
	return p->key_where[key_index(section, key)];
}

static int finish_model(struct parse *p)
{
	struct ss_case *c = p->c;
	int err = require(p, "model", "repose_angle", "degrees in (0, 90)");
	if (err)
		return err;
	if (c->closure == SS_CLOSURE_HERSCHEL_BULKLEY) {
		if ((err = require(p, "model", "gamma", "the herschel-bulkley exponent, > 0")))
			return err;
	} else {
		c->gamma = 1.0;
	}

	static const char *const physical[] = {"delta", "density", "viscosity", "consistency",
	                                       "gravity"};
	const char *given = NULL;
	for (int k = 0; k < 5 && !given; k++)
		if (is_set(p, "model", physical[k]))
			given = physical[k];
	if (is_set(p, "model", "nu")) {
		if (given)
			return ss_error_input("%s: [model] gives both nu and %s: give nu, or the "
			                      "physical parameters to derive it", where_of(p, "model", given),
			                      given);
		return SS_OK;
	}
	if (!given)
		return ss_error_input("%s: [model] is missing 'nu' (m^2/s, > 0) or the physical "
		                      "parameters delta, density and viscosity (bingham, casson) "
		                      "or consistency (herschel-bulkley)", p->path);
	if (c->closure == SS_CLOSURE_COULOMB)
		return ss_error_input("%s: [model] %s: the coulomb closure takes nu directly "
		                      "(SPEC section 1 derives nu only for bingham, "
		                      "herschel-bulkley and casson)", where_of(p, "model", given), given);
	const char *law = c->closure == SS_CLOSURE_HERSCHEL_BULKLEY ? "consistency" : "viscosity";
	const char *other = c->closure == SS_CLOSURE_HERSCHEL_BULKLEY ? "viscosity" : "consistency";
	if (is_set(p, "model", other))
		return ss_error_input("%s: [model] %s does not apply to %s: expected %s",
		                      where_of(p, "model", other), other,
		                      ss_closure_name(c->closure), law);
	if ((err = require(p, "model", "delta", "sliding layer thickness, m")) ||
	    (err = require(p, "model", "density", "kg/m^3")) ||
	    (err = require(p, "model", law, c->closure == SS_CLOSURE_HERSCHEL_BULKLEY
	                                    ? "consistency k, Pa s^gamma" : "viscosity mu, Pa s")))
		return err;
	/* tau = rho g delta sin a_cr; SPEC section 1, [Paper] eqs. 8 and 12 */
	const double tau = c->density * c->gravity * c->delta *
	                   sin(c->repose_angle_deg * M_PI / 180.0);
	const double d2 = c->delta * c->delta;
	switch (c->closure) {
	case SS_CLOSURE_BINGHAM:
		c->nu = tau * d2 / (6.0 * c->viscosity);
		break;
	case SS_CLOSURE_CASSON:
		c->nu = tau * d2 / (30.0 * c->viscosity);
		break;
	case SS_CLOSURE_HERSCHEL_BULKLEY: {
		const double g = c->gamma;
		c->nu = pow(tau / c->consistency, 1.0 / g) * g / ((1.0 + g) * (1.0 + 2.0 * g)) * d2;
		break;
	}
	default:
		break;
	}
	if (!(c->nu > 0.0) || !isfinite(c->nu))
		return ss_error_input("%s: [model] the physical parameters give nu = %g m^2/s: "
		                      "expected a finite value > 0", p->path, c->nu);
	return SS_OK;
}

/* A shape must lie inside the grid (with a tolerance of 1e-9 of its size). */
static int check_shape_extent(const struct ss_case *c, const struct ss_region *r)
{
	const struct ss_shape *sh = &r->shape;
	double lo_x = INFINITY, lo_y = INFINITY, hi_x = -INFINITY, hi_y = -INFINITY;
	switch (sh->kind) {
	case SS_SHAPE_RECT:
		lo_x = sh->v[0], lo_y = sh->v[1], hi_x = sh->v[2], hi_y = sh->v[3];
		break;
	case SS_SHAPE_DISK:
		lo_x = sh->v[0] - sh->v[2], hi_x = sh->v[0] + sh->v[2];
		lo_y = sh->v[1] - sh->v[2], hi_y = sh->v[1] + sh->v[2];
		break;
	case SS_SHAPE_POLYGON:
		for (int k = 0; k < sh->polygon_points; k++) {
			lo_x = fmin(lo_x, sh->polygon[2 * k]), hi_x = fmax(hi_x, sh->polygon[2 * k]);
			lo_y = fmin(lo_y, sh->polygon[2 * k + 1]), hi_y = fmax(hi_y, sh->polygon[2 * k + 1]);
		}
		break;
	default:
		return SS_OK;
	}
	const double x0 = c->origin_x, x1 = c->origin_x + c->nx * c->dx;
	const double y0 = c->origin_y, y1 = c->origin_y + c->ny * c->dy;
	const double tol = 1e-9 * fmax(x1 - x0, y1 - y0);
	if (lo_x < x0 - tol || hi_x > x1 + tol || lo_y < y0 - tol || hi_y > y1 + tol)
		return ss_error_input("%s: [%s %s] extends over [%g, %g] x [%g, %g] m, outside "
		                      "the grid [%g, %g] x [%g, %g] m", sh->where,
		                      region_prefix[r->role], r->name, lo_x, hi_x, lo_y, hi_y,
		                      x0, x1, y0, y1);
	return SS_OK;
}

static int finish(struct parse *p)
{
	struct ss_case *c = p->c;
	int err;
	if ((err = require(p, "grid", "nx", "number of cells west to east, an integer >= 1")) ||
	    (err = require(p, "grid", "ny", "number of cells south to north, an integer >= 1")) ||
	    (err = require(p, "grid", "dx", "cell size in m, > 0")) ||
	    (err = require(p, "time", "end", "a time in s, or steady")) ||
	    (err = require(p, "time", "output_every", "seconds between snapshots, > 0")))
		return err;
	if (!is_set(p, "grid", "dy"))
		c->dy = c->dx;
	snprintf(c->grid_where, sizeof c->grid_where, "%s", where_of(p, "grid", "nx"));
	/* shapes are checked against the far corner: it must be a number */
	if (!isfinite(c->origin_x + c->nx * c->dx) || !isfinite(c->origin_y + c->ny * c->dy))
		return ss_error_input("%s: [grid] the grid from (%g, %g) m over %d x %d cells of %g x "
		                      "%g m ends beyond the largest number: expected a finite extent",
		                      c->grid_where, c->origin_x, c->origin_y, c->nx, c->ny, c->dx,
		                      c->dy);
	if ((err = finish_model(p)))
		return err;
	if (is_set(p, "time", "max_time") && !c->steady)
		return ss_error_input("%s: [time] max_time applies to end = steady: the run "
		                      "already stops at end", where_of(p, "time", "max_time"));
	static const char *const sides[] = {"west", "east", "south", "north"};
	for (int side = 0; side < 4; side++) {
		const int opposite = side ^ 1;
		if ((c->boundary.side[side] == SS_SIDE_PERIODIC) !=
		    (c->boundary.side[opposite] == SS_SIDE_PERIODIC) &&
		    c->boundary.side[side] == SS_SIDE_PERIODIC)
			return ss_error_input("%s: [boundary] %s = periodic needs %s = periodic too "
			                      "(opposite sides wrap together)",
			                      where_of(p, "boundary", sides[side]), sides[side],
			                      sides[opposite]);
	}

	/* [initial]: keys that belong to another type are mistakes */
	static const char *const cone_keys[] = {"center", "radius", "angle"};
	for (int k = 0; k < 3; k++) {
		if (c->initial != SS_INITIAL_CONE && is_set(p, "initial", cone_keys[k]))
			return ss_error_input("%s: [initial] %s applies to type = cone",
			                      where_of(p, "initial", cone_keys[k]), cone_keys[k]);
		if (c->initial == SS_INITIAL_CONE &&
		    (err = require(p, "initial", cone_keys[k],
		                   k == 0 ? "'X Y' in m" : k == 1 ? "m, > 0" : "degrees in (0, 90)")))
			return err;
	}
	if (c->initial != SS_INITIAL_FILE && is_set(p, "initial", "file"))
		return ss_error_input("%s: [initial] file applies to type = file",
		                      where_of(p, "initial", "file"));
	if (c->initial == SS_INITIAL_FILE) {
		if ((err = require(p, "initial", "file", "an ESRI ASCII .asc or sandslide .h5 file")))
			return err;
		if (is_set(p, "initial", "height"))
			return ss_error_input("%s: [initial] height applies to type = flat or cone",
			                      where_of(p, "initial", "height"));
	}

	for (int k = 0; k < c->region_count; k++) {
		struct ss_region *r = &c->regions[k];
		if (r->shape.kind == SS_SHAPE_NONE)
			return ss_error_input("%s: [%s %s] has no shape: expected one of rect, disk, "
			                      "polygon, mask", r->where, region_prefix[r->role], r->name);
		if (r->shape.kind == SS_SHAPE_POLYGON && r->shape.polygon_points < 3)
			return ss_error_input("%s: [%s %s] polygon has %d points: expected at least 3",
			                      r->shape.where, region_prefix[r->role], r->name,
			                      r->shape.polygon_points);
		if (r->role == SS_REGION_SOURCE && !r->rate_where[0])
			return ss_error_input("%s: [source %s] is missing 'rate' (m/s, > 0)",
			                      r->where, r->name);
		if (r->role == SS_REGION_SOURCE && !(r->stop > r->start)) {
			/* blame the value that came last: an --set over the file */
			const char *at = !strncmp(r->stop_where, "--set", 5) ? r->stop_where
			               : !strncmp(r->start_where, "--set", 5) ? r->start_where
			               : r->stop_where[0] ? r->stop_where
			               : r->start_where[0] ? r->start_where : r->where;
			return ss_error_input("%s: [source %s] stop = %g s is not after start = %g s",
			                      at, r->name, r->stop, r->start);
		}
		if ((err = check_shape_extent(c, r)))
			return err;
	}
	return SS_OK;
}

/* ---- entry points ---------------------------------------------------- */

static void set_defaults(struct ss_case *c)
{
	c->closure = SS_CLOSURE_COULOMB;
	c->gamma = 1.0;
	c->gravity = 9.81;
	c->cfl = 0.9;
	c->steady_tol = 1e-9;
	c->steady_slope_tol = 1e-6;
	c->integrator = SS_INTEGRATOR_AUTO;
	c->rkl2_max_stages = SS_RKL2_MAX_STAGES_DEFAULT;
	c->rkl2_tol = SS_RKL2_TOL_DEFAULT;
	c->max_time = INFINITY;
	c->end = INFINITY;
	for (int s = 0; s < 4; s++)
		c->boundary.side[s] = SS_SIDE_WALL;
	c->boundary.open_level = 0.0;
	c->initial = SS_INITIAL_FLAT;
}

static char *trim(char *s)
{
	s += strspn(s, " \t");
	size_t n = strlen(s);
	while (n && isspace((unsigned char)s[n - 1]))
		s[--n] = '\0';
	return s;
}

static int apply_override(struct parse *p, const char *arg)
{
	snprintf(p->where, sizeof p->where, "--set %s", arg);
	const char *eq = strchr(arg, '=');
	char lhs[256];
	size_t n = eq ? (size_t)(eq - arg) : 0;
	if (!eq || n == 0 || n >= sizeof lhs)
		return fail_at(p, "expected SECTION.KEY=VALUE, e.g. model.closure=casson");
	memcpy(lhs, arg, n);
	lhs[n] = '\0';
	char *dot = strrchr(lhs, '.');
	if (!dot || dot == lhs || !dot[1])
		return fail_at(p, "expected SECTION.KEY=VALUE, e.g. model.closure=casson");
	*dot = '\0';
	char value[512];
	snprintf(value, sizeof value, "%s", eq + 1);
	/* the same trimming inih applies to file sections, keys and values */
	p->continuation = 0;
	p->overriding = 1;
	return apply(p, trim(lhs), trim(dot + 1), trim(value));
}

int ss_case_parse(struct ss_case *c, const char *path, const char *text,
                  const char *const *overrides, int override_count)
{
	memset(c, 0, sizeof *c);
	set_defaults(c);
	c->path = dup_string(path);
	c->text = dup_string(text);
	if (!c->path || !c->text)
		return ss_error_fail("out of memory reading '%s'", path);

	struct parse *p = calloc(1, sizeof *p);
	if (!p)
		return ss_error_fail("out of memory reading '%s'", path);
	p->c = c;
	p->path = path;
	p->text = p->cursor = c->text;

	int err = prescan(p);
	if (!err) {
		p->line = 0;
		int r = ini_parse_stream(reader, p, handler, p);
		if (p->failed)
			err = SS_ERR_INPUT;
		else if (r != 0)
			err = ss_error_input("%s:%d: cannot parse this line", path, r);
	}
	for (int k = 0; !err && k < override_count; k++)
		err = apply_override(p, overrides[k]);
	if (!err)
		err = finish(p);
	free(p);
	return err;
}

int ss_case_load(struct ss_case *c, const char *path,
                 const char *const *overrides, int override_count)
{
	memset(c, 0, sizeof *c);
	FILE *f = fopen(path, "rb");
	if (!f)
		return ss_error_input("cannot open case file '%s': %s", path, strerror(errno));
	char *text = NULL;
	size_t size = 0, cap = 0;
	int err = SS_OK;
	for (;;) {
		if (cap - size < 4096) {
			cap = cap ? 2 * cap : 8192;
			char *grown = cap > (64u << 20) ? NULL : realloc(text, cap);
			if (!grown) {
				err = ss_error_input("case file '%s' is too large (over 64 MiB)", path);
				break;
			}
			text = grown;
		}
		size_t got = fread(text + size, 1, cap - size - 1, f);
		size += got;
		if (got == 0)
			break;
	}
	if (!err && ferror(f))
		err = ss_error_input("cannot read case file '%s': %s", path, strerror(errno));
	fclose(f);
	if (!err && memchr(text, '\0', size))
		err = ss_error_input("case file '%s' is not a text file (it holds a NUL byte)", path);
	if (err) {
		free(text);
		return err;
	}
	text[size] = '\0';
	err = ss_case_parse(c, path, text, overrides, override_count);
	free(text);
	return err;
}

void ss_case_release(struct ss_case *c)
{
	for (int k = 0; k < c->region_count; k++) {
		free(c->regions[k].shape.polygon);
		free(c->regions[k].shape.mask_path);
	}
	free(c->regions);
	free(c->initial_file);
	free(c->bedrock_file);
	free(c->text);
	free(c->path);
	memset(c, 0, sizeof *c);
}
