/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * case.c - case file parser (see case.h; every key is documented in
 * doc/case-file.md and cases/reference.ini).
 *
 * inih does the INI syntax; a reader callback counts lines so that each
 * message names file:line (Debian's inih is built without line numbers in
 * the handler).  A first pass over the text checks what inih would accept
 * silently: section names, repeated sections, over-long lines, lines that
 * are neither a section, a key nor a comment.  The keys of the fixed
 * sections are one option table (option.h), continued by the model's
 * (model_options.h), so parsing, defaults and messages agree with relax's
 * command line.
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

#include "base/strings.h"
#include "sandslide/error.h"

/* ---- the keys of the fixed sections ----------------------------------- */

/* "X Y" into two doubles */
static int parse_pair(const char *value, void *field)
{
	double v[2];
	if (ss_parse_numbers(value, 0, v, 2) != 2)
		return -1;
	memcpy(field, v, sizeof v);
	return 0;
}

static int parse_side(const char *value, void *field)
{
	return ss_side_kind_parse(value, field);
}

/* a time > 0, or "steady": INFINITY (the case's steady flag follows end) */
static int parse_end(const char *value, void *field)
{
	if (!strcmp(value, "steady")) {
		*(double *)field = INFINITY;
		return 0;
	}
	char *end;
	errno = 0;
	const double t = strtod(value, &end);
	if (end == value || *end || errno || !isfinite(t) || !(t > 0.0))
		return -1;
	*(double *)field = t;
	return 0;
}

static int parse_initial(const char *value, void *field)
{
	static const char *const names[] = {"flat", "cone", "file"};
	for (int m = 0; m < 3; m++) {
		if (!strcmp(value, names[m])) {
			*(enum ss_initial_type *)field = (enum ss_initial_type)m;
			return 0;
		}
	}
	return -1;
}

#define AT(m) offsetof(struct ss_case, m)
#define KEY(k, kind_, field, ...) \
	{.case_key = k, .kind = kind_, .offset = AT(field), __VA_ARGS__}
#define NUMBER(k, field, ...) KEY(k, SS_OPTION_REAL, field, __VA_ARGS__)
#define WORD(k, field, f, ...) KEY(k, SS_OPTION_WORD, field, .parse = f, __VA_ARGS__)

static const struct ss_option keys[] = {
	KEY("grid.nx", SS_OPTION_INT, nx, .lo = 1, .hi = INT_MAX / 4,
	    .flags = SS_OPTION_CASE_REQUIRED, .expected = "an integer >= 1",
	    .help = "number of cells west to east"),
	KEY("grid.ny", SS_OPTION_INT, ny, .lo = 1, .hi = INT_MAX / 4,
	    .flags = SS_OPTION_CASE_REQUIRED, .expected = "an integer >= 1",
	    .help = "number of cells south to north"),
	NUMBER("grid.dx", dx, .lo = 0.0, .hi = INFINITY,
	       .flags = SS_OPTION_CASE_REQUIRED | SS_OPTION_LO_OPEN,
	       .expected = "a finite number > 0", .help = "cell size in m"),
	NUMBER("grid.dy", dy, SS_OPTION_POSITIVE, .expected = "a finite number > 0",
	       .help = "cell size south to north, m (default dx)"),
	WORD("grid.origin", origin_x, parse_pair, .default_value = "0 0",
	     .expected = "two finite numbers 'X Y'", .help = "lower-left corner, m"),
	WORD("time.end", end, parse_end, .flags = SS_OPTION_CASE_REQUIRED,
	     .expected = "a time in s > 0, or steady", .help = "when the run stops"),
	NUMBER("time.output_every", output_every, .lo = 0.0, .hi = INFINITY,
	       .flags = SS_OPTION_CASE_REQUIRED | SS_OPTION_LO_OPEN,
	       .expected = "a finite number > 0", .help = "seconds between snapshots"),
	WORD("boundary.west", boundary.side[SS_WEST], parse_side, .default_value = "wall",
	     .expected = "wall, open or periodic"),
	WORD("boundary.east", boundary.side[SS_EAST], parse_side, .default_value = "wall",
	     .expected = "wall, open or periodic"),
	WORD("boundary.south", boundary.side[SS_SOUTH], parse_side, .default_value = "wall",
	     .expected = "wall, open or periodic"),
	WORD("boundary.north", boundary.side[SS_NORTH], parse_side, .default_value = "wall",
	     .expected = "wall, open or periodic"),
	NUMBER("boundary.open_level", boundary.open_level, .default_value = "0", .lo = -INFINITY,
	       .hi = INFINITY, .expected = "a finite number", .help = "m"),
	WORD("initial.type", initial, parse_initial, .default_value = "flat",
	     .expected = "flat, cone or file"),
	NUMBER("initial.height", initial_height, .default_value = "0", .lo = -INFINITY,
	       .hi = INFINITY, .expected = "a finite number", .help = "m"),
	WORD("initial.center", cone_x, parse_pair, .expected = "two finite numbers 'X Y'",
	     .help = "'X Y' in m"),
	NUMBER("initial.radius", cone_radius, SS_OPTION_POSITIVE, .expected = "a finite number > 0",
	       .help = "m, > 0"),
	NUMBER("initial.angle", cone_angle_deg, .lo = 0.0, .hi = 90.0,
	       .flags = SS_OPTION_LO_OPEN | SS_OPTION_HI_OPEN, .expected = "degrees in (0, 90)",
	       .help = "degrees in (0, 90)"),
	KEY("initial.file", SS_OPTION_TEXT, initial_file, .expected = "a file name",
	    .help = "a raster of the grid's size"),
	KEY("initial.bedrock", SS_OPTION_TEXT, bedrock_file, .expected = "a file name",
	    .help = "a raster of the grid's size"),
};
#undef KEY
#undef NUMBER
#undef WORD

static const struct ss_option_part parts[] = {{&ss_model_option_table, AT(model)}};

const struct ss_option_table ss_case_option_table = {
	.command = "case", .options = keys, .count = sizeof keys / sizeof *keys,
	.parts = parts, .part_count = 1,
};

/* Every key of the table and of the model's, in order: an index for the
 * parse state's bookkeeping. */
enum { MAX_KEYS = 64 };

static const char *const fixed_sections[] = {"grid", "model", "time", "boundary", "initial"};
static const char *const region_prefix[] = {
	[SS_REGION_WALL] = "wall", [SS_REGION_OPEN] = "open", [SS_REGION_SOURCE] = "source",
};
#define SECTIONS_ACCEPTED "grid, model, time, boundary, initial, wall NAME, open NAME, " \
                          "source NAME, material NAME"
#define MAX_REGIONS 256

/* Where a key's value came from: the file (file:line) or an override. */
struct key_state {
	int set;                        /* given, and not unset since */
	int by_override;                /* last given by --set */
	char where[SS_CASE_WHERE_SIZE]; /* "file:line" or "--set ..." */
};

struct parse {
	struct ss_case *c;
	const char *path;          /* for messages */
	const char *text, *cursor; /* reader state */
	int line;                  /* line inih is handling */
	int continuation;          /* that line starts with white space */
	int overriding;            /* applying --set: later values replace */
	int failed;
	char where[SS_CASE_WHERE_SIZE];           /* location of the value being applied */
	struct key_state key[MAX_KEYS];
	char last_region_key[16];  /* for polygon continuation lines */
};

/* An error in the value being applied: named by its location, and the
 * first error is the only one reported. */
#define fail_at(p, ...) ((p)->failed = 1, ss_error_input_at((p)->where, __VA_ARGS__))

/* The option of key "section.key" and its index in the bookkeeping, or
 * NULL. */
static const struct ss_option *find_key(const char *key, int *index, size_t *offset)
{
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(&ss_case_option_table, option, at);
	if (n > MAX_KEYS)
		SS_BUG("the case has %d keys: more than MAX_KEYS", n);
	for (int k = 0; k < n; k++)
		if (option[k]->case_key && !strcmp(option[k]->case_key, key)) {
			*index = k;
			*offset = at[k];
			return option[k];
		}
	return NULL;
}

/* The bookkeeping of "section.key", which must exist. */
static struct key_state *state_of(struct parse *p, const char *key)
{
	int index;
	size_t offset;
	if (!find_key(key, &index, &offset))
		SS_BUG("no case key %s", key);
	return &p->key[index];
}

static int is_set(struct parse *p, const char *key)
{
	return state_of(p, key)->set;
}

static const char *where_of(struct parse *p, const char *key)
{
	return state_of(p, key)->where;
}

/* ---- values ---------------------------------------------------------- */

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

/* The file keys' own copies: a path resolved and owned by the case. */
static int store_path(struct parse *p, char **field, const char *value)
{
	char *s = resolve_path(p->path, value);
	if (!s)
		return ss_error_fail("out of memory reading '%s'", p->path);
	free(*field);
	*field = s;
	char *where = field == &p->c->bedrock_file ? p->c->bedrock_where
	            : field == &p->c->angle_file ? p->c->angle_where
	            : field == (char **)&p->c->model.materials_file ? p->c->materials_where
	            : p->c->initial_where;
	snprintf(where, SS_CASE_WHERE_SIZE, "%s", p->where);
	return SS_OK;
}

/* key (section.key) of the fixed sections = value */
static int store_value(struct parse *p, const char *section, const char *name,
                       const struct ss_option *o, size_t offset, const char *value)
{
	void *field = (char *)p->c + offset + o->offset;
	if (o->kind == SS_OPTION_TEXT && *value)
		return store_path(p, field, value);
	if (o->kind != SS_OPTION_TEXT && ss_option_parse(o, value, field) == 0) {
		if (field == &p->c->end)
			p->c->steady = isinf(p->c->end);
		if (o->flags & SS_OPTION_OR_FILE) {
			/* [model] repose_angle: a number, or a raster the case owns */
			const char **file = (const char **)((char *)field - o->offset +
			                                    o->value_offset);
			int err = SS_OK;
			if (*file)
				err = store_path(p, &p->c->angle_file, *file);
			else {
				free(p->c->angle_file);
				p->c->angle_file = NULL;
			}
			*file = p->c->angle_file;
			return err;
		}
		return SS_OK;
	}
	return fail_at(p, "[%s] %s = '%s' is not valid: expected %s", section, name, value,
	               o->expected);
}

/* key back to what it is when no one gives it: its default, or none */
static void reset_value(struct parse *p, const struct ss_option *o, size_t offset)
{
	void *field = (char *)p->c + offset + o->offset;
	if (o->kind == SS_OPTION_TEXT) {
		free(*(char **)field);
		*(char **)field = NULL;
		return;
	}
	if (o->flags & SS_OPTION_OR_FILE) {
		free(p->c->angle_file);
		p->c->angle_file = NULL;
	}
	if (o->default_value)
		ss_option_parse(o, o->default_value, field);
	else if (o->kind == SS_OPTION_REAL)
		*(double *)field = NAN;
	else if (o->kind == SS_OPTION_WORD)
		*(double *)field = 0.0;   /* end, a pair: as the case starts */
	else
		*(int *)field = 0;
	if (field == &p->c->end)
		p->c->steady = 0;
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

static void shape_clear(struct ss_shape *sh)
{
	free(sh->polygon);
	free(sh->mask_path);
	memset(sh, 0, sizeof *sh);
}

static int region_shape(struct parse *p, struct ss_region *r, const char *key,
                        const char *value, const char *section)
{
	struct ss_shape *sh = &r->shape;
	int polygon_more = p->continuation && strcmp(key, "polygon") == 0 &&
	                   sh->kind == SS_SHAPE_POLYGON &&
	                   strcmp(p->last_region_key, "polygon") == 0;
	if (p->overriding && !polygon_more)
		shape_clear(sh);
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
	const enum ss_shape_kind kind = !strcmp(key, "rect") ? SS_SHAPE_RECT
	                              : !strcmp(key, "disk") ? SS_SHAPE_DISK : SS_SHAPE_POLYGON;
	if (kind != SS_SHAPE_POLYGON) {
		if (ss_shape_parse_numbers(kind, value, sh))
			return fail_at(p, "[%s] %s = '%s': expected %s", section, key, value,
			               ss_shape_expected(kind));
		return SS_OK;
	}
	/* polygon, possibly continued on indented lines */
	const int count = ss_parse_numbers(value, 0, NULL, 0);
	if (count < 0 || count % 2)
		return fail_at(p, "[%s] polygon = '%s': expected %s", section, value,
		               ss_shape_expected(SS_SHAPE_POLYGON));
	double *pts = realloc(sh->polygon, (size_t)(2 * sh->polygon_points + count) * sizeof *pts);
	if (!pts)
		return ss_error_fail("out of memory");
	sh->polygon = pts;
	ss_parse_numbers(value, 0, pts + 2 * sh->polygon_points, count);
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

/* The region an override names, or NULL after the message. */
static struct ss_region *override_region(struct parse *p, const char *section)
{
	enum ss_region_role role;
	const char *name;
	if (region_section(section, &role, &name)) {
		fail_at(p, "unknown section [%s]: expected " SECTIONS_ACCEPTED, section);
		return NULL;
	}
	/* --set changes a section of the case; it does not make one up (an
	 * --set of a misspelt name said the new section "has no shape") */
	struct ss_region *r = region_find(p, role, name, 0);
	if (!r)
		no_such_region(p, role, name);
	return r;
}

static int is_shape_key(const char *key)
{
	return !strcmp(key, "rect") || !strcmp(key, "disk") || !strcmp(key, "polygon") ||
	       !strcmp(key, "mask");
}

static int is_source_key(const char *key)
{
	return !strcmp(key, "rate") || !strcmp(key, "start") || !strcmp(key, "stop");
}

static int unknown_region_key(struct parse *p, enum ss_region_role role, const char *section,
                              const char *key)
{
	return fail_at(p, "unknown key '%s' in [%s]: expected %s", key, section,
	               role == SS_REGION_SOURCE
	               ? "rect, disk, polygon or mask, and rate, start, stop"
	               : "one of rect, disk, polygon, mask");
}

static int apply_region_key(struct parse *p, const char *section, const char *key,
                            const char *value)
{
	enum ss_region_role role;
	const char *name;
	struct ss_region *r;
	if (p->overriding) {
		if (!(r = override_region(p, section)))
			return SS_ERR_INPUT;
		role = r->role;
	} else {
		if (region_section(section, &role, &name))
			return fail_at(p, "unknown section [%s]: expected " SECTIONS_ACCEPTED, section);
		if (!(r = region_find(p, role, name, 1)))
			return SS_ERR_INPUT;
	}

	int err;
	if (is_shape_key(key)) {
		err = region_shape(p, r, key, value, section);
	} else if (role == SS_REGION_SOURCE && is_source_key(key)) {
		const int is_rate = key[0] == 'r', is_start = key[2] == 'a';
		char *where = is_rate ? r->rate_where : is_start ? r->start_where : r->stop_where;
		double v;
		if (where[0] && !p->overriding)
			return fail_at(p, "[%s] %s is set twice (first at %s)", section, key, where);
		if (ss_parse_real(value, 0.0, INFINITY, &v) || (is_rate && v == 0.0))
			return fail_at(p, "[%s] %s = '%s': expected %s", section, key, value,
			               is_rate ? "a finite number > 0 (m/s)" : "a time in s >= 0");
		*(is_rate ? &r->rate : is_start ? &r->start : &r->stop) = v;
		snprintf(where, SS_CASE_WHERE_SIZE, "%s", p->where);
		err = SS_OK;
	} else {
		return unknown_region_key(p, role, section, key);
	}
	snprintf(p->last_region_key, sizeof p->last_region_key, "%s", key);
	return err;
}

/* ---- one key = value ------------------------------------------------- */

static int is_fixed(const char *section)
{
	for (size_t s = 0; s < sizeof fixed_sections / sizeof *fixed_sections; s++)
		if (!strcmp(section, fixed_sections[s]))
			return 1;
	return 0;
}

static int unknown_key(struct parse *p, const char *section, const char *key)
{
	char known[512] = "";
	const size_t n = strlen(section);
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int count = ss_option_flatten(&ss_case_option_table, option, at);
	for (int k = 0; k < count; k++) {
		const char *ck = option[k]->case_key;
		if (!ck || strncmp(ck, section, n) || ck[n] != '.')
			continue;
		if (known[0])
			strncat(known, ", ", sizeof known - strlen(known) - 1);
		strncat(known, ck + n + 1, sizeof known - strlen(known) - 1);
	}
	return fail_at(p, "unknown key '%s' in [%s]: expected one of %s", key, section, known);
}

/* The option of [section] key of a fixed section, or NULL after the
 * message naming the keys the section has. */
static const struct ss_option *fixed_key(struct parse *p, const char *section,
                                         const char *key, int *index, size_t *offset)
{
	char full[256];
	snprintf(full, sizeof full, "%s.%s", section, key);
	const struct ss_option *o = find_key(full, index, offset);
	if (!o)
		unknown_key(p, section, key);
	return o;
}

/* key = value of [material NAME] (material_table.h); an override changes
 * a section of the case, it does not make one up. */
static int apply_material_key(struct parse *p, const char *name, const char *key,
                              const char *value)
{
	struct ss_case *c = p->c;
	int known = 0;
	for (int k = 0; c->material_table && k < c->material_table->count; k++)
		known |= !strcmp(c->material_table->item[k].name, name);
	if (p->overriding && !known)
		return fail_at(p, "the case has no [material %s]", name);
	if (!c->material_table && !(c->material_table = calloc(1, sizeof *c->material_table)))
		return ss_error_fail("out of memory reading '%s'", p->path);
	return ss_material_table_set(c->material_table, name, key, value, p->where);
}

static int apply(struct parse *p, const char *section, const char *key,
                 const char *value)
{
	const char *material = ss_material_section(section);
	if (material) {
		if (p->continuation)
			return fail_at(p, "[%s] %s continues on an indented line: only polygon "
			               "values may", section, key);
		return apply_material_key(p, material, key, value);
	}
	if (!is_fixed(section)) {
		if (p->continuation && strcmp(key, "polygon") != 0)
			return fail_at(p, "only polygon values may continue on an indented line");
		return apply_region_key(p, section, key, value);
	}
	if (p->continuation)
		return fail_at(p, "[%s] %s continues on an indented line: only polygon "
		               "values may", section, key);

	int index;
	size_t offset;
	const struct ss_option *o = fixed_key(p, section, key, &index, &offset);
	if (!o)
		return SS_ERR_INPUT;
	struct key_state *k = &p->key[index];
	if (k->set && !p->overriding)
		return fail_at(p, "[%s] %s is set twice (first at %s)", section, key, k->where);
	int err = store_value(p, section, key, o, offset, value);
	if (err)
		return err;
	k->set = 1;
	k->by_override = p->overriding;
	snprintf(k->where, sizeof k->where, "%s", p->where);
	return SS_OK;
}

/* --unset SECTION.KEY (as if the file did not give it) or --unset SECTION
 * (a wall, open or source section removed). */
static int unset(struct parse *p, char *lhs)
{
	char *dot = strrchr(lhs, '.');
	if (!dot) {
		if (is_fixed(lhs))
			return fail_at(p, "[%s] cannot be removed: unset its keys (SECTION.KEY)", lhs);
		struct ss_region *r = override_region(p, lhs);
		if (!r)
			return SS_ERR_INPUT;
		struct ss_case *c = p->c;
		shape_clear(&r->shape);
		const ptrdiff_t at = r - c->regions;
		memmove(r, r + 1, (size_t)(c->region_count - at - 1) * sizeof *r);
		c->region_count--;
		return SS_OK;
	}
	*dot = '\0';
	const char *section = lhs, *key = dot + 1;
	if (!is_fixed(section)) {
		struct ss_region *r = override_region(p, section);
		if (!r)
			return SS_ERR_INPUT;
		if (is_shape_key(key)) {
			shape_clear(&r->shape);   /* finish() then says it has none */
		} else if (r->role == SS_REGION_SOURCE && is_source_key(key)) {
			const int is_rate = key[0] == 'r', is_start = key[2] == 'a';
			if (is_rate) {
				r->rate = 0.0;
				r->rate_where[0] = '\0';
			} else if (is_start) {
				r->start = 0.0;
				r->start_where[0] = '\0';
			} else {
				r->stop = INFINITY;
				r->stop_where[0] = '\0';
			}
		} else {
			return unknown_region_key(p, r->role, section, key);
		}
		return SS_OK;
	}
	int index;
	size_t offset;
	const struct ss_option *o = fixed_key(p, section, key, &index, &offset);
	if (!o)
		return SS_ERR_INPUT;
	reset_value(p, o, offset);
	memset(&p->key[index], 0, sizeof p->key[index]);
	return SS_OK;
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
			enum ss_region_role role;
			const char *rname;
			if (!is_fixed(name) && region_section(name, &role, &rname) != 0 &&
			    !ss_material_section(name)) {
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

/* Every key flagged SS_OPTION_CASE_REQUIRED, in the tables' order: its
 * help and what it accepts say what is missing. */
static int require_flagged(struct parse *p)
{
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(&ss_case_option_table, option, at);
	for (int k = 0; k < n; k++) {
		const struct ss_option *o = option[k];
		if (!(o->flags & SS_OPTION_CASE_REQUIRED) || is_set(p, o->case_key))
			continue;
		if (!strcmp(o->case_key, "model.repose_angle") && is_set(p, "model.materials"))
			continue;   /* the materials give the angles */
		const char *dot = strchr(o->case_key, '.');
		return ss_error_input("%s: [%.*s] is missing '%s' (%s, %s)", p->path,
		                      (int)(dot - o->case_key), o->case_key, dot + 1, o->help,
		                      o->expected);
	}
	return SS_OK;
}

static int require(struct parse *p, const char *key, const char *meaning)
{
	if (is_set(p, key))
		return SS_OK;
	const char *dot = strchr(key, '.');
	return ss_error_input("%s: [%.*s] is missing '%s' (%s)", p->path, (int)(dot - key), key,
	                      dot + 1, meaning);
}

/* Another sentence for the summary: what an override did to the file. */
__attribute__((format(printf, 2, 3)))
static void note(struct parse *p, const char *fmt, ...)
{
	struct ss_case *c = p->c;
	if (c->note_count == SS_CASE_MAX_NOTES)
		return;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(c->notes[c->note_count++], SS_CASE_NOTE_SIZE, fmt, ap);
	va_end(ap);
}

/* The file's key, made redundant by the override at why, is dropped. */
static void drop(struct parse *p, const char *key, const char *why, const char *reason)
{
	int index = 0;
	size_t offset = 0;
	const struct ss_option *o = find_key(key, &index, &offset);
	const char *dot = strchr(key, '.');
	if (!o || !dot)
		SS_BUG("no case key %s", key);
	note(p, "[%.*s] %s (%s) is dropped: %s %s", (int)(dot - key), key, dot + 1,
	     p->key[index].where, why, reason);
	reset_value(p, o, offset);
	memset(&p->key[index], 0, sizeof p->key[index]);
}

/* The file gives key, and an override makes it redundant: dropped.  Else
 * (both from the file, or both overrides) it is an error. */
static int file_key(struct parse *p, const char *key)
{
	const struct key_state *k = state_of(p, key);
	return k->set && !k->by_override;
}

static int by_override(struct parse *p, const char *key)
{
	const struct key_state *k = state_of(p, key);
	return k->set && k->by_override;
}

static int finish_model(struct parse *p)
{
	struct ss_case *c = p->c;
	struct ss_model_options *m = &c->model;
	int err;
	if (m->closure != SS_CLOSURE_HERSCHEL_BULKLEY)
		m->gamma = 1.0;   /* the others have no exponent (the output says 1) */

	/* nu, or the sliding layer it derives from (the model's keys of
	 * ss_model_option_is_layer, in the table's order): an override of
	 * one drops the other from the file */
	const char *physical[8];
	int physical_count = 0;
	for (int k = 0; k < ss_model_option_table.count; k++)
		if (ss_model_option_is_layer(&ss_model_option_table.options[k]))
			physical[physical_count++] = ss_model_option_table.options[k].case_key;
	const char *given = NULL, *given_by_override = NULL;
	for (int k = 0; k < physical_count; k++) {
		if (!given && is_set(p, physical[k]))
			given = physical[k];
		if (!given_by_override && by_override(p, physical[k]))
			given_by_override = physical[k];
	}
	if (given && is_set(p, "model.nu")) {
		if (by_override(p, "model.nu") && !given_by_override) {
			for (int k = 0; k < physical_count; k++)
				if (is_set(p, physical[k]))
					drop(p, physical[k], where_of(p, "model.nu"), "gives nu");
			given = NULL;
		} else if (given_by_override && file_key(p, "model.nu")) {
			drop(p, "model.nu", where_of(p, given_by_override),
			     "gives the sliding layer nu is derived from");
		} else {
			return ss_error_input("%s: [model] gives both nu and %s: give nu, or the "
			                      "physical parameters to derive it", where_of(p, given),
			                      strchr(given, '.') + 1);
		}
	}
	if (is_set(p, "model.nu"))
		return SS_OK;
	if (!given)
		return ss_error_input("%s: [model] is missing 'nu' (m^2/s, > 0) or the physical "
		                      "parameters delta, density and viscosity (bingham, casson) "
		                      "or consistency (herschel-bulkley)", p->path);
	if (m->closure == SS_CLOSURE_COULOMB)
		return ss_error_input("%s: [model] %s: the coulomb closure takes nu directly "
		                      "(doc/model.md derives nu only for bingham, "
		                      "herschel-bulkley and casson)%s",
		                      by_override(p, "model.closure") ? where_of(p, "model.closure")
		                                                      : where_of(p, given),
		                      strchr(given, '.') + 1,
		                      by_override(p, "model.closure") ? ": give model.nu too" : "");
	const int hb = m->closure == SS_CLOSURE_HERSCHEL_BULKLEY;
	const char *law = hb ? "model.consistency" : "model.viscosity";
	const char *other = hb ? "model.viscosity" : "model.consistency";
	if (file_key(p, other) && by_override(p, "model.closure"))
		drop(p, other, where_of(p, "model.closure"), "takes the other law");
	if (is_set(p, other))
		return ss_error_input("%s: [model] %s does not apply to %s: expected %s",
		                      where_of(p, other), strchr(other, '.') + 1,
		                      ss_closure_name(m->closure), strchr(law, '.') + 1);
	if ((err = require(p, "model.delta", "sliding layer thickness, m")) ||
	    (err = require(p, "model.density", "kg/m^3")) ||
	    (err = require(p, law, hb ? "consistency k, Pa s^gamma" : "viscosity mu, Pa s")))
		return err;
	m->nu = ss_model_nu_from_layer(m);
	m->nu_from_layer = 1;
	if (!(m->nu > 0.0) || !isfinite(m->nu))
		return ss_error_input("%s: [model] the physical parameters give nu = %g m^2/s: "
		                      "expected a finite value > 0", p->path, m->nu);
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

/* A key of [initial] that belongs to another type: dropped when the type
 * came from an override and the key from the file, else an error. */
static int initial_key_of_other_type(struct parse *p, const char *key, const char *applies)
{
	if (!is_set(p, key))
		return SS_OK;
	if (file_key(p, key) && by_override(p, "initial.type")) {
		char reason[64];
		snprintf(reason, sizeof reason, "(%s applies to type = %s)", strchr(key, '.') + 1,
		         applies);
		drop(p, key, where_of(p, "initial.type"), reason);
		return SS_OK;
	}
	return ss_error_input("%s: [initial] %s applies to type = %s", where_of(p, key),
	                      strchr(key, '.') + 1, applies);
}

static int finish_initial(struct parse *p)
{
	struct ss_case *c = p->c;
	static const char *const cone_keys[] = {"initial.center", "initial.radius", "initial.angle"};
	static const char *const cone_meaning[] = {"'X Y' in m", "m, > 0", "degrees in (0, 90)"};
	int err;
	for (int k = 0; k < 3; k++) {
		if (c->initial != SS_INITIAL_CONE &&
		    (err = initial_key_of_other_type(p, cone_keys[k], "cone")))
			return err;
		if (c->initial == SS_INITIAL_CONE && (err = require(p, cone_keys[k], cone_meaning[k])))
			return err;
	}
	if (c->initial != SS_INITIAL_FILE &&
	    (err = initial_key_of_other_type(p, "initial.file", "file")))
		return err;
	if (c->initial == SS_INITIAL_FILE) {
		if ((err = require(p, "initial.file", "an ESRI ASCII .asc or sandslide .h5 file")) ||
		    (err = initial_key_of_other_type(p, "initial.height", "flat or cone")))
			return err;
	}
	return SS_OK;
}

static int finish_regions(struct parse *p)
{
	struct ss_case *c = p->c;
	int err;
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

/* [model] materials = FILE and [material NAME] sections go together; the
 * angles come one way. */
static int finish_materials(struct parse *p)
{
	struct ss_case *c = p->c;
	if (c->model.materials_file && !c->material_table)
		return ss_error_input("%s: [model] materials = %s needs a [material NAME] section "
		                      "for each class", c->materials_where, c->model.materials_file);
	if (c->material_table && !c->model.materials_file)
		return ss_error_input("%s: [material %s] needs [model] materials = FILE, the raster "
		                      "of classes", c->material_table->item[0].where,
		                      c->material_table->item[0].name);
	if (c->material_table && is_set(p, "model.repose_angle"))
		return ss_error_input("%s: [model] repose_angle with materials = %s: each [material "
		                      "NAME] gives its own", where_of(p, "model.repose_angle"),
		                      c->model.materials_file);
	return c->material_table ? ss_material_table_check(c->material_table, p->path) : SS_OK;
}

static int finish(struct parse *p)
{
	struct ss_case *c = p->c;
	int err;
	if ((err = require_flagged(p)))
		return err;
	if (!is_set(p, "grid.dy"))
		c->dy = c->dx;
	snprintf(c->grid_where, sizeof c->grid_where, "%s", where_of(p, "grid.nx"));
	/* shapes are checked against the far corner: it must be a number */
	if (!isfinite(c->origin_x + c->nx * c->dx) || !isfinite(c->origin_y + c->ny * c->dy))
		return ss_error_input("%s: [grid] the grid from (%g, %g) m over %d x %d cells of %g x "
		                      "%g m ends beyond the largest number: expected a finite extent",
		                      c->grid_where, c->origin_x, c->origin_y, c->nx, c->ny, c->dx,
		                      c->dy);
	if ((err = finish_model(p)))
		return err;
	if ((err = finish_materials(p)))
		return err;
	/* max_time limits a steady run; an override that gives the run an end
	 * makes the file's max_time redundant */
	if (is_set(p, "time.max_time") && !c->steady) {
		if (file_key(p, "time.max_time") && by_override(p, "time.end"))
			drop(p, "time.max_time", where_of(p, "time.end"),
			     "gives the run its end (max_time applies to end = steady)");
		else
			return ss_error_input("%s: [time] max_time applies to end = steady: the run "
			                      "already stops at end", where_of(p, "time.max_time"));
	}
	static const char *const sides[] = {"boundary.west", "boundary.east", "boundary.south",
	                                    "boundary.north"};
	for (int side = 0; side < 4; side++) {
		const int opposite = side ^ 1;
		if ((c->boundary.side[side] == SS_SIDE_PERIODIC) !=
		    (c->boundary.side[opposite] == SS_SIDE_PERIODIC) &&
		    c->boundary.side[side] == SS_SIDE_PERIODIC)
			return ss_error_input("%s: [boundary] %s = periodic needs %s = periodic too "
			                      "(opposite sides wrap together)",
			                      where_of(p, sides[side]), sides[side] + 9,
			                      sides[opposite] + 9);
	}
	if ((err = finish_initial(p)))
		return err;
	return finish_regions(p);
}

/* ---- entry points ---------------------------------------------------- */

static char *trim(char *s)
{
	s += strspn(s, " \t");
	size_t n = strlen(s);
	while (n && isspace((unsigned char)s[n - 1]))
		s[--n] = '\0';
	return s;
}

/* "SECTION.KEY=VALUE" sets a key; "SECTION.KEY" or "SECTION" unsets. */
static int apply_override(struct parse *p, const char *arg)
{
	const char *eq = strchr(arg, '=');
	snprintf(p->where, sizeof p->where, "%s %s", eq ? "--set" : "--unset", arg);
	char lhs[256];
	const size_t n = eq ? (size_t)(eq - arg) : strlen(arg);
	if (n == 0 || n >= sizeof lhs)
		return fail_at(p, eq ? "expected SECTION.KEY=VALUE, e.g. model.closure=casson"
		                     : "expected SECTION.KEY, e.g. time.max_time, or a section "
		                       "such as 'source pour'");
	memcpy(lhs, arg, n);
	lhs[n] = '\0';
	p->continuation = 0;
	p->overriding = 1;
	if (!eq)
		return unset(p, trim(lhs));
	char *dot = strrchr(lhs, '.');
	if (!dot || dot == lhs || !dot[1])
		return fail_at(p, "expected SECTION.KEY=VALUE, e.g. model.closure=casson");
	*dot = '\0';
	char value[512];
	snprintf(value, sizeof value, "%s", eq + 1);
	/* the same trimming inih applies to file sections, keys and values */
	return apply(p, trim(lhs), trim(dot + 1), trim(value));
}

int ss_case_parse(struct ss_case *c, const char *path, const char *text,
                  const char *const *overrides, int override_count)
{
	memset(c, 0, sizeof *c);
	ss_option_defaults(&ss_case_option_table, c);
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
	for (int k = 0; k < c->region_count; k++)
		shape_clear(&c->regions[k].shape);
	free(c->regions);
	free(c->initial_file);
	free(c->bedrock_file);
	free(c->angle_file);
	free((char *)c->model.materials_file);
	free(c->material_table);
	free(c->text);
	free(c->path);
	memset(c, 0, sizeof *c);
}
