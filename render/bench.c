/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * bench.c - `sandslide render --bench N`: throughput of the shaded style.
 *
 * A synthetic N x N snapshot in memory (a cone with ripples, wall blocks,
 * an open strip) is resampled 1:1 and coloured `repeats` times on the
 * current threads; the median, min and max time give Mpixel/s.  The PNG
 * encoding of the same picture is timed separately (once per zlib level
 * shown), since it is serial and its cost depends on the level.  Nothing
 * here is a test: timings vary with the machine and its load.
 */
#include "internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sandslide/error.h"
#include "sandslide/grid.h"
#include "sandslide/parallel.h"

static int cmp_double(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

static void synthetic(int n, double *h, uint8_t *type)
{
	#pragma omp parallel for schedule(static)
	for (int j = 0; j < n; j++)
		for (int i = 0; i < n; i++) {
			const double x = (i + 0.5) / n - 0.5, y = (j + 0.5) / n - 0.5;
			const double r = sqrt(x * x + y * y);
			const size_t k = (size_t)j * n + i;
			h[k] = fmax(0.0, 0.35 - 0.7 * r) + 0.01 * sin(40.0 * x) * cos(30.0 * y);
			type[k] = SS_CELL_FLOW;
			if (fabs(x - 0.25) < 0.04 && fabs(y) < 0.2)
				type[k] = SS_CELL_WALL;
			if (i < n / 64)
				type[k] = SS_CELL_OPEN;
		}
}

/* The PNG encoding of img, once per level of report->png_levels, timed. */
static int time_png(const struct ss_render_image *img, struct ss_render_bench_report *report)
{
	char path[4200];
	const char *dir = getenv("TMPDIR");
	snprintf(path, sizeof path, "%s/sandslide-bench-%ld.png", dir && *dir ? dir : "/tmp",
	         (long)getpid());
	int err = SS_OK;
	for (int l = 0; l < 2 && !err; l++) {
		const double t0 = ss_parallel_wall_seconds();
		err = ss_render_write_png(img, path, report->png_levels[l]);
		report->png[l] = ss_parallel_wall_seconds() - t0;
		struct stat st;
		report->png_bytes[l] = !err && stat(path, &st) == 0 ? (double)st.st_size : 0.0;
		remove(path);
	}
	return err;
}

int ss_render_bench(int n, int repeats, struct ss_render_bench_report *report)
{
	if (n < 16 || n > 32768 || repeats < 1 || repeats > 100)
		return ss_error_input("--bench %d: expected a grid of 16 to 32768 cells a side "
		                      "(and 1 to 100 repeats)", n);
	*report = (struct ss_render_bench_report){.n = n, .repeats = repeats,
	                                          .threads = ss_parallel_max_threads(),
	                                          .png_levels = {1, 6}};
	const size_t cells = (size_t)n * n;
	double *h = ss_alloc(cells, sizeof *h, "bench heights");
	uint8_t *type = ss_alloc(cells, 1, "bench cell types");
	double *times = ss_alloc((size_t)repeats, sizeof *times, "bench timings");
	if (!h || !type || !times) {
		ss_free(h);
		ss_free(type);
		ss_free(times);
		return SS_ERR_FAIL;
	}
	synthetic(n, h, type);
	struct ss_render_options o;
	ss_render_options_default(&o);
	o.scale = 1;   /* one pixel per cell, as the frames below are fed (the
	                  default enlarges grids under 512 cells a side) */
	const struct ss_render_field f = {n, n, 1e-3, 1e-3, n, h, type, 0.0, 0};

	/* As in a series: the plan (scale, pixel types) once, then per frame
	 * the colouring of the heights, one pixel per cell, into a new picture.
	 * One untimed frame first (first touch of the pages; the picture to
	 * encode below). */
	struct ss_render_plan plan;
	struct ss_render_image img = {0};
	const double *north = h + (size_t)(n - 1) * n;
	int err = ss_render_plan_init(&plan, &o, n, n, f.dx, f.dy, type, n, 0, 0.0, 0.35, 1);
	if (err)
		goto out_free;
	err = ss_render_plan_draw(&plan, north, -(ptrdiff_t)n, NULL, NULL, 0.0, &img, 1);
	for (int r = 0; r < repeats && !err; r++) {
		struct ss_render_image again;
		const double t0 = ss_parallel_wall_seconds();
		err = ss_render_plan_draw(&plan, north, -(ptrdiff_t)n, NULL, NULL, 0.0, &again, 1);
		times[r] = ss_parallel_wall_seconds() - t0;
		if (!err)
			ss_render_image_release(&again);
	}
	ss_render_plan_release(&plan);
	if (!err) {
		qsort(times, (size_t)repeats, sizeof *times, cmp_double);
		report->median = times[repeats / 2];
		report->min = times[0];
		report->max = times[repeats - 1];
		/* the whole of ss_render_field: plan, range and colouring each time */
		struct ss_render_image once;
		const double started = ss_parallel_wall_seconds();
		if (!(err = ss_render_field(&f, &o, &once))) {
			report->field = ss_parallel_wall_seconds() - started;
			ss_render_image_release(&once);
		}
	}
	if (!err)
		err = time_png(&img, report);
	ss_render_image_release(&img);
out_free:
	ss_free(times);
	ss_free(type);
	ss_free(h);
	return err;
}
