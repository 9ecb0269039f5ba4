/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * print.h - what the commands print: the progress line of a run, the
 * summaries, the benchmark's table or JSON and `info`.  The library
 * returns its figures in structs and callbacks; this is their only reader
 * that writes to a terminal.
 */
#ifndef SANDSLIDE_CLI_PRINT_H
#define SANDSLIDE_CLI_PRINT_H

#include "sandslide/bench.h"
#include "sandslide/fit.h"
#include "sandslide/progress.h"
#include "sandslide/relax.h"
#include "sandslide/render.h"
#include "sandslide/run.h"
#include "sandslide/snapshot.h"

/* The progress line on stderr ("\r  t = ..."), at most twice a second, or
 * a fit's ("\r  fitting ..."), at most four times (a process shows one;
 * context is unused). */
void cli_print_progress(void *context, const struct ss_progress *p);
/* End the progress line, if one was shown. */
void cli_progress_done(void);

/* How a run or a relaxation ended: the interruption on stderr, else (and
 * for relax also then) the summary on stdout unless quiet. */
void cli_print_run_end(const struct ss_run_summary *s, int quiet);
/* ss_run_options.on_plan: the output's projected size (context: NULL) */
void cli_print_run_plan(void *context, const struct ss_run_plan *p);
void cli_print_relax_end(const struct ss_relax_report *r, int quiet);

/* The benchmark's callbacks; context is a struct cli_bench, zeroed but
 * for json.  cli_bench_done closes the JSON document. */
struct cli_bench {
	int json;
	int rows;
};
void cli_bench_header(void *context, const struct ss_bench_header *h);
void cli_bench_result(void *context, const struct ss_bench_result *r);
void cli_bench_done(const struct cli_bench *b);

void cli_print_info(const char *path, const struct ss_snapshot_summary *s);

void cli_print_render_bench(const struct ss_render_bench_report *r);

/* The frames, video and viewer written unless quiet, and a video that
 * could not be made. */
void cli_print_render_series(const struct ss_render_series_options *o,
                             const struct ss_render_series_report *r, int quiet);

#endif
