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

#include <string.h>

#include "app/named.h"
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

#define AT(m) offsetof(struct ss_run_options, m)
#define TEXT(n, m, e, slot) {n, SS_NAMED_TEXT, AT(m), 0, 0, e, slot, NULL}

static const struct ss_named keys[] = {
	TEXT("case", case_path, "a path", TEXT_CASE),
	TEXT("output", output, "a path", TEXT_OUTPUT),
	TEXT("restart", restart, "a path", TEXT_RESTART),
	TEXT("history", history, "a text", TEXT_HISTORY),
	{"set", SS_NAMED_OWN, 0, 0, 0, "SECTION.KEY=VALUE", 0, NULL},
	{"threads", SS_NAMED_INT, AT(threads), 1, 4096, "an integer from 1 to 4096", 0, NULL},
	{"force", SS_NAMED_FLAG, AT(force), 0, 0, "1 or 0", 0, NULL},
	{"reference-kernel", SS_NAMED_FLAG, AT(reference_kernel), 0, 0, "1 or 0", 0, NULL},
	{"deflate", SS_NAMED_INT, AT(deflate), 0, 9, "0 to 9", 0, NULL},
	{"tile", SS_NAMED_OWN, 0, 0, 0, "NXxNY, e.g. 256x64", 0, NULL},
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
	char *copy = ss_named_copy(value);
	if (!copy)
		return SS_ERR_FAIL;
	w->sets[o->override_count++] = copy;
	o->overrides = (const char *const *)w->sets;
	return SS_OK;
}

int ss_run_options_set(struct ss_run_options *o, const char *key, const char *value)
{
	static const struct ss_named_table table = {"run", keys, sizeof keys / sizeof *keys};
	const struct ss_named *k = ss_named_find(&table, key);
	if (!k)
		return SS_ERR_INPUT;
	struct owned_options *w = (struct owned_options *)o;
	if (k->kind != SS_NAMED_OWN)
		return ss_named_set(k, key, value, o, w->text);
	if (!value || !*value)
		return ss_error_input("%s needs a value: %s", key, k->expected);
	if (!strcmp(k->name, "set"))
		return append_set(w, value);
	int tile[2];
	if (ss_parse_tile(value, tile))
		return ss_error_input("%s '%s': expected %s", key, value, k->expected);
	o->tile_nx = tile[0];
	o->tile_ny = tile[1];
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
