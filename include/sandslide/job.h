/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * job.h - what the commands share, whatever they compute: where the output
 * goes and whether it may replace it, the threads, the tiles of the sweep,
 * the command line for the output's history, and how another party follows
 * and stops a command (a stop flag, a progress callback).  run, relax, fit
 * and render embed a struct ss_job in their options, and their option
 * tables continue with the job's, so that each of these options is
 * defined, parsed and documented once.  A watch (watch.h,
 * ss_job_set_watch) fills the stop flag and the progress.
 */
#ifndef SANDSLIDE_JOB_H
#define SANDSLIDE_JOB_H

#include <signal.h>

#include "sandslide/device.h"
#include "sandslide/option.h"
#include "sandslide/progress.h"

struct ss_job {
	const char *output;          /* the command's output file; NULL: the
	                              * command's default (its --help) */
	int force;                   /* replace an existing output (else refused) */
	int threads;                 /* OpenMP threads; <= 0: OMP_NUM_THREADS,
	                              * else the processors this process may
	                              * run on over the node's ranks
	                              * (parallel.h) */
	int tile[2];                 /* cells per tile of the sweep, nx and ny;
	                              * <= 0: the defaults (the same bits for
	                              * any tile size) */
	struct ss_device device;     /* where it computes (device.h): the CPU
	                              * unless --device names a GPU */
	const char *history;         /* the command line, for the output */
	const volatile sig_atomic_t *stop_signal; /* when it becomes non-zero,
	                              * the command stops after its substep and
	                              * writes what it has (NULL: none) */
	ss_progress_fn *progress;    /* after every substep (NULL: none) */
	void *progress_context;
};

/* The job's options (option.h): force and threads, a part of the run,
 * relax, fit and render tables; tile, device and history, of the commands
 * that step a model (run, relax, fit; at the same struct).  The output is each
 * command's own row (its meaning and default differ), stored in the job. */
extern const struct ss_option_table ss_job_option_table;
extern const struct ss_option_table ss_job_stepping_option_table;

/* The job in options whose table is t (the part of t that is the job's),
 * or NULL when t has none: for foreign callers that hold an options
 * object (ss_option_object_create) and its table. */
struct ss_job *ss_job_of(const struct ss_option_table *t, void *options);

#endif
