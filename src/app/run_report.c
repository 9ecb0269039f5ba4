/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * run_report.c - run's summary as JSON (its field table, report.h), and
 * run with the summary in a buffer, for callers that cannot lay out its
 * structs (see run.h).  Python's ctypes module (python/sandslide) is the
 * caller this is written for: the struct layouts change between versions,
 * names and strings do not.
 */
#include "sandslide/run.h"

#include <stddef.h>

#include "base/report.h"

static const char *end_name(int end)
{
	switch ((enum ss_run_end)end) {
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

#define FIELD(n, k, m) {.name = n, .kind = k, .offset = AT(m)}
/* a field that starts a line of the JSON */
#define LINE(n, k, m) {.name = n, .kind = k, .offset = AT(m), .line = 1}
#define AT(m) offsetof(struct ss_run_summary, m)

static const struct ss_field fields[] = {
	FIELD("output", SS_FIELD_CHARS, output),
	{.name = "end", .kind = SS_FIELD_NAME, .offset = AT(end), .line = 1, .name_of = end_name},
	FIELD("snapshots", SS_FIELD_COUNT, snapshots),
	FIELD("time", SS_FIELD_REAL, time),
	LINE("steps", SS_FIELD_COUNT, steps),
	FIELD("steps_here", SS_FIELD_COUNT, steps_here),
	FIELD("evaluations", SS_FIELD_COUNT, evaluations),
	FIELD("evaluations_here", SS_FIELD_COUNT, evaluations_here),
	LINE("integrator", SS_FIELD_TEXT, integrator),
	FIELD("stages_max", SS_FIELD_INT, stages_max),
	LINE("cells", SS_FIELD_REAL, cells),
	FIELD("cell_updates_here", SS_FIELD_REAL, cell_updates_here),
	FIELD("bytes_per_cell", SS_FIELD_REAL, bytes_per_cell),
	FIELD("memory_peak_bytes", SS_FIELD_REAL, memory_peak_bytes),
	FIELD("threads", SS_FIELD_INT, threads),
	FIELD("ranks", SS_FIELD_INT, ranks),
	LINE("wall_seconds", SS_FIELD_SECONDS, wall_seconds),
	FIELD("measure_seconds", SS_FIELD_SECONDS, measure_seconds),
	FIELD("sweep_seconds", SS_FIELD_SECONDS, sweep_seconds),
	LINE("output_seconds", SS_FIELD_SECONDS, output_seconds),
	FIELD("comm_seconds", SS_FIELD_SECONDS, comm_seconds),
	{.name = "notes", .kind = SS_FIELD_CHARS_LIST, .offset = AT(notes), .line = 1,
	 .count_offset = AT(note_count), .item_size = sizeof ((struct ss_run_summary *)0)->notes[0]},
};

int ss_run_summary_json(const struct ss_run_summary *s, char *buf, size_t size)
{
	return ss_report_json(fields, sizeof fields / sizeof *fields, s, "the run summary", buf,
	                      size);
}

int ss_run_case_json(const struct ss_run_options *o, char *summary_json, size_t size)
{
	struct ss_run_summary s;
	const int err = ss_run_case(o, &s);
	return err ? err : ss_run_summary_json(&s, summary_json, size);
}
