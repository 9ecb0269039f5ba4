/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * bench.h - `sandslide bench`: throughput of the fast sweep on synthetic
 * surfaces, next to the machine's memory bandwidth measured in the same run.
 *
 *   supercritical  a tilted plane, periodic sides: every face slides
 *   subcritical    a gentler plane inside walls: nothing slides after the
 *                  first sweep, so every tile is skipped
 *   patch          a flat floor with one 512 x 512 supercritical ramp
 *   room           the door of cases/door.ini on 480 x 320 cells whatever
 *                  --nx and --ny (the video of doc/rendering.md: a room
 *                  with a wall, a door and open sides, a heap in the room
 *                  and a source pouring on it), stepped by RKL2 super-steps
 *                  of 32 stages as a pouring run is: what an evaluation
 *                  costs on a room-sized grid
 *
 * A case is one surface, closure and thread count: one warm-up step, then
 * `repeats` timings of `steps` steps each (cell-updates/s = nx ny steps /
 * wall time, counting every cell of the grid, swept or skipped; for the
 * room a step is a super-step, and the rate counts its 33 evaluations).  Bytes
 * per cell are those the sweep's design moves (heights read and written,
 * the ring rows, the type byte on tiles that need it); the roofline is the
 * probe's bandwidth over them.
 *
 * On a GPU (--device cuda[:N], a build with CUDA; doc/gpu.md) a case is
 * the device's forward-Euler loop (src/cuda/cuda.h): every cell every
 * step, 26 B per cell-update, against a device-to-device copy's bandwidth;
 * the thread counts do not apply, and the room (RKL2) and materials are
 * not on the device yet.
 */
#ifndef SANDSLIDE_BENCH_H
#define SANDSLIDE_BENCH_H

#include <stddef.h>

#include "sandslide/closure.h"
#include "sandslide/device.h"
#include "sandslide/option.h"

#define SS_BENCH_MAX_CASES 8

enum ss_bench_surface {
	SS_BENCH_SUPERCRITICAL,
	SS_BENCH_SUBCRITICAL,
	SS_BENCH_PATCH,
	SS_BENCH_ROOM,          /* RKL2 stages in a room with a door (below) */
	SS_BENCH_SURFACES
};

struct ss_bench_closure {
	enum ss_closure_kind kind;
	double gamma;
	char label[32];          /* "herschel-bulkley(0.5)" */
};

/* What the benchmark measured before its cases: the set-up and the
 * memory bandwidth per thread count. */
struct ss_bench_header {
	int nx, ny, tile_nx, tile_ny;      /* cells; tile size used */
	int repeats;
	const char *rsqrt;                 /* ss_face_rsqrt_method() */
	size_t probe_doubles;              /* size of the bandwidth probe's array */
	int thread_count;
	const int *threads;                /* thread_count entries */
	const double *bandwidth;           /* bytes/s, read+write, per entry */
	int angles;                        /* repose angles (materials) */
	const char *device;                /* NULL: the CPU; else the GPU,
	                                    * "cuda:0: NVIDIA H200, ..." (its
	                                    * bandwidth: a device-to-device
	                                    * copy, the one entry of bandwidth) */
	const char *note;                  /* NULL, or what was left out */
};

/* One case: a surface, closure and thread count. */
struct ss_bench_result {
	enum ss_bench_surface surface;
	const char *closure;               /* its label */
	int threads;                       /* 0 on a GPU */
	double median, min, max;           /* cell-updates/s over the repeats */
	long long steps;                   /* timed steps per repeat */
	double active_fraction;            /* tiles swept / tiles */
	double bytes_per_cell;             /* what the sweep's design moves */
	double roofline;                   /* bandwidth / bytes_per_cell */
};

/* Set ss_bench_options_init's defaults; the callbacks are the caller's. */
struct ss_bench_options {
	int nx, ny;                                        /* cells */
	struct ss_bench_closure closures[SS_BENCH_MAX_CASES];
	int closure_count;
	int threads[SS_BENCH_MAX_CASES];
	int thread_count;
	int surfaces[SS_BENCH_SURFACES];                   /* 1: run it */
	int repeats;                                       /* timings per case */
	int steps;                                         /* per timing; 0: auto */
	int tile[2];                                       /* cells per tile, nx
	                                                    * and ny; < 1: defaults */
	int angles;                                        /* repose angles over
	                                                    * the grid (materials,
	                                                    * doc/model.md); 1: one */
	struct ss_device device;                           /* the CPU, or a GPU:
	                                                    * forward Euler on the
	                                                    * device (doc/gpu.md) */
	/* the figures, as they come (the caller prints them) */
	void (*on_header)(void *context, const struct ss_bench_header *h);
	void (*on_result)(void *context, const struct ss_bench_result *r);
	void *context;
};

/* The surface names "supercritical", "subcritical", "patch", "room". */
const char *ss_bench_surface_name(enum ss_bench_surface s);

/* bench's options (option.h): the command line's parser and help read them. */
extern const struct ss_option_table ss_bench_option_table;

/* Every option at the table's default (8192^2 cells, every closure and
 * surface, 1 and 2 threads, 5 repeats). */
void ss_bench_options_init(struct ss_bench_options *o);

/* Run the benchmark.  SS_ERR_INPUT for a bad option (a grid too small for
 * the patch, too little memory), SS_ERR_FAIL otherwise. */
int ss_bench_run(const struct ss_bench_options *o);

#endif
