/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * main.c - the `sandslide` command line (doc/sandslide.1.in): parse the
 * arguments (each command's options are the library's table, option.h,
 * and a few of the command line's own, which also give its --help:
 * options.h), dispatch to the library, print what it returns (print.h) and
 * turn its status into the exit code (0 success, 1 failure while running,
 * 2 bad usage or bad input).
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/strings.h"
#include "cli/options.h"
#include "cli/print.h"
#include "sandslide/bench.h"
#include "sandslide/device.h"
#include "sandslide/dem.h"
#include "sandslide/comm.h"
#include "sandslide/cpu.h"
#include "sandslide/error.h"
#include "sandslide/fit.h"
#include "sandslide/parallel.h"
#include "sandslide/relax.h"
#include "sandslide/render.h"
#include "sandslide/run.h"
#include "sandslide/snapshot.h"
#include "sandslide/version.h"

#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const char usage_main[] =
	"usage: sandslide <command> [options]\n"
	"\n"
	"Sand slides on raster grids: the degenerate parabolic sliding model\n"
	"dh/dt = nu div[f_sl(|grad h|) grad h / |grad h|] + q.\n"
	"\n"
	"commands:\n"
	"  run CASE.ini     run a case, writing HDF5 snapshots\n"
	"  info FILE.h5     summarise an output file\n"
	"  relax DEM        relax a DEM to the repose angle (terrain in, terrain out)\n"
	"  render FILE.h5   draw snapshots as PNG frames (and a video)\n"
	"  bench            measure the sweep's throughput on synthetic surfaces\n"
	"  fit CASE.ini OBS find the closure and parameters that reproduce observations\n"
	"\n"
	"  sandslide --version    print the version\n"
	"  sandslide CMD --help   options of a command (also: sandslide help CMD)\n";

/* The signal that asked a run to stop (SIGINT or SIGTERM), 0 while none
 * did: the run finishes its substep, writes a snapshot and returns, and the
 * exit status is 128 + the signal.  A second signal kills at once
 * (SA_RESETHAND). */
static volatile sig_atomic_t stop_signal;

static void on_stop_signal(int sig)
{
	stop_signal = sig;
}

/* What the long commands (run, relax) share: the stop signals caught and,
 * on a terminal unless quiet, a progress line (the callback to give). */
static ss_progress_fn *watch(int quiet, const volatile sig_atomic_t **stop)
{
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = on_stop_signal;
	sa.sa_flags = SA_RESETHAND;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	/* past a file-size limit, write() must fail with EFBIG (and the run
	 * report it) rather than the process die silently */
	signal(SIGXFSZ, SIG_IGN);
	*stop = &stop_signal;
	return !quiet && ss_comm_rank() == 0 && isatty(fileno(stderr)) ? cli_print_progress
	                                                               : NULL;
}

/* The exit status of a command that a signal may have stopped. */
static int exit_status(int status)
{
	const int code = ss_status_exit_code(status);
	return code == 0 && stop_signal ? 128 + stop_signal : code;
}

/* ---- run ------------------------------------------------------------------ */

/* What the command line adds to run's options (run.h): printing and frames. */
struct run_cli {
	int quiet;
	const char *frames_dir;
};

#define RUN_CLI(m) offsetof(struct run_cli, m)
static const struct ss_option run_cli_options[] = {
	{.name = "quiet", .alias = "-q", .kind = SS_OPTION_FLAG, .offset = RUN_CLI(quiet),
	 .help = "no progress line and no summary"},
	{.name = "frames", .value_name = "DIR", .kind = SS_OPTION_TEXT,
	 .offset = RUN_CLI(frames_dir), .expected = "a folder",
	 .help = "also draw each snapshot as it is written, to\n"
	         "DIR/frame_00000.png, ... (shaded; the look options\n"
	         "of `sandslide render --help` apply, e.g. --label)"},
};
static const struct ss_option_table run_cli_table = {
	.command = "run", .options = run_cli_options,
	.count = sizeof run_cli_options / sizeof *run_cli_options,
};

/* `run --frames`: render each snapshot the run reports. */
static int render_run_snapshot(void *context, const struct ss_run_snapshot *s)
{
	const struct ss_render_frames_bounds b = {s->source_rise, s->open_level,
	                                          s->any_open_side};
	return ss_render_frames_add(context, s->path, s->index, &b);
}

/* The run as the command line gave it, with the frames to draw, if any. */
static int run_with_frames(struct ss_run_options *o, const struct run_cli *cli,
                           const struct ss_render_options *look, const char *history)
{
	struct ss_render_frames *frames = NULL;
	struct ss_run_summary s;
	int err = cli->frames_dir ? ss_render_frames_create(&frames, cli->frames_dir, look)
	                          : SS_OK;
	if (!err) {
		o->job.history = history;
		o->on_snapshot = frames ? render_run_snapshot : NULL;
		o->snapshot_context = frames;
		o->on_plan = cli->quiet ? NULL : cli_print_run_plan;
		o->job.progress = watch(cli->quiet, &o->job.stop_signal);
		err = ss_run_case(o, &s);
		cli_progress_done();
	}
	if (!err)
		cli_print_run_end(&s, cli->quiet);
	if (!err && frames && !cli->quiet)
		printf("wrote %lld frames to %s%s\n", ss_render_frames_count(frames), cli->frames_dir,
		       cli->frames_dir[strlen(cli->frames_dir) - 1] == '/' ? "" : "/");
	ss_render_frames_destroy(frames);
	return err;
}

static int cmd_run(int argc, char **argv)
{
	struct ss_run_options o;
	struct run_cli cli = {0, NULL};
	struct ss_render_options look;
	ss_run_options_init(&o);
	ss_render_options_default(&look);
	struct cli_command cmd = {
		.usage = "usage: sandslide run CASE.ini [-o OUT.h5] [--threads N] "
		         "[--set SECTION.KEY=VALUE ...]\n"
		         "       sandslide run --restart OUT.h5 [CASE.ini] [--threads N]\n",
		.groups = {{&ss_run_option_table, &o, 0}, {&run_cli_table, &cli, 0},
		           {&ss_render_look_option_table, &look, 1}},
		.outro = "Writes OUT.h5 (doc/output.md) and the XDMF sidecar OUT.xmf, flushed after\n"
		         "every snapshot.  Ctrl-C (SIGINT) or SIGTERM finish the substep, write a\n"
		         "snapshot and exit 130 or 143 naming the command that continues the run.\n"
		         "Another run writing the same output is refused, --force or not.\n"
		         "Exit status: 0 done, 1 failure while running, 2 bad input.\n",
		.what = "case file", .args = &o.case_path, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	char *history = NULL;
	if (status == CLI_GO_ON && !o.case_path && !o.restart)
		status = cli_usage_error(&cmd, "run needs a case file (or --restart OUT.h5)");
	const char *look_given = cli_given_in(&cmd, &ss_render_look_option_table);
	if (status == CLI_GO_ON && look_given && !cli.frames_dir)
		status = cli_usage_error(&cmd, "%s sets the look of frames: it needs --frames DIR",
		                         look_given);
	if (status == CLI_GO_ON && !(history = ss_strings_join((const char *const *)argv, argc,
	                                                       " ", 0)))
		status = 1;
	if (status == CLI_GO_ON)
		status = exit_status(run_with_frames(&o, &cli, &look, history));
	free(history);
	ss_option_release(&ss_run_option_table, &o);
	return status;
}

/* ---- relax ---------------------------------------------------------------- */

/* What the command line adds to relax's options (relax.h). */
struct relax_cli {
	int quiet;
};

static const struct ss_option relax_cli_options[] = {
	{.name = "quiet", .alias = "-q", .kind = SS_OPTION_FLAG,
	 .offset = offsetof(struct relax_cli, quiet), .help = "no progress line and no summary"},
};
static const struct ss_option_table relax_cli_table = {
	.command = "relax", .options = relax_cli_options, .count = 1,
};

static int cmd_relax(int argc, char **argv)
{
	struct ss_relax_options o;
	struct relax_cli cli = {0};
	ss_relax_options_init(&o);
	struct cli_command cmd = {
		.usage = "usage: sandslide relax DEM [-o OUT] [--angle DEG] [--closure NAME] "
		         "[--nu V]\n"
		         "                       [--tol X] [--max-time T] [--threads N] [...]\n",
		.intro = "Relaxes a digital elevation model to the repose angle: every slope steeper\n"
		         "than it slides until the surface is steady, the volume conserved.\n"
		         "\n"
		         "  DEM                   .asc (ESRI ASCII grid), .png (16-bit greyscale),\n"
		         "                        FILE.h5[:/dataset] (sandslide HDF5, last snapshot),\n"
		         "                        .tif and other GDAL rasters (builds with GDAL)\n",
		.groups = {{&ss_relax_option_table, &o, 0}, {&relax_cli_table, &cli, 0}},
		.outro = "Prints cells and volume moved, steepest face before and after, steps and\n"
		         "wall time.  The input is never modified; the output is written under a\n"
		         "temporary name and renamed when complete, and another run writing it is\n"
		         "refused.  Ctrl-C (SIGINT) or SIGTERM finish the substep and write the\n"
		         "surface as it is then (exit 130 or 143).  Exit status: 0 done, 1\n"
		         "failure while running, 2 bad input.\n",
		.what = "DEM", .args = &o.dem, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	if (status == CLI_GO_ON && !o.dem)
		status = cli_usage_error(&cmd, "relax needs a DEM");
	if (status != CLI_GO_ON)
		return status;
	struct ss_relax_report report;
	char *history = ss_strings_join((const char *const *)argv, argc, " ", 0);
	if (!history)
		return 1;
	o.job.history = history;
	o.job.progress = watch(cli.quiet, &o.job.stop_signal);
	const int err = ss_relax_run(&o, &report);
	cli_progress_done();
	if (!err)
		cli_print_relax_end(&report, cli.quiet);
	free(history);
	return exit_status(err);
}

/* ---- render --------------------------------------------------------------- */

/* What the command line adds to render's options (render.h). */
struct render_cli {
	int quiet, bench, bench_n, no_label, no_colorbar;
};

#define RENDER_CLI(m) offsetof(struct render_cli, m)
static const struct ss_option render_cli_options[] = {
	{.name = "no-label", .kind = SS_OPTION_FLAG, .offset = RENDER_CLI(no_label),
	 .help = "no time label on a video's frames (--video draws one)"},
	{.name = "no-colorbar", .kind = SS_OPTION_FLAG, .offset = RENDER_CLI(no_colorbar),
	 .help = "no colour bar on a video's frames (--video adds one)"},
	{.name = "quiet", .alias = "-q", .kind = SS_OPTION_FLAG, .offset = RENDER_CLI(quiet),
	 .help = "no summary"},
	{.name = "bench", .value_name = "[N]", .kind = SS_OPTION_OPTIONAL_INT,
	 .offset = RENDER_CLI(bench), .value_offset = RENDER_CLI(bench_n), .lo = 16, .hi = 32768,
	 .help = "time the shaded style on an N x N grid (default 4096)"},
};
static const struct ss_option_table render_cli_table = {
	.command = "render", .options = render_cli_options,
	.count = sizeof render_cli_options / sizeof *render_cli_options,
};

static int cmd_render(int argc, char **argv)
{
	struct ss_render_series_options o;
	struct render_cli cli = {.bench_n = 4096};
	ss_render_series_options_init(&o);
	o.time = NAN;
	struct cli_command cmd = {
		.usage = "usage: sandslide render FILE.h5 [-o DIR] [--frames A:B:STEP | --time T] "
		         "[options]\n"
		         "       sandslide render FILE.h5 --html FILE.html [options]\n"
		         "       sandslide render --bench [N]\n",
		.intro = "Draws the snapshots of a sandslide output file as PNG pictures,\n"
		         "DIR/frame_00000.png, frame_00001.png, ... in time order (doc/rendering.md),\n"
		         "or into one HTML page that shows them (--html).\n",
		.groups = {{&ss_render_option_table, &o, 0}, {&render_cli_table, &cli, 0}},
		.outro = "Each PNG holds the time, the height scale and the snapshot in text chunks;\n"
		         "a frame is written under a temporary name and renamed when complete.\n"
		         "Exit status: 0 done, 1 failure while rendering, 2 bad input.\n",
		.what = "file", .args = &o.input, .max_args = 1,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	ss_parallel_set_threads(o.job.threads > 0 ? o.job.threads : ss_parallel_default_threads(1));
	if (cli.bench) {
		struct ss_render_bench_report report;
		const int err = ss_render_bench(cli.bench_n, 5, &report);
		if (!err)
			cli_print_render_bench(&report);
		return ss_status_exit_code(err);
	}
	if (!o.input)
		return cli_usage_error(&cmd, "render needs a sandslide output file");
	/* a video is watched without its file: it shows the time and the scale */
	if (o.video && o.look.style != SS_RENDER_GRAY16) {
		o.look.label |= !cli.no_label;
		o.look.colorbar |= !cli.no_colorbar;
	}
	if (cli.no_label)
		o.look.label = 0;
	if (cli.no_colorbar)
		o.look.colorbar = 0;
	/* a viewer or a video needs no frame folder: -o keeps the frames */
	if ((o.html || o.video) && !cli_given(&cmd, "--output"))
		o.output_dir = NULL;
	struct ss_render_series_report report;
	const int err = ss_render_series(&o, &report);
	if (!err)
		cli_print_render_series(&o, &report, cli.quiet);
	return ss_status_exit_code(err);
}

/* ---- bench ---------------------------------------------------------------- */

static const struct ss_option bench_cli_options[] = {
	{.name = "json", .kind = SS_OPTION_FLAG, .offset = offsetof(struct cli_bench, json),
	 .help = "one JSON document instead of a table"},
};
static const struct ss_option_table bench_cli_table = {
	.command = "bench", .options = bench_cli_options, .count = 1,
};

static int cmd_bench(int argc, char **argv)
{
	struct ss_bench_options o;
	struct cli_bench print;
	memset(&print, 0, sizeof print);
	ss_bench_options_init(&o);
	struct cli_command cmd = {
		.usage = "usage: sandslide bench [--nx N] [--ny N] [--closure NAME|all] "
		         "[--threads 1,2]\n"
		         "                       [--surface NAME|all] [--repeats N] [--steps N] "
		         "[--tile NXxNY]\n"
		         "                       [--json]\n",
		.groups = {{&ss_bench_option_table, &o, 0}, {&bench_cli_table, &print, 0}},
		.outro = "Also measures the memory bandwidth (read+write of one array) in the same run\n"
		         "and reports the fraction of that roofline each case reaches.\n",
		.what = "argument", .max_args = 0,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	o.on_header = cli_bench_header;
	o.on_result = cli_bench_result;
	o.context = &print;
	const int err = ss_bench_run(&o);
	if (!err)
		cli_bench_done(&print);
	return ss_status_exit_code(err);
}

/* ---- info ----------------------------------------------------------------- */

static int cmd_info(int argc, char **argv)
{
	const char *path = NULL;
	struct cli_command cmd = {
		.usage = "usage: sandslide info FILE.h5\n",
		.intro = "Prints the grid, model, cell counts and the diagnostics of every snapshot\n"
		         "(first and last ten when there are more than twenty).\n",
		.what = "file", .args = &path, .max_args = 1,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	if (!path)
		return cli_usage_error(&cmd, "info needs a file");
	struct ss_snapshot_summary s;
	const int err = ss_snapshot_read_summary(path, &s);
	if (err)
		return ss_status_exit_code(err);
	cli_print_info(path, &s);
	ss_snapshot_summary_release(&s);
	return 0;
}

/* ---- fit ------------------------------------------------------------------ */

struct fit_cli {
	int quiet;
	int json;
};

static const struct ss_option fit_cli_options[] = {
	{.name = "quiet", .alias = "-q", .kind = SS_OPTION_FLAG,
	 .offset = offsetof(struct fit_cli, quiet), .help = "no progress line and no summary"},
	{.name = "json", .kind = SS_OPTION_FLAG, .offset = offsetof(struct fit_cli, json),
	 .help = "print the report (JSON) instead of the summary"},
};
static const struct ss_option_table fit_cli_table = {
	.command = "fit", .options = fit_cli_options, .count = 2,
};

static int cmd_fit(int argc, char **argv)
{
	struct ss_fit_options o;
	struct fit_cli cli = {0, 0};
	const char *args[2] = {NULL, NULL};
	ss_fit_options_init(&o);
	struct cli_command cmd = {
		.usage = "usage: sandslide fit CASE.ini OBS --param NAME=LO:HI[:log] ... "
		         "[-o FIT.json]\n"
		         "                     [--closures all|LIST] [--cost NAME] [--plot FIT.png]\n",
		.intro = "Finds the closure and parameters with which CASE.ini reproduces the\n"
		         "observations OBS: a series of heights (OBS.h5 in sandslide's layout, or\n"
		         "a CSV time,path of rasters) or the front of the sand (a CSV time,x,y),\n"
		         "with their uncertainty and whether the data identify them\n"
		         "(doc/fit.md).\n",
		.groups = {{&ss_fit_option_table, &o, 0}, {&fit_cli_table, &cli, 0}},
		.outro = "Ctrl-C (SIGINT) or SIGTERM stop the fit; the report of the best so far is\n"
		         "written and the exit status is 130 or 143.\n"
		         "Exit status: 0 done, 1 failure while fitting, 2 bad input.\n",
		.what = "case file or observations", .args = args, .max_args = 2,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	if (status == CLI_GO_ON && !args[1])
		status = cli_usage_error(&cmd, "fit needs a case file and observations");
	if (status == CLI_GO_ON) {
		char *report = NULL, *summary = NULL;
		o.case_path = args[0];
		o.observations = args[1];
		o.job.progress = watch(cli.quiet || cli.json, &o.job.stop_signal);
		const int err = ss_fit_run(&o, &report, &summary);
		cli_progress_done();
		if (!err && cli.json)
			fputs(report, stdout);
		else if (!err && !cli.quiet && summary)
			printf("%s", summary);
		if (!err && !cli.quiet && !cli.json && o.job.output)
			printf("wrote %s%s%s\n", o.job.output, o.plot ? " and " : "",
			       o.plot ? o.plot : "");
		free(report);
		free(summary);
		status = exit_status(err);
	}
	ss_option_release(&ss_fit_option_table, &o);
	return status;
}

/* ---- main ----------------------------------------------------------------- */

static int main_usage_error(const char *fmt, const char *arg)
{
	if (ss_comm_rank() != 0)
		return 2;
	fflush(stdout);
	fputs("sandslide: ", stderr);
	fprintf(stderr, fmt, arg);
	fputs(" (see 'sandslide --help')\n", stderr);
	return 2;
}

/* The command, run by every rank of a distributed run (comm.h); only
 * rank 0 prints (the others' stdout goes nowhere, and their error messages
 * reach rank 0 through ss_comm_agree). */
static int command(int argc, char **argv)
{
	static const struct {
		const char *name;
		int (*run)(int argc, char **argv);
	} commands[] = {
		{"run", cmd_run}, {"info", cmd_info}, {"bench", cmd_bench},
		{"render", cmd_render}, {"relax", cmd_relax}, {"fit", cmd_fit},
	};
	ss_snapshot_library_init();
	if (ss_cpu_init())   /* SANDSLIDE_CPU, on every rank before anything runs */
		return 2;
	if (argc < 2)
		return main_usage_error("%s", "no command given");
	const char *cmd = argv[1];
	if (!strcmp(cmd, "help") && argc > 2) {   /* help CMD: that command's --help */
		/* help --roff CMD: its options as roff, for the man page (Makefile) */
		const int roff = argc > 3 && !strcmp(argv[2], "--roff");
		char *name = argv[2 + roff];
		cli_help_set_roff(roff);
		for (int k = 0; k < COUNT(commands); k++)
			if (!strcmp(name, commands[k].name)) {
				char *args[] = {argv[0], name, "--help", NULL};
				return commands[k].run(3, args);
			}
		return main_usage_error("help: unknown command '%s': expected run, relax, info, "
		                        "render, bench or fit", name);
	}
	if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
		fputs(usage_main, stdout);
		return 0;
	}
	if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) {
		printf("sandslide %s (OpenMP: %s, %d processors, wait policy %s; GDAL: %s; MPI: %s; "
		       "CUDA: %s; kernel: %s)\n",
		       ss_version(),
#ifdef _OPENMP
		       "on",
#else
		       "off",
#endif
		       ss_parallel_processors(), ss_parallel_wait_policy(),
		       ss_dem_gdal_available() ? "on" : "off",
		       ss_comm_library() ? ss_comm_library() : "off",
		       ss_device_cuda_built() ? "on" : "off", ss_cpu_path_name(ss_cpu_path()));
		/* the devices --device may name, each on a line of its own */
		char devices[2048];
		ss_device_list(devices, sizeof devices);
		printf("devices (--device):\n");
		for (const char *line = devices; *line;) {
			const size_t n = strcspn(line, "\n");
			printf("  %.*s\n", (int)n, line);
			line += n + (line[n] == '\n');
		}
		return 0;
	}
	/* the distributed commands: the others work on one block */
	if (ss_comm_size() > 1 && strcmp(cmd, "run") != 0 && strcmp(cmd, "relax") != 0)
		return main_usage_error("'%s' runs on one rank: only run and relax are distributed "
		                        "(start it without mpirun)", cmd);
	for (int k = 0; k < COUNT(commands); k++)
		if (!strcmp(cmd, commands[k].name))
			return commands[k].run(argc, argv);
	return main_usage_error("unknown command '%s': expected run, relax, info, render, bench or fit",
	                        cmd);
}

/*
 * OpenMP's idle threads sleep unless the user said otherwise: spinning
 * ones (libgomp's default spins about 3 ms at every barrier) lose their
 * core to any other process, and every barrier then waits for them
 * (doc/running.md#threads measures it).  libgomp reads OMP_WAIT_POLICY
 * and GOMP_SPINCOUNT once, in its constructor, and a setenv before that
 * is undone: the C library's own constructor puts back the environment
 * the process started with.  So when neither variable is set, this
 * program starts itself again with OMP_WAIT_POLICY=passive added, from
 * the executable's .preinit_array: before any library's constructor, so
 * the first start costs the loading only, not the initialisation of HDF5
 * and GDAL (0.08 s more for `sandslide version` on a loaded 2-core
 * machine: 0.23 s against 0.15 s with the variable set).  Should the exec fail (no /proc), the
 * run goes on with the runtime's default, which `sandslide version`
 * then names.
 */
#if defined(_OPENMP) && defined(__linux__) && defined(__GNUC__)
static void passive_wait_by_default(int argc, char **argv, char **envp)
{
	char *env[4096];
	size_t n = 0;
	(void)argc;
	for (; envp[n]; n++)
		if (!strncmp(envp[n], "OMP_WAIT_POLICY=", 16) ||
		    !strncmp(envp[n], "GOMP_SPINCOUNT=", 15) || n + 2 >= sizeof env / sizeof *env)
			return;
	memcpy(env, envp, n * sizeof *env);
	env[n] = (char *)"OMP_WAIT_POLICY=passive";
	env[n + 1] = NULL;
	execve("/proc/self/exe", argv, env);
}

__attribute__((section(".preinit_array"), used))
static void (*const preinit_passive_wait)(int, char **, char **) = passive_wait_by_default;
#endif

int main(int argc, char **argv)
{
	ss_comm_init(&argc, &argv);
	if (ss_comm_rank() != 0 && !freopen("/dev/null", "w", stdout))
		ss_comm_abort(1);
	const int code = command(argc, argv);
	ss_comm_finalize();
	return code;
}
