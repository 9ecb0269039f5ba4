/*
 * run_api.c - `run` for callers that cannot lay out its structs (see
 * run.h): options created on the heap and set by name, and the summary
 * as JSON in a buffer.  Python's ctypes module (python/sandslide) is the
 * caller this is written for: the struct layouts change between versions,
 * names and strings do not.
 *
 * The names, ranges and messages are those of run's table in
 * src/cli/main.c; `set` takes one --set override at a time, checked by
 * the case parser as the command line's are.
 */
#include "sandslide/run.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"

/* The text values an options object owns (its copies of the caller's). */
enum { TEXT_CASE, TEXT_OUTPUT, TEXT_RESTART, TEXT_HISTORY, TEXT_COUNT };

struct owned_options {
	struct ss_run_options o;     /* first: the caller's pointer is to it */
	char *text[TEXT_COUNT];      /* NULL, or the value of o's text field */
	char **sets;                 /* the overrides, o.overrides points here */
	int set_room;                /* entries allocated at sets */
};

enum key_kind { INT, FLAG, TEXT, TILE, SET };

struct key {
	const char *name;            /* run's option without "--" ("case": CASE.ini) */
	enum key_kind kind;
	size_t offset;               /* of the field in struct ss_run_options */
	long lo, hi;                 /* INT */
	const char *expected;        /* for the message, as the CLI says it */
	int text;                    /* TEXT: its slot in owned_options */
};

#define AT(m) offsetof(struct ss_run_options, m)

static const struct key keys[] = {
	{"case", TEXT, AT(case_path), 0, 0, "a path", TEXT_CASE},
	{"output", TEXT, AT(output), 0, 0, "a path", TEXT_OUTPUT},
	{"restart", TEXT, AT(restart), 0, 0, "a path", TEXT_RESTART},
	{"history", TEXT, AT(history), 0, 0, "a text", TEXT_HISTORY},
	{"set", SET, 0, 0, 0, "SECTION.KEY=VALUE", 0},
	{"threads", INT, AT(threads), 1, 4096, "an integer from 1 to 4096", 0},
	{"force", FLAG, AT(force), 0, 0, "1 or 0", 0},
	{"reference-kernel", FLAG, AT(reference_kernel), 0, 0, "1 or 0", 0},
	{"deflate", INT, AT(deflate), 0, 9, "0 to 9", 0},
	{"tile", TILE, 0, 0, 0, "NXxNY, e.g. 256x64", 0},
};

struct ss_run_options *ss_run_options_create(void)
{
	struct owned_options *w = ss_alloc(1, sizeof *w, "run options");
	return w ? &w->o : NULL;   /* zero: the defaults, as the command line's */
}

void ss_run_options_destroy(struct ss_run_options *o)
{
	if (!o)
		return;
	struct owned_options *w = (struct owned_options *)o;
	for (int k = 0; k < TEXT_COUNT; k++)
		ss_free(w->text[k]);
	for (int k = 0; k < o->override_count; k++)
		ss_free(w->sets[k]);
	ss_free(w->sets);
	ss_free(w);
}

/* key names option name, '_' standing for '-' */
static int same_key(const char *key, const char *name)
{
	for (; *key && *name; key++, name++)
		if (*key != *name && !(*key == '_' && *name == '-'))
			return 0;
	return *key == *name;
}

static int unknown_key(const char *key)
{
	char names[256];
	struct ss_strbuf b = {names, sizeof names, 0};
	for (size_t k = 0; k < sizeof keys / sizeof *keys; k++)
		ss_strbuf_printf(&b, "%s%s", k ? ", " : "", keys[k].name);
	return ss_error_input("unknown run option '%s': expected one of %s", key, names);
}

/* An integer in [lo, hi] from all of s into *out; 0, or -1. */
static int parse_int(const char *s, long lo, long hi, int *out)
{
	char *end;
	errno = 0;
	const long v = strtol(s, &end, 10);
	if (end == s || *end || errno || v < lo || v > hi)
		return -1;
	*out = (int)v;
	return 0;
}

/* "NXxNY" into o's tile size, as the command line's --tile */
static int parse_tile(const char *s, struct ss_run_options *o)
{
	const char *x = strchr(s, 'x');
	char nx[32];
	int a, b;
	if (!x || x - s >= (long)sizeof nx)
		return -1;
	memcpy(nx, s, (size_t)(x - s));
	nx[x - s] = '\0';
	if (parse_int(nx, 1, 1 << 20, &a) || parse_int(x + 1, 1, 1 << 20, &b))
		return -1;
	o->tile_nx = a;
	o->tile_ny = b;
	return 0;
}

static char *copy_text(const char *s)
{
	const size_t n = strlen(s) + 1;
	char *copy = ss_alloc(n, 1, "an option's text");
	if (copy)
		memcpy(copy, s, n);
	return copy;
}

/* One more override at the end of o's list. */
static int append_set(struct owned_options *w, const char *value)
{
	struct ss_run_options *o = &w->o;
	if (o->override_count == w->set_room) {
		const int room = w->set_room ? 2 * w->set_room : 8;
		char **sets = ss_alloc((size_t)room, sizeof *sets, "the --set overrides");
		if (!sets)
			return SS_ERR_FAIL;
		if (o->override_count)
			memcpy(sets, w->sets, (size_t)o->override_count * sizeof *sets);
		ss_free(w->sets);
		w->sets = sets;
		w->set_room = room;
	}
	char *copy = copy_text(value);
	if (!copy)
		return SS_ERR_FAIL;
	w->sets[o->override_count++] = copy;
	o->overrides = (const char *const *)w->sets;
	return SS_OK;
}

int ss_run_options_set(struct ss_run_options *o, const char *key, const char *value)
{
	const struct key *k = NULL;
	for (size_t n = 0; n < sizeof keys / sizeof *keys && !k; n++)
		if (same_key(key, keys[n].name))
			k = &keys[n];
	if (!k)
		return unknown_key(key);
	if (!value || !*value)
		return ss_error_input("%s needs a value: %s", key, k->expected);
	struct owned_options *w = (struct owned_options *)o;
	void *target = (char *)o + k->offset;
	int bad = 0;
	switch (k->kind) {
	case INT:
		bad = parse_int(value, k->lo, k->hi, target);
		break;
	case FLAG:
		bad = strcmp(value, "0") && strcmp(value, "1");
		if (!bad)
			*(int *)target = value[0] == '1';
		break;
	case TILE:
		bad = parse_tile(value, o);
		break;
	case SET:
		return append_set(w, value);
	case TEXT: {
		char *copy = copy_text(value);
		if (!copy)
			return SS_ERR_FAIL;
		ss_free(w->text[k->text]);
		w->text[k->text] = copy;
		*(const char **)target = copy;
		break;
	}
	}
	if (bad)
		return ss_error_input("%s '%s': expected %s", key, value, k->expected);
	return SS_OK;
}

static const char *end_name(enum ss_run_end end)
{
	switch (end) {
	case SS_RUN_DONE:
		return "done";
	case SS_RUN_STEADY:
		return "steady";
	case SS_RUN_NOT_STEADY:
		return "not steady";
	case SS_RUN_INTERRUPTED:
		return "interrupted";
	}
	return "?";
}

int ss_run_summary_json(const struct ss_run_summary *s, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	ss_strbuf_printf(&b, "{\n  \"output\": ");
	ss_strbuf_json_string(&b, s->output);
	ss_strbuf_printf(&b, ",\n  \"end\": \"%s\", \"snapshots\": %lld, \"time\": ",
	                 end_name(s->end), s->snapshots);
	ss_strbuf_json_number(&b, s->time, 17);
	ss_strbuf_printf(&b, ",\n  \"steps\": %lld, \"steps_here\": %lld, \"evaluations\": %lld, "
	                 "\"evaluations_here\": %lld,\n  \"integrator\": \"%s\", "
	                 "\"stages_max\": %d,\n  \"cells\": ", s->steps, s->steps_here,
	                 s->evaluations, s->evaluations_here, s->integrator ? s->integrator : "",
	                 s->stages_max);
	ss_strbuf_json_number(&b, s->cells, 17);
	ss_strbuf_printf(&b, ", \"bytes_per_cell\": ");
	ss_strbuf_json_number(&b, s->bytes_per_cell, 17);
	ss_strbuf_printf(&b, ", \"threads\": %d, \"ranks\": %d,\n  \"wall_seconds\": ", s->threads,
	                 s->ranks);
	ss_strbuf_json_number(&b, s->wall_seconds, 6);
	ss_strbuf_printf(&b, ", \"measure_seconds\": ");
	ss_strbuf_json_number(&b, s->measure_seconds, 6);
	ss_strbuf_printf(&b, ", \"sweep_seconds\": ");
	ss_strbuf_json_number(&b, s->sweep_seconds, 6);
	ss_strbuf_printf(&b, ",\n  \"output_seconds\": ");
	ss_strbuf_json_number(&b, s->output_seconds, 6);
	ss_strbuf_printf(&b, ", \"comm_seconds\": ");
	ss_strbuf_json_number(&b, s->comm_seconds, 6);
	ss_strbuf_printf(&b, "\n}\n");
	if (b.len >= size)
		return ss_error_input("the run summary needs %zu bytes: the buffer has %zu",
		                      b.len + 1, size);
	return SS_OK;
}

int ss_run_case_json(const struct ss_run_options *o, char *summary_json, size_t size)
{
	struct ss_run_summary s;
	const int err = ss_run_case(o, &s);
	return err ? err : ss_run_summary_json(&s, summary_json, size);
}
