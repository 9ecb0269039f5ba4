/*
 * main.c - the `sandslide` command line (SPEC section 3): parse the
 * arguments (each command's options are a table, options.h, which also
 * gives its --help), dispatch to the library, print what it returns
 * (print.h) and turn its status into the exit code (0 success, 1 failure
 * while running, 2 bad usage or bad input).
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
#include "sandslide/dem.h"
#include "sandslide/comm.h"
#include "sandslide/cpu.h"
#include "sandslide/error.h"
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

/* Option table entries that several commands share. */
#define THREADS(at)                                                                  \
	{.name = "--threads", .value = "N", .kind = CLI_INT, .offset = at, .lo = 1,  \
	 .hi = 4096, .expected = "an integer from 1 to 4096",                        \
	 .help = "OpenMP threads (default: OMP_NUM_THREADS, else\n"                 \
	         "the processors this process may run on)"}
#define QUIET(at, h) {.name = "--quiet", .alias = "-q", .kind = CLI_FLAG, .offset = at, .help = h}
#define FORCE(at, h) {.name = "--force", .kind = CLI_FLAG, .offset = at, .help = h}
#define TILE(at, h)                                                                  \
	{.name = "--tile", .value = "NXxNY", .kind = CLI_PARSE, .offset = at,        \
	 .parse = cli_parse_tile, .expected = "NXxNY, e.g. 256x64", .help = h}

/* ---- the look of frames: `render` and `run --frames` ------------------- */

static int parse_style(const char *word, void *target)
{
	return ss_render_style_parse(word, target);
}

static int parse_cmap(const char *word, void *target)
{
	return ss_render_cmap_parse(word, target);
}

#define LOOK(m) offsetof(struct ss_render_options, m)
/* Any finite number: ss_render_options_check says what a look accepts. */
#define NUMBER(n, v, m, h)                                                         \
	{.name = n, .value = v, .kind = CLI_REAL, .offset = LOOK(m), .lo = -INFINITY, \
	 .hi = INFINITY, .expected = "a finite number", .help = h}

static const struct cli_option look_options[] = {
	{.help = "The look of the frames (also for `sandslide run --frames`):\n"},
	{.name = "--style", .value = "NAME", .kind = CLI_PARSE, .offset = LOOK(style),
	 .parse = parse_style, .expected = SS_RENDER_STYLE_NAMES,
	 .help = "shaded (default): colour map x hillshade, 8-bit RGB;\n"
	         "gray16: 16-bit grey heights, zmin..zmax in the PNG text;\n"
	         "oblique: perspective view, walls as raised blocks"},
	{.name = "--cmap", .value = "NAME", .kind = CLI_PARSE, .offset = LOOK(cmap),
	 .parse = parse_cmap, .expected = SS_RENDER_CMAP_NAMES,
	 .help = "dune (default; perceptually uniform), terrain, gray"},
	NUMBER("--zmin", "Z", zmin, "bottom of the height scale, m (default: the lowest\n"
	                            "sand of the whole file, so all frames share it)"),
	NUMBER("--zmax", "Z", zmax, "top of the height scale, m (default: the highest sand)"),
	NUMBER("--azimuth", "DEG", azimuth_deg,
	       "light from this compass bearing (default 315: north-west)"),
	NUMBER("--altitude", "DEG", altitude_deg, "light above the horizon (default 45)"),
	NUMBER("--zscale", "S", zscale, "vertical exaggeration of shading and of the oblique\n"
	                                "view (default 1)"),
	NUMBER("--contour", "DZ", contour, "contour lines every DZ m (shaded)"),
	{.name = "--label", .kind = CLI_FLAG, .offset = LOOK(label),
	 .help = "the simulated time in a strip above each frame"},
	{.name = "--colorbar", .kind = CLI_FLAG, .offset = LOOK(colorbar),
	 .help = "add a colour bar with the height scale"},
	{.name = "--max-size", .value = "PX", .kind = CLI_INT, .offset = LOOK(max_size),
	 .lo = 8, .hi = 65536, .expected = "8 to 65536 px",
	 .help = "at most PX pixels a side (cells are area-averaged)"},
	{.name = "--scale", .value = "K", .kind = CLI_INT, .offset = LOOK(scale), .lo = 1,
	 .hi = 100, .expected = "1 to 100 px per cell",
	 .help = "K pixels per cell (default 1 for gray16, otherwise\n"
	         "enough for a side of 512 px)"},
	NUMBER("--view-azimuth", "DEG", view_azimuth_deg,
	       "oblique: the camera's bearing from the centre (default:\n"
	       "from the open side, away from the walls)"),
	NUMBER("--view-elevation", "DEG", view_elevation_deg,
	       "oblique: the camera above the horizon (55)"),
	{.name = "--compression", .value = "N", .kind = CLI_INT, .offset = LOOK(compression),
	 .lo = 0, .hi = 9, .expected = "0 to 9",
	 .help = "zlib level of the PNGs, 0 to 9 (default 6)"},
};

/* ---- run ------------------------------------------------------------------ */

struct run_args {
	struct ss_run_options o;
	struct cli_list sets;
	const char *frames_dir;
	int quiet, tile[2];
	struct ss_render_options look;
};

#define RUN(m) offsetof(struct run_args, m)
static const struct cli_option run_options[] = {
	{.name = "--output", .alias = "-o", .value = "OUT.h5", .kind = CLI_TEXT,
	 .offset = RUN(o.output),
	 .help = "output file (default out/<case name>.h5; its folder\n"
	         "must exist unless it is the default out/)"},
	FORCE(RUN(o.force), "replace OUT.h5 if it exists (else refused)"),
	{.name = "--restart", .value = "OUT.h5", .kind = CLI_TEXT, .offset = RUN(o.restart),
	 .help = "continue the run in OUT.h5 from its last snapshot,\n"
	         "appending to it, with the case stored in it (a\n"
	         "CASE.ini given too must be that case, and its\n"
	         "files are found beside it); the snapshots are\n"
	         "those of a run never interrupted"},
	THREADS(RUN(o.threads)),
	{.name = "--set", .alias = "-P", .value = "SECTION.KEY=VALUE", .kind = CLI_LIST,
	 .offset = RUN(sets),
	 .help = "override key KEY of section SECTION of the case, e.g.\n"
	         "--set model.closure=casson, --set 'source pour.rate=0.002'"},
	TILE(RUN(tile), "cells per tile of the sweep (default 256x128, smaller\n"
	                "on small grids); results are the same bits for any\n"
	                "tile size and thread count"),
	{.name = "--reference-kernel", .kind = CLI_FLAG, .offset = RUN(o.reference_kernel),
	 .help = "use the plain two-pass sweep the fast one is tested\n"
	         "against (same bits, several times slower)"},
	{.name = "--deflate", .value = "N", .kind = CLI_INT, .offset = RUN(o.deflate), .lo = 0,
	 .hi = 9, .expected = "0 to 9", .help = "HDF5 deflate level of /height, 0 (off, default) to 9"},
	QUIET(RUN(quiet), "no progress line and no summary"),
	{.name = "--frames", .value = "DIR", .kind = CLI_TEXT, .offset = RUN(frames_dir),
	 .help = "also draw each snapshot as it is written, to\n"
	         "DIR/frame_00000.png, ... (shaded; the look options\n"
	         "of `sandslide render --help` apply, e.g. --label)"},
};

/* `run --frames`: render each snapshot the run reports. */
static int render_run_snapshot(void *context, const struct ss_run_snapshot *s)
{
	const struct ss_render_frames_bounds b = {s->source_rise, s->open_level,
	                                          s->any_open_side};
	return ss_render_frames_add(context, s->path, s->index, &b);
}

/* The run as the command line gave it, with the frames to draw, if any. */
static int run_with_frames(struct run_args *a, const char *history)
{
	struct ss_render_frames *frames = NULL;
	struct ss_run_summary s;
	int err = a->frames_dir ? ss_render_frames_create(&frames, a->frames_dir, &a->look)
	                        : SS_OK;
	if (!err) {
		a->o.overrides = a->sets.v;
		a->o.override_count = a->sets.n;
		a->o.tile_nx = a->tile[0];
		a->o.tile_ny = a->tile[1];
		a->o.history = history;
		a->o.on_snapshot = frames ? render_run_snapshot : NULL;
		a->o.snapshot_context = frames;
		a->o.progress = watch(a->quiet, &a->o.stop_signal);
		err = ss_run_case(&a->o, &s);
		cli_progress_done();
	}
	if (!err)
		cli_print_run_end(&s, a->quiet);
	if (!err && frames && !a->quiet)
		printf("wrote %lld frames to %s%s\n", ss_render_frames_count(frames), a->frames_dir,
		       a->frames_dir[strlen(a->frames_dir) - 1] == '/' ? "" : "/");
	ss_render_frames_destroy(frames);
	return err;
}

static int cmd_run(int argc, char **argv)
{
	struct run_args a = {.sets = {calloc((size_t)argc, sizeof(char *)), 0}};
	if (!a.sets.v)
		return ss_status_exit_code(ss_error_fail("out of memory"));
	ss_render_options_default(&a.look);
	struct cli_command cmd = {
		.usage = "usage: sandslide run CASE.ini [-o OUT.h5] [--threads N] "
		         "[--set SECTION.KEY=VALUE ...]\n"
		         "       sandslide run --restart OUT.h5 [CASE.ini] [--threads N]\n",
		.groups = {{run_options, COUNT(run_options), &a, 0},
		           {look_options, COUNT(look_options), &a.look, 1}},
		.outro = "Writes OUT.h5 (SPEC section 5) and the XDMF sidecar OUT.xmf, flushed after\n"
		         "every snapshot.  Ctrl-C (SIGINT) or SIGTERM finish the substep, write a\n"
		         "snapshot and exit 130 or 143 naming the command that continues the run.\n"
		         "Another run writing the same output is refused, --force or not.\n"
		         "Exit status: 0 done, 1 failure while running, 2 bad input.\n",
		.what = "case file", .args = &a.o.case_path, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	char *history = NULL;
	if (status == CLI_GO_ON && !a.o.case_path && !a.o.restart)
		status = cli_usage_error(&cmd, "run needs a case file (or --restart OUT.h5)");
	if (status == CLI_GO_ON && cli_given_in(&cmd, 1) && !a.frames_dir)
		status = cli_usage_error(&cmd, "%s sets the look of frames: it needs --frames DIR",
		                         cli_given_in(&cmd, 1));
	if (status == CLI_GO_ON && !(history = ss_strings_join((const char *const *)argv, argc,
	                                                       " ", 0)))
		status = 1;
	if (status == CLI_GO_ON)
		status = exit_status(run_with_frames(&a, history));
	free(history);
	free(a.sets.v);
	return status;
}

/* ---- relax ---------------------------------------------------------------- */

static int parse_closure(const char *word, void *target)
{
	return ss_closure_parse(word, target);
}

static int parse_integrator(const char *word, void *target)
{
	return ss_integrator_parse(word, target);
}

static int parse_sides(const char *word, void *target)
{
	return ss_relax_sides_parse(word, target);
}

static int parse_nodata(const char *word, void *target)
{
	return ss_relax_nodata_parse(word, target);
}

/* rect=X0,Y0,X1,Y1 or disk=X,Y,R into a shape; -1 if malformed. */
static int parse_sand_shape(const char *s, void *target)
{
	struct ss_shape *shape = target;
	const int rect = !strncmp(s, "rect=", 5), disk = !strncmp(s, "disk=", 5);
	if (!rect && !disk)
		return -1;
	const int n = rect ? 4 : 3;
	const char *p = s + 5;
	for (int k = 0; k < n; k++) {
		char *end;
		errno = 0;
		shape->v[k] = strtod(p, &end);
		if (end == p || errno || !isfinite(shape->v[k]) || *end != (k + 1 < n ? ',' : '\0'))
			return -1;
		p = end + 1;
	}
	if (rect && !(shape->v[0] < shape->v[2] && shape->v[1] < shape->v[3]))
		return -1;
	if (disk && !(shape->v[2] > 0.0))
		return -1;
	shape->kind = rect ? SS_SHAPE_RECT : SS_SHAPE_DISK;
	snprintf(shape->where, sizeof shape->where, "--add-sand");
	return 0;
}

struct relax_args {
	struct ss_relax_options o;
	int quiet;
};

#define RELAX(m) offsetof(struct relax_args, m)
/* A number in [lo, hi] for relax's table. */
#define RANGE(n, v, m, l, u, e, h)                                                   \
	{.name = n, .value = v, .kind = CLI_REAL, .offset = RELAX(m), .lo = l, .hi = u, \
	 .expected = e, .help = h}
#define POSITIVE(n, v, m, e, h) RANGE(n, v, m, 1e-300, 1e300, e, h)

static const struct cli_option relax_options[] = {
	{.name = "--output", .alias = "-o", .value = "OUT", .kind = CLI_TEXT,
	 .offset = RELAX(o.output),
	 .help = ".asc, .png, .tif: the relaxed raster; .h5: the whole\n"
	         "series with diagnostics (default out/<DEM>-relaxed\n"
	         "with the input's extension)"},
	RANGE("--angle", "DEG", o.angle_deg, 1e-9, 90.0 - 1e-9, "degrees in (0, 90)",
	      "repose angle (default 35)"),
	{.name = "--closure", .value = "NAME", .kind = CLI_PARSE, .offset = RELAX(o.closure),
	 .parse = parse_closure, .expected = SS_CLOSURE_NAMES,
	 .help = SS_CLOSURE_NAMES " (default coulomb)"},
	RANGE("--gamma", "G", o.gamma, 1e-6, 1e6, "a number > 0",
	      "herschel-bulkley exponent (default 1)"),
	POSITIVE("--nu", "V", o.nu, "m^2/s > 0", "m^2/s (default 1): sets the time scale only"),
	POSITIVE("--tol", "X", o.tol, "m/s > 0", "steady when max |dh/dt| < X m/s (default 1e-9)"),
	POSITIVE("--slope-tol", "E", o.slope_tol, "a number > 0",
	         "and no sand face steeper than tan(angle) + E\n"
	         "(default 1e-6; other closures: the same flux)"),
	{.name = "--integrator", .value = "NAME", .kind = CLI_PARSE, .offset = RELAX(o.integrator),
	 .parse = parse_integrator, .expected = SS_INTEGRATOR_NAMES,
	 .help = "euler, rkl2 (super-steps) or auto (default: euler,\n"
	         "which relaxes DEMs faster as measured; rkl2\n"
	         "cannot be used with --bedrock)"},
	{.name = "--rkl2-max-stages", .value = "S", .kind = CLI_INT,
	 .offset = RELAX(o.rkl2_max_stages), .lo = 2, .hi = 100000,
	 .expected = "an integer >= 2",
	 .help = "rkl2: at most S stages a super-step (default 256)"},
	POSITIVE("--rkl2-tol", "E", o.rkl2_tol, "a number > 0",
	         "rkl2: error estimate of a super-step at most\n"
	         "E tan(angle) dx (default 0.1)"),
	POSITIVE("--max-time", "T", o.max_time, "s > 0",
	         "stop at T s even if not steady (default: none)"),
	RANGE("--cfl", "C", o.cfl, 1e-9, 1.0, "(0, 1]",
	      "fraction of the stable forward-Euler step (default 0.9)"),
	THREADS(RELAX(o.threads)),
	{.name = "--sides", .value = "wall|open", .kind = CLI_PARSE, .offset = RELAX(o.sides),
	 .parse = parse_sides, .expected = "wall or open",
	 .help = "the four sides of the DEM (default wall)"},
	{.name = "--nodata", .value = "wall|open", .kind = CLI_PARSE,
	 .offset = RELAX(o.nodata_type), .parse = parse_nodata, .expected = "wall or open",
	 .help = "cells without data (default wall: no sand enters\n"
	         "them; open: sand leaves there, at --open-level)"},
	RANGE("--open-level", "M", o.open_level, -1e300, 1e300, "a height in m",
	      "height held on open sides and open nodata cells\n"
	      "(default: the lowest height of the DEM)"),
	{.name = "--bedrock", .value = "FILE", .kind = CLI_TEXT, .offset = RELAX(o.bedrock),
	 .help = "non-erodible base, a raster of the DEM's size: only\n"
	         "the sand above it moves"},
	{.name = "--add-sand", .value = "SHAPE", .kind = CLI_PARSE, .offset = RELAX(o.sand_shape),
	 .parse = parse_sand_shape,
	 .expected = "rect=X0,Y0,X1,Y1 (X0 < X1, Y0 < Y1) or disk=X,Y,R (R > 0), in m",
	 .help = "pour sand on rect=X0,Y0,X1,Y1 or disk=X,Y,R (m)"},
	POSITIVE("--sand-rate", "R", o.sand_rate, "m/s > 0", "at R m/s (needed with --add-sand)"),
	POSITIVE("--sand-duration", "S", o.sand_duration, "s > 0",
	         "for S seconds from t = 0 (needed with --add-sand)"),
	POSITIVE("--dx", "M", o.read.cellsize, "m > 0", "cell size, for files that do not give one"),
	POSITIVE("--zscale", "Z", o.read.zscale, "m per grey level > 0",
	         "PNG: m per grey level (default: the file's range)"),
	RANGE("--zoffset", "Z0", o.read.zoffset, -1e300, 1e300, "m",
	      "PNG: height of grey 0, m (default 0)"),
	POSITIVE("--output-every", "T", o.output_every, "s > 0", ".h5 output: a snapshot every T s"),
	{.name = "--report", .value = "FILE.json", .kind = CLI_TEXT, .offset = RELAX(o.report),
	 .help = "write the diagnostics for scripts"},
	FORCE(RELAX(o.force), "replace OUT if it exists (else refused)"),
	QUIET(RELAX(quiet), "no progress line and no summary"),
};

/* What relax's options need together, checked after parsing. */
static int check_relax(struct cli_command *cmd, struct ss_relax_options *o)
{
	const int pour = cli_given(cmd, "--add-sand") != NULL;
	const int rate = cli_given(cmd, "--sand-rate") != NULL;
	const int duration = cli_given(cmd, "--sand-duration") != NULL;
	if (!o->dem)
		return cli_usage_error(cmd, "relax needs a DEM");
	if (pour != (rate && duration) || (!pour && (rate || duration)))
		return cli_usage_error(cmd, "--add-sand, --sand-rate and --sand-duration go together");
	if (!isnan(o->read.zoffset) && isnan(o->read.zscale))
		return cli_usage_error(cmd, "--zoffset needs --zscale");
	o->add_sand = pour;
	return CLI_GO_ON;
}

static int cmd_relax(int argc, char **argv)
{
	struct relax_args a = {.quiet = 0};
	ss_relax_options_init(&a.o);
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
		.groups = {{relax_options, COUNT(relax_options), &a, 0}},
		.outro = "Prints cells and volume moved, steepest face before and after, steps and\n"
		         "wall time.  The input is never modified; the output is written under a\n"
		         "temporary name and renamed when complete, and another run writing it is\n"
		         "refused.  Ctrl-C (SIGINT) or SIGTERM finish the substep and write the\n"
		         "surface as it is then (exit 130 or 143).  Exit status: 0 done, 1\n"
		         "failure while running, 2 bad input.\n",
		.what = "DEM", .args = &a.o.dem, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	if (status == CLI_GO_ON)
		status = check_relax(&cmd, &a.o);
	if (status != CLI_GO_ON)
		return status;
	struct ss_relax_report report;
	char *history = ss_strings_join((const char *const *)argv, argc, " ", 0);
	if (!history)
		return 1;
	a.o.history = history;
	a.o.progress = watch(a.quiet, &a.o.stop_signal);
	const int err = ss_relax_run(&a.o, &report);
	cli_progress_done();
	if (!err)
		cli_print_relax_end(&report, a.o.angle_deg, a.quiet);
	free(history);
	return exit_status(err);
}

/* ---- render --------------------------------------------------------------- */

struct render_args {
	struct ss_render_series_options o;
	int threads, quiet, bench, bench_n, no_label, no_colorbar;
};

#define RENDER(m) offsetof(struct render_args, m)
static const struct cli_option render_options[] = {
	{.name = "--output", .alias = "-o", .value = "DIR", .kind = CLI_TEXT,
	 .offset = RENDER(o.output_dir),
	 .help = "folder of the frames (default frames/, created if\nmissing)"},
	{.name = "--frames", .value = "A:B:STEP", .kind = CLI_TEXT, .offset = RENDER(o.frames),
	 .help = "snapshots A, A+STEP, ... before B, as a Python slice\n"
	         "(negative counts from the end; parts may be left out)"},
	{.name = "--time", .value = "T", .kind = CLI_REAL, .offset = RENDER(o.time),
	 .lo = -INFINITY, .hi = INFINITY, .expected = "a time in s",
	 .help = "only the snapshot nearest T seconds"},
	{.name = "--video", .value = "FILE.mp4", .kind = CLI_TEXT, .offset = RENDER(o.video),
	 .help = "assemble the frames with ffmpeg (H.264, yuv420p) if it\n"
	         "is on PATH; without it the frames are kept"},
	{.name = "--fps", .value = "N", .kind = CLI_INT, .offset = RENDER(o.fps), .lo = 1,
	 .hi = 240, .expected = "1 to 240",
	 .help = "frames per second of the video, and the speed the\n"
	         "viewer starts at (default 24)"},
	{.name = "--no-label", .kind = CLI_FLAG, .offset = RENDER(no_label),
	 .help = "no time label on a video's frames (--video draws one)"},
	{.name = "--no-colorbar", .kind = CLI_FLAG, .offset = RENDER(no_colorbar),
	 .help = "no colour bar on a video's frames (--video adds one)"},
	{.name = "--html", .value = "FILE.html", .kind = CLI_TEXT, .offset = RENDER(o.html),
	 .help = "write a self-contained viewer (frames, slider, play,\n"
	         "height under the mouse) to FILE.html; alone, no\n"
	         "frame folder is written (with -o or --video, both)"},
	FORCE(RENDER(o.force), "replace existing frames, video or viewer"),
	THREADS(RENDER(threads)),
	QUIET(RENDER(quiet), "no summary"),
	{.name = "--bench", .value = "[N]", .kind = CLI_OPTIONAL_INT, .offset = RENDER(bench),
	 .value_offset = RENDER(bench_n), .lo = 16, .hi = 32768,
	 .help = "time the shaded style on an N x N grid (default 4096)"},
};

static int cmd_render(int argc, char **argv)
{
	struct render_args a = {.o = {.output_dir = "frames", .time = NAN, .fps = 24},
	                        .bench_n = 4096};
	ss_render_options_default(&a.o.look);
	struct cli_command cmd = {
		.usage = "usage: sandslide render FILE.h5 [-o DIR] [--frames A:B:STEP | --time T] "
		         "[options]\n"
		         "       sandslide render FILE.h5 --html FILE.html [options]\n"
		         "       sandslide render --bench [N]\n",
		.intro = "Draws the snapshots of a sandslide output file as PNG pictures,\n"
		         "DIR/frame_00000.png, frame_00001.png, ... in time order (SPEC section 6),\n"
		         "or into one HTML page that shows them (--html).\n",
		.groups = {{render_options, COUNT(render_options), &a, 0},
		           {look_options, COUNT(look_options), &a.o.look, 0}},
		.outro = "Each PNG holds the time, the height scale and the snapshot in text chunks;\n"
		         "a frame is written under a temporary name and renamed when complete.\n"
		         "Exit status: 0 done, 1 failure while rendering, 2 bad input.\n",
		.what = "file", .args = &a.o.input, .max_args = 1,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	ss_parallel_set_threads(a.threads > 0 ? a.threads : ss_parallel_default_threads(1));
	if (a.bench) {
		struct ss_render_bench_report report;
		const int err = ss_render_bench(a.bench_n, 5, &report);
		if (!err)
			cli_print_render_bench(&report);
		return ss_status_exit_code(err);
	}
	if (!a.o.input)
		return cli_usage_error(&cmd, "render needs a sandslide output file");
	/* a video is watched without its file: it shows the time and the scale */
	if (a.o.video && a.o.look.style != SS_RENDER_GRAY16) {
		a.o.look.label |= !a.no_label;
		a.o.look.colorbar |= !a.no_colorbar;
	}
	if (a.no_label)
		a.o.look.label = 0;
	if (a.no_colorbar)
		a.o.look.colorbar = 0;
	/* the viewer alone needs no frame files; a video is made from them */
	if (a.o.html && !cli_given(&cmd, "--output") && !a.o.video)
		a.o.output_dir = NULL;
	struct ss_render_series_report report;
	const int err = ss_render_series(&a.o, &report);
	if (!err)
		cli_print_render_series(&a.o, &report, a.quiet);
	return ss_status_exit_code(err);
}

/* ---- bench ---------------------------------------------------------------- */

static void add_bench_closure(struct ss_bench_options *o, enum ss_closure_kind kind,
                              double gamma)
{
	struct ss_bench_closure *c = &o->closures[o->closure_count++];
	c->kind = kind;
	c->gamma = gamma;
	if (kind == SS_CLOSURE_HERSCHEL_BULKLEY)
		snprintf(c->label, sizeof c->label, "herschel-bulkley(%g)", gamma);
	else
		snprintf(c->label, sizeof c->label, "%s", ss_closure_name(kind));
}

/* --closure NAME|all: herschel-bulkley stands for gamma 0.5 and 2. */
static int parse_bench_closures(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	enum ss_closure_kind kind;
	const int all = !strcmp(word, "all");
	if (!all && ss_closure_parse(word, &kind))
		return -1;
	o->closure_count = 0;
	for (int k = SS_CLOSURE_COULOMB; k <= SS_CLOSURE_CASSON; k++) {
		if (!all && k != (int)kind)
			continue;
		if (k == SS_CLOSURE_HERSCHEL_BULKLEY) {
			add_bench_closure(o, SS_CLOSURE_HERSCHEL_BULKLEY, 0.5);
			add_bench_closure(o, SS_CLOSURE_HERSCHEL_BULKLEY, 2.0);
		} else {
			add_bench_closure(o, (enum ss_closure_kind)k, 1.0);
		}
	}
	return 0;
}

static int parse_bench_surfaces(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	int matched = 0;
	for (int s = 0; s < SS_BENCH_SURFACES; s++) {
		o->surfaces[s] = !strcmp(word, "all") ||
		                 !strcmp(word, ss_bench_surface_name((enum ss_bench_surface)s));
		matched |= o->surfaces[s];
	}
	return matched ? 0 : -1;
}

/* --threads 1,2: at most SS_BENCH_MAX_CASES counts. */
static int parse_bench_threads(const char *word, void *target)
{
	struct ss_bench_options *o = target;
	o->thread_count = 0;
	for (const char *p = word; *p;) {
		char buf[16];
		const size_t len = strcspn(p, ",");
		if (len == 0 || len >= sizeof buf || o->thread_count == SS_BENCH_MAX_CASES)
			return -1;
		memcpy(buf, p, len);
		buf[len] = '\0';
		if (ss_parse_int(buf, 1, 4096, &o->threads[o->thread_count++]))
			return -1;
		p += len + (p[len] == ',');
	}
	return o->thread_count > 0 ? 0 : -1;
}

struct bench_args {
	struct ss_bench_options o;
	struct cli_bench print;
	int tile[2];
};

#define BENCH(m) offsetof(struct bench_args, m)
#define CELLS(n, m, h)                                                                \
	{.name = n, .value = "N", .kind = CLI_INT, .offset = BENCH(m), .lo = 1, .hi = 1 << 20, \
	 .expected = "a cell count from 1 to 1048576", .help = h}
static const struct cli_option bench_options[] = {
	CELLS("--nx", o.nx, "cells along x (default 8192)"),
	CELLS("--ny", o.ny, "cells along y (default 8192)"),
	{.name = "--closure", .value = "NAME|all", .kind = CLI_PARSE, .offset = BENCH(o),
	 .parse = parse_bench_closures, .expected = "all, " SS_CLOSURE_NAMES,
	 .help = "coulomb, bingham, herschel-bulkley (gamma 0.5 and 2),\n"
	         "casson, or all (default)"},
	{.name = "--threads", .value = "LIST", .kind = CLI_PARSE, .offset = BENCH(o),
	 .parse = parse_bench_threads,
	 .expected = "a list such as 1,2 (at most 8 entries from 1 to 4096)",
	 .help = "thread counts, comma-separated (default 1,2)"},
	{.name = "--surface", .value = "NAME|all", .kind = CLI_PARSE, .offset = BENCH(o),
	 .parse = parse_bench_surfaces, .expected = "all, supercritical, subcritical or patch",
	 .help = "supercritical (every face slides), subcritical (none\n"
	         "does), patch (a 512 x 512 ramp on a flat floor), all"},
	{.name = "--repeats", .value = "N", .kind = CLI_INT, .offset = BENCH(o.repeats), .lo = 1,
	 .hi = 64, .expected = "1 to 64", .help = "timings per case (default 5); median, min and max"},
	{.name = "--steps", .value = "N", .kind = CLI_INT, .offset = BENCH(o.steps), .lo = 1,
	 .hi = 1000000, .expected = "1 to 1000000",
	 .help = "steps per timing (default: about 0.3 s worth)"},
	TILE(BENCH(tile), "tile size of the sweep (default 256x128)"),
	{.name = "--json", .kind = CLI_FLAG, .offset = BENCH(print.json),
	 .help = "one JSON document instead of a table"},
};

static int cmd_bench(int argc, char **argv)
{
	struct bench_args a = {.o = {.nx = 8192, .ny = 8192, .repeats = 5}};
	parse_bench_closures("all", &a.o);
	parse_bench_surfaces("all", &a.o);
	parse_bench_threads("1,2", &a.o);
	struct cli_command cmd = {
		.usage = "usage: sandslide bench [--nx N] [--ny N] [--closure NAME|all] "
		         "[--threads 1,2]\n"
		         "                       [--surface NAME|all] [--repeats N] [--steps N] "
		         "[--tile NXxNY]\n"
		         "                       [--json]\n",
		.groups = {{bench_options, COUNT(bench_options), &a, 0}},
		.outro = "Also measures the memory bandwidth (read+write of one array) in the same run\n"
		         "and reports the fraction of that roofline each case reaches.\n",
		.what = "argument", .max_args = 0,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	a.o.tile_nx = a.tile[0];
	a.o.tile_ny = a.tile[1];
	a.o.on_header = cli_bench_header;
	a.o.on_result = cli_bench_result;
	a.o.context = &a.print;
	const int err = ss_bench_run(&a.o);
	if (!err)
		cli_bench_done(&a.print);
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
		{"render", cmd_render}, {"relax", cmd_relax},
	};
	ss_snapshot_library_init();
	if (ss_cpu_init())   /* SANDSLIDE_CPU, on every rank before anything runs */
		return 2;
	if (argc < 2)
		return main_usage_error("%s", "no command given");
	const char *cmd = argv[1];
	if (!strcmp(cmd, "help") && argc > 2) {   /* help CMD: that command's --help */
		for (int k = 0; k < COUNT(commands); k++)
			if (!strcmp(argv[2], commands[k].name)) {
				char *args[] = {argv[0], argv[2], "--help", NULL};
				return commands[k].run(3, args);
			}
		return main_usage_error("help: unknown command '%s': expected run, relax, info, "
		                        "render or bench", argv[2]);
	}
	if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
		fputs(usage_main, stdout);
		return 0;
	}
	if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) {
		printf("sandslide %s (OpenMP: %s, %d processors; GDAL: %s; MPI: %s; kernel: %s)\n",
		       ss_version(),
#ifdef _OPENMP
		       "on",
#else
		       "off",
#endif
		       ss_parallel_processors(), ss_dem_gdal_available() ? "on" : "off",
		       ss_comm_library() ? ss_comm_library() : "off", ss_cpu_path_name(ss_cpu_path()));
		return 0;
	}
	/* the distributed commands: the others work on one block */
	if (ss_comm_size() > 1 && strcmp(cmd, "run") != 0 && strcmp(cmd, "relax") != 0)
		return main_usage_error("'%s' runs on one rank: only run and relax are distributed "
		                        "(start it without mpirun)", cmd);
	for (int k = 0; k < COUNT(commands); k++)
		if (!strcmp(cmd, commands[k].name))
			return commands[k].run(argc, argv);
	return main_usage_error("unknown command '%s': expected run, relax, info, render or bench",
	                        cmd);
}

int main(int argc, char **argv)
{
	ss_comm_init(&argc, &argv);
	if (ss_comm_rank() != 0 && !freopen("/dev/null", "w", stdout))
		ss_comm_abort(1);
	const int code = command(argc, argv);
	ss_comm_finalize();
	return code;
}
