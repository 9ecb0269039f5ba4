/*
 * run_api.c - `run` for callers that cannot lay out its structs (see
 * run.h): the summary as JSON in a buffer.  Python's ctypes module
 * (python/sandslide) is the caller this is written for: the struct layouts
 * change between versions, names and strings do not.  The options set by
 * name are run_options.c's.
 */
#include "sandslide/run.h"

#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"
#include "sandslide/watch.h"

void ss_run_options_set_watch(struct ss_run_options *o, struct ss_watch *w)
{
	o->stop_signal = w ? ss_watch_stop_flag(w) : NULL;
	o->progress = w ? ss_watch_progress : NULL;
	o->progress_context = w;
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
	ss_strbuf_printf(&b, ", \"memory_peak_bytes\": ");
	ss_strbuf_json_number(&b, s->memory_peak_bytes, 17);
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
	ss_strbuf_printf(&b, ",\n  \"notes\": [");
	for (int k = 0; k < s->note_count; k++) {
		ss_strbuf_printf(&b, "%s", k ? ", " : "");
		ss_strbuf_json_string(&b, s->notes[k]);
	}
	ss_strbuf_printf(&b, "]\n}\n");
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
