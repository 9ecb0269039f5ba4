/*
 * main.c - the `sandslide` command line (SPEC section 3): parse the
 * arguments (each command's options are one table, options.h, which also
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
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/relax.h"
#include "sandslide/render.h"
#include "sandslide/run.h"
#include "sandslide/snapshot.h"

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
	"  sandslide CMD --help   options of a command\n";

/* The signal that asked a run to stop (SIGINT or SIGTERM), 0 while none
 * did: the run finishes its substep, writes a snapshot and returns, and the
 * exit status is 128 + the signal.  A second signal kills at once
 * (SA_RESETHAND). */
static volatile sig_atomic_t stop_signal;

static void on_stop_signal(int sig)
{
	stop_signal = sig;
}

static void install_signal_handlers(void)
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
}

/* The exit status of a command that a signal may have stopped. */
static int exit_status(int status)
{
	const int code = ss_status_exit_code(status);
	return code == 0 && stop_signal ? 128 + stop_signal : code;
}

static struct cli_option threads_option(int *threads)
{
	return (struct cli_option){
		.name = "--threads", .value = "N", .kind = CLI_INT, .target = threads,
		.lo = 1, .hi = 4096, .expected = "an integer from 1 to 4096",
		.help = "OpenMP threads (default: all processors)",
	};
}

/* ---- the look of frames: `render` and `run --frames` ------------------- */

static int parse_style(const char *word, void *target)
{
	return ss_render_style_parse(word, target);
}

static int parse_cmap(const char *word, void *target)
{
	return ss_render_cmap_parse(word, target);
}

enum { LOOK_OPTIONS = 16 };

/* Any finite number: ss_render_options_check says what a look accepts. */
#define NUMBER(n, v, t, h)                                                          \
	{.name = n, .value = v, .kind = CLI_REAL, .target = t, .lo = -INFINITY,     \
	 .hi = INFINITY, .expected = "a finite number", .help = h}

/* The look options into out (LOOK_OPTIONS entries); each sets *given. */
static void look_options(struct cli_option *out, struct ss_render_options *o, int *given,
                         int hidden)
{
	const struct cli_option table[LOOK_OPTIONS] = {
		{.help = "The look of the frames (also for `sandslide run --frames`):\n"},
		{.name = "--style", .value = "NAME", .kind = CLI_PARSE, .target = &o->style,
		 .parse = parse_style, .expected = SS_RENDER_STYLE_NAMES,
		 .help = "shaded (default): colour map x hillshade, 8-bit RGB;\n"
		         "gray16: 16-bit grey heights, zmin..zmax in the PNG text;\n"
		         "oblique: perspective view, walls as raised blocks"},
		{.name = "--cmap", .value = "NAME", .kind = CLI_PARSE, .target = &o->cmap,
		 .parse = parse_cmap, .expected = SS_RENDER_CMAP_NAMES,
		 .help = "dune (default; perceptually uniform), terrain, gray"},
		NUMBER("--zmin", "Z", &o->zmin,
		       "bottom of the height scale, m (default: the lowest\n"
		       "sand of the whole file, so all frames share it)"),
		NUMBER("--zmax", "Z", &o->zmax,
		       "top of the height scale, m (default: the highest sand)"),
		NUMBER("--azimuth", "DEG", &o->azimuth_deg,
		       "light from this compass bearing (default 315: north-west)"),
		NUMBER("--altitude", "DEG", &o->altitude_deg,
		       "light above the horizon (default 45)"),
		NUMBER("--zscale", "S", &o->zscale,
		       "vertical exaggeration of shading and view (default 1)"),
		NUMBER("--contour", "DZ", &o->contour,
		       "contour lines every DZ m (shaded)"),
		{.name = "--label", .kind = CLI_FLAG, .target = &o->label,
		 .help = "draw the simulated time on each frame"},
		{.name = "--colorbar", .kind = CLI_FLAG, .target = &o->colorbar,
		 .help = "add a colour bar with the height scale"},
		{.name = "--max-size", .value = "PX", .kind = CLI_INT, .target = &o->max_size,
		 .lo = 8, .hi = 65536, .expected = "8 to 65536 px",
		 .help = "at most PX pixels a side (cells are area-averaged)"},
		{.name = "--scale", .value = "K", .kind = CLI_INT, .target = &o->scale,
		 .lo = 1, .hi = 100, .expected = "1 to 100 px per cell",
		 .help = "K pixels per cell (default 1 for gray16, otherwise\n"
		         "enough for a side of 512 px)"},
		NUMBER("--view-azimuth", "DEG", &o->view_azimuth_deg,
		       "oblique: the camera's bearing from the centre (200)"),
		NUMBER("--view-elevation", "DEG", &o->view_elevation_deg,
		       "oblique: the camera above the horizon (45)"),
		{.name = "--compression", .value = "N", .kind = CLI_INT, .target = &o->compression,
		 .lo = 0, .hi = 9, .expected = "0 to 9",
		 .help = "zlib level of the PNGs, 0 to 9 (default 6)"},
	};
	for (int k = 0; k < LOOK_OPTIONS; k++) {
		out[k] = table[k];
		out[k].given = out[k].name ? given : NULL;
		out[k].hidden = hidden;
	}
}

/* ---- run ------------------------------------------------------------------ */

/* `run --frames`: render each snapshot the run reports. */
static int render_run_snapshot(void *context, const struct ss_run_snapshot *s)
{
	const struct ss_render_frames_bounds b = {s->source_rise, s->open_level,
	                                          s->any_open_side};
	return ss_render_frames_add(context, s->path, s->index, &b);
}

/* What the long commands (run, relax) share: the stop signals caught and,
 * on a terminal unless quiet, a progress line (the callback to give). */
static ss_progress_fn *watch(int quiet, const volatile sig_atomic_t **stop)
{
	install_signal_handlers();
	*stop = &stop_signal;
	return !quiet && isatty(fileno(stderr)) ? cli_print_progress : NULL;
}

/* The first argument that is one of the n options (for messages). */
static const char *first_of(const struct cli_option *options, int n, int argc, char **argv)
{
	for (int k = 2; k < argc; k++)
		for (int m = 0; m < n; m++) {
			const size_t len = options[m].name ? strlen(options[m].name) : 0;
			if (len && !strncmp(argv[k], options[m].name, len) &&
			    (argv[k][len] == '\0' || argv[k][len] == '='))
				return argv[k];
		}
	return "a look option";
}

/* The run with what the command line gave (the frames to draw, if any). */
static int run_with_frames(int argc, char **argv, struct ss_run_options *o,
                           const char *frames_dir, const struct ss_render_options *look,
                           int quiet)
{
	struct ss_render_frames *frames = NULL;
	struct ss_run_summary s;
	char *history = NULL;
	int err = frames_dir ? ss_render_frames_create(&frames, frames_dir, look) : SS_OK;
	if (!err && !(history = ss_strings_join((const char *const *)argv, argc, " ", 0)))
		err = SS_ERR_FAIL;
	if (!err) {
		o->history = history;
		o->on_snapshot = frames ? render_run_snapshot : NULL;
		o->snapshot_context = frames;
		o->progress = watch(quiet, &o->stop_signal);
		err = ss_run_case(o, &s);
		cli_progress_done();
	}
	if (!err)
		cli_print_run_end(&s, quiet);
	if (!err && frames && !quiet)
		printf("wrote %lld frames to %s%s\n", ss_render_frames_count(frames), frames_dir,
		       frames_dir[strlen(frames_dir) - 1] == '/' ? "" : "/");
	free(history);
	ss_render_frames_destroy(frames);
	return err;
}

static int cmd_run(int argc, char **argv)
{
	struct ss_run_options o = {0};
	struct ss_render_options look;
	struct cli_list sets = {calloc((size_t)argc, sizeof(char *)), 0};
	const char *case_path = NULL, *frames_dir = NULL;
	int quiet = 0, look_given = 0, tile[2] = {0, 0};
	if (!sets.v)
		return ss_status_exit_code(ss_error_fail("out of memory"));
	ss_render_options_default(&look);
	struct cli_option options[10 + LOOK_OPTIONS] = {
		{.name = "--output", .alias = "-o", .value = "OUT.h5", .kind = CLI_TEXT,
		 .target = &o.output,
		 .help = "output file (default out/<case name>.h5; its folder\n"
		         "must exist unless it is the default out/)"},
		{.name = "--force", .kind = CLI_FLAG, .target = &o.force,
		 .help = "replace OUT.h5 if it exists (else refused)"},
		{.name = "--restart", .value = "OUT.h5", .kind = CLI_TEXT, .target = &o.restart,
		 .help = "continue the run in OUT.h5 from its last snapshot,\n"
		         "appending to it, with the case stored in it (a\n"
		         "CASE.ini given too must be that case, and its\n"
		         "files are found beside it); the snapshots are\n"
		         "those of a run never interrupted"},
		threads_option(&o.threads),
		{.name = "--set", .alias = "-P", .value = "SECTION.KEY=VALUE", .kind = CLI_LIST,
		 .target = &sets,
		 .help = "override key KEY of section SECTION of the case, e.g.\n"
		         "--set model.closure=casson, --set 'source pour.rate=0.002'"},
		{.name = "--tile", .value = "NXxNY", .kind = CLI_PARSE, .target = tile,
		 .parse = cli_parse_tile, .expected = "NXxNY, e.g. 256x64",
		 .help = "cells per tile of the sweep (default 256x128, smaller\n"
		         "on small grids); results are the same bits for any\n"
		         "tile size and thread count"},
		{.name = "--reference-kernel", .kind = CLI_FLAG, .target = &o.reference_kernel,
		 .help = "use the plain two-pass sweep the fast one is tested\n"
		         "against (same bits, several times slower)"},
		{.name = "--deflate", .value = "N", .kind = CLI_INT, .target = &o.deflate,
		 .lo = 0, .hi = 9, .expected = "0 to 9",
		 .help = "HDF5 deflate level of /height, 0 (off, default) to 9"},
		{.name = "--quiet", .alias = "-q", .kind = CLI_FLAG, .target = &quiet,
		 .help = "no progress line and no summary"},
		{.name = "--frames", .value = "DIR", .kind = CLI_TEXT, .target = &frames_dir,
		 .help = "also draw each snapshot as it is written, to\n"
		         "DIR/frame_00000.png, ... (shaded; the look options\n"
		         "of `sandslide render --help` apply, e.g. --label)"},
	};
	look_options(options + 10, &look, &look_given, 1);
	struct cli_command cmd = {
		.usage = "usage: sandslide run CASE.ini [-o OUT.h5] [--threads N] "
		         "[--set SECTION.KEY=VALUE ...]\n"
		         "       sandslide run --restart OUT.h5 [CASE.ini] [--threads N]\n",
		.options = options, .option_count = COUNT(options),
		.outro = "Writes OUT.h5 (SPEC section 5) and the XDMF sidecar OUT.xmf, flushed after\n"
		         "every snapshot.  Ctrl-C (SIGINT) or SIGTERM finish the substep, write a\n"
		         "snapshot and exit 130 or 143 naming the command that continues the run.\n"
		         "Another run writing the same output is refused, --force or not.\n"
		         "Exit status: 0 done, 1 failure while running, 2 bad input.\n",
		.what = "case file", .args = &case_path, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	if (status == CLI_GO_ON && !case_path && !o.restart)
		status = cli_usage_error(&cmd, "run needs a case file (or --restart OUT.h5)");
	if (status == CLI_GO_ON && look_given && !frames_dir)
		status = cli_usage_error(&cmd, "%s sets the look of frames: it needs --frames DIR",
		                         first_of(options + 10, LOOK_OPTIONS, argc, argv));
	if (status == CLI_GO_ON) {
		o.case_path = case_path;
		o.overrides = sets.v;
		o.override_count = sets.n;
		o.tile_nx = tile[0];
		o.tile_ny = tile[1];
		status = exit_status(run_with_frames(argc, argv, &o, frames_dir, &look, quiet));
	}
	free(sets.v);
	return status;
}

/* ---- relax ---------------------------------------------------------------- */

static int parse_closure(const char *word, void *target)
{
	return ss_closure_parse(word, target);
}

static int parse_sides(const char *word, void *target)
{
	return ss_side_kind_parse(word, target) || *(enum ss_side_kind *)target == SS_SIDE_PERIODIC
	       ? -1 : 0;
}

static int parse_nodata(const char *word, void *target)
{
	enum ss_cell_type *type = target;
	if (strcmp(word, "wall") && strcmp(word, "open"))
		return -1;
	*type = !strcmp(word, "wall") ? SS_CELL_WALL : SS_CELL_OPEN;
	return 0;
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

/* A number > 0 (up to 1e300) for relax's table. */
#define POSITIVE(n, v, t, e, h)                                                      \
	{.name = n, .value = v, .kind = CLI_REAL, .target = t, .lo = 1e-300, .hi = 1e300, \
	 .expected = e, .help = h}

static int cmd_relax(int argc, char **argv)
{
	struct ss_relax_options o;
	int quiet = 0, have_rate = 0, have_duration = 0;
	ss_relax_options_init(&o);
	const struct cli_option options[] = {
		{.name = "--output", .alias = "-o", .value = "OUT", .kind = CLI_TEXT,
		 .target = &o.output,
		 .help = ".asc, .png, .tif: the relaxed raster; .h5: the whole\n"
		         "series with diagnostics (default out/<DEM>-relaxed\n"
		         "with the input's extension)"},
		{.name = "--angle", .value = "DEG", .kind = CLI_REAL, .target = &o.angle_deg,
		 .lo = 1e-9, .hi = 90.0 - 1e-9, .expected = "degrees in (0, 90)",
		 .help = "repose angle (default 35)"},
		{.name = "--closure", .value = "NAME", .kind = CLI_PARSE, .target = &o.closure,
		 .parse = parse_closure, .expected = SS_CLOSURE_NAMES,
		 .help = SS_CLOSURE_NAMES " (default coulomb)"},
		{.name = "--gamma", .value = "G", .kind = CLI_REAL, .target = &o.gamma, .lo = 1e-6,
		 .hi = 1e6, .expected = "a number > 0",
		 .help = "herschel-bulkley exponent (default 1)"},
		POSITIVE("--nu", "V", &o.nu, "m^2/s > 0", "m^2/s (default 1): sets the time scale only"),
		POSITIVE("--tol", "X", &o.tol, "m/s > 0",
		         "steady when max |dh/dt| < X m/s (default 1e-9)"),
		POSITIVE("--max-time", "T", &o.max_time, "s > 0",
		         "stop at T s even if not steady (default: none)"),
		{.name = "--cfl", .value = "C", .kind = CLI_REAL, .target = &o.cfl, .lo = 1e-9,
		 .hi = 1.0, .expected = "(0, 1]",
		 .help = "fraction of the stable forward-Euler step (default 0.9)"},
		threads_option(&o.threads),
		{.name = "--sides", .value = "wall|open", .kind = CLI_PARSE, .target = &o.sides,
		 .parse = parse_sides, .expected = "wall or open",
		 .help = "the four sides of the DEM (default wall)"},
		{.name = "--nodata", .value = "wall|open", .kind = CLI_PARSE,
		 .target = &o.nodata_type, .parse = parse_nodata, .expected = "wall or open",
		 .help = "cells without data (default open: sand leaves there)"},
		{.name = "--open-level", .value = "M", .kind = CLI_REAL, .target = &o.open_level,
		 .lo = -1e300, .hi = 1e300, .expected = "a height in m",
		 .help = "height held on open cells and sides (default: the\n"
		         "lowest height of the DEM)"},
		{.name = "--bedrock", .value = "FILE", .kind = CLI_TEXT, .target = &o.bedrock,
		 .help = "non-erodible base, a raster of the DEM's size: only\n"
		         "the sand above it moves"},
		{.name = "--add-sand", .value = "SHAPE", .kind = CLI_PARSE, .target = &o.sand_shape,
		 .parse = parse_sand_shape, .given = &o.add_sand,
		 .expected = "rect=X0,Y0,X1,Y1 (X0 < X1, Y0 < Y1) or disk=X,Y,R (R > 0), in m",
		 .help = "pour sand on rect=X0,Y0,X1,Y1 or disk=X,Y,R (m)"},
		{.name = "--sand-rate", .value = "R", .kind = CLI_REAL, .target = &o.sand_rate,
		 .lo = 1e-300, .hi = 1e300, .expected = "m/s > 0", .given = &have_rate,
		 .help = "at R m/s (needed with --add-sand)"},
		{.name = "--sand-duration", .value = "S", .kind = CLI_REAL,
		 .target = &o.sand_duration, .lo = 1e-300, .hi = 1e300, .expected = "s > 0",
		 .given = &have_duration,
		 .help = "for S seconds from t = 0 (needed with --add-sand)"},
		POSITIVE("--dx", "M", &o.read.cellsize, "m > 0",
		         "cell size, for files that do not give one"),
		POSITIVE("--zscale", "Z", &o.read.zscale, "m per grey level > 0",
		         "PNG: m per grey level (default: the file's range)"),
		{.name = "--zoffset", .value = "Z0", .kind = CLI_REAL, .target = &o.read.zoffset,
		 .lo = -1e300, .hi = 1e300, .expected = "m",
		 .help = "PNG: height of grey 0, m (default 0)"},
		POSITIVE("--output-every", "T", &o.output_every, "s > 0",
		         ".h5 output: a snapshot every T s"),
		{.name = "--report", .value = "FILE.json", .kind = CLI_TEXT, .target = &o.report,
		 .help = "write the diagnostics for scripts"},
		{.name = "--force", .kind = CLI_FLAG, .target = &o.force,
		 .help = "replace OUT if it exists (else refused)"},
		{.name = "--quiet", .alias = "-q", .kind = CLI_FLAG, .target = &quiet,
		 .help = "no progress line and no summary"},
	};
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
		.options = options, .option_count = COUNT(options),
		.outro = "Prints cells and volume moved, steepest face before and after, steps and\n"
		         "wall time.  The input is never modified; the output is written under a\n"
		         "temporary name and renamed when complete, and another run writing it is\n"
		         "refused.  Ctrl-C (SIGINT) or SIGTERM finish the substep and write the\n"
		         "surface as it is then (exit 130 or 143).  Exit status: 0 done, 1\n"
		         "failure while running, 2 bad input.\n",
		.what = "DEM", .args = &o.dem, .max_args = 1,
	};
	int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	if (!o.dem)
		return cli_usage_error(&cmd, "relax needs a DEM");
	if (o.add_sand != (have_rate && have_duration) || (!o.add_sand && (have_rate || have_duration)))
		return cli_usage_error(&cmd, "--add-sand, --sand-rate and --sand-duration go together");
	if (!isnan(o.read.zoffset) && isnan(o.read.zscale))
		return cli_usage_error(&cmd, "--zoffset needs --zscale");
	struct ss_relax_report report;
	char *history = ss_strings_join((const char *const *)argv, argc, " ", 0);
	if (!history)
		return 1;
	o.history = history;
	o.progress = watch(quiet, &o.stop_signal);
	const int err = ss_relax_run(&o, &report);
	cli_progress_done();
	if (!err)
		cli_print_relax_end(&report, o.angle_deg, quiet);
	free(history);
	return exit_status(err);
}

/* ---- render --------------------------------------------------------------- */

static int cmd_render(int argc, char **argv)
{
	struct ss_render_series_options o = {0};
	struct cli_optional_int bench = {0, 4096};
	int threads = 0, look_given = 0;
	ss_render_options_default(&o.look);
	o.output_dir = "frames";
	o.time = NAN;
	o.fps = 24;
	struct cli_option options[8 + LOOK_OPTIONS] = {
		{.name = "--output", .alias = "-o", .value = "DIR", .kind = CLI_TEXT,
		 .target = &o.output_dir,
		 .help = "folder of the frames (default frames/, created if\nmissing)"},
		{.name = "--frames", .value = "A:B:STEP", .kind = CLI_TEXT, .target = &o.frames,
		 .help = "snapshots A, A+STEP, ... before B, as a Python slice\n"
		         "(negative counts from the end; parts may be left out)"},
		{.name = "--time", .value = "T", .kind = CLI_REAL, .target = &o.time,
		 .lo = -INFINITY, .hi = INFINITY, .expected = "a time in s",
		 .help = "only the snapshot nearest T seconds"},
		{.name = "--video", .value = "FILE.mp4", .kind = CLI_TEXT, .target = &o.video,
		 .help = "assemble the frames with ffmpeg (H.264, yuv420p) if it\n"
		         "is on PATH; without it the frames are kept"},
		{.name = "--fps", .value = "N", .kind = CLI_INT, .target = &o.fps, .lo = 1,
		 .hi = 240, .expected = "1 to 240",
		 .help = "frames per second of the video (default 24)"},
		threads_option(&threads),
		{.name = "--quiet", .alias = "-q", .kind = CLI_FLAG, .target = &o.quiet,
		 .help = "no summary"},
		{.name = "--bench", .value = "[N]", .kind = CLI_OPTIONAL_INT, .target = &bench,
		 .lo = 16, .hi = 32768,
		 .help = "time the shaded style on an N x N grid (default 4096)"},
	};
	look_options(options + 8, &o.look, &look_given, 0);
	const char *input = NULL;
	struct cli_command cmd = {
		.usage = "usage: sandslide render FILE.h5 [-o DIR] [--frames A:B:STEP | --time T] "
		         "[options]\n"
		         "       sandslide render --bench [N]\n",
		.intro = "Draws the snapshots of a sandslide output file as PNG pictures,\n"
		         "DIR/frame_00000.png, frame_00001.png, ... in time order (SPEC section 6).\n",
		.options = options, .option_count = COUNT(options),
		.outro = "Each PNG holds the time, the height scale and the snapshot in text chunks;\n"
		         "a frame is written under a temporary name and renamed when complete.\n"
		         "Exit status: 0 done, 1 failure while rendering, 2 bad input.\n",
		.what = "file", .args = &input, .max_args = 1,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	ss_parallel_set_threads(threads > 0 ? threads : ss_parallel_processors());
	if (bench.given)
		return ss_status_exit_code(ss_render_bench(bench.value, 5));
	if (!input)
		return cli_usage_error(&cmd, "render needs a sandslide output file");
	o.input = input;
	return ss_status_exit_code(ss_render_series(&o));
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
		if (cli_parse_int(buf, 1, 4096, &o->threads[o->thread_count++]))
			return -1;
		p += len + (p[len] == ',');
	}
	return o->thread_count > 0 ? 0 : -1;
}

static int cmd_bench(int argc, char **argv)
{
	struct ss_bench_options o = {.nx = 8192, .ny = 8192, .repeats = 5};
	struct cli_bench b = {0};
	int tile[2] = {0, 0};
	parse_bench_closures("all", &o);
	parse_bench_surfaces("all", &o);
	parse_bench_threads("1,2", &o);
	const struct cli_option options[] = {
		{.name = "--nx", .value = "N", .kind = CLI_INT, .target = &o.nx, .lo = 1,
		 .hi = 1 << 20, .expected = "a cell count from 1 to 1048576",
		 .help = "cells along x (default 8192)"},
		{.name = "--ny", .value = "N", .kind = CLI_INT, .target = &o.ny, .lo = 1,
		 .hi = 1 << 20, .expected = "a cell count from 1 to 1048576",
		 .help = "cells along y (default 8192)"},
		{.name = "--closure", .value = "NAME|all", .kind = CLI_PARSE, .target = &o,
		 .parse = parse_bench_closures, .expected = "all, " SS_CLOSURE_NAMES,
		 .help = "coulomb, bingham, herschel-bulkley (gamma 0.5 and 2),\n"
		         "casson, or all (default)"},
		{.name = "--threads", .value = "LIST", .kind = CLI_PARSE, .target = &o,
		 .parse = parse_bench_threads,
		 .expected = "a list such as 1,2 (at most 8 entries from 1 to 4096)",
		 .help = "thread counts, comma-separated (default 1,2)"},
		{.name = "--surface", .value = "NAME|all", .kind = CLI_PARSE, .target = &o,
		 .parse = parse_bench_surfaces,
		 .expected = "all, supercritical, subcritical or patch",
		 .help = "supercritical (every face slides), subcritical (none\n"
		         "does), patch (a 512 x 512 ramp on a flat floor), all"},
		{.name = "--repeats", .value = "N", .kind = CLI_INT, .target = &o.repeats, .lo = 1,
		 .hi = 64, .expected = "1 to 64",
		 .help = "timings per case (default 5); median, min and max"},
		{.name = "--steps", .value = "N", .kind = CLI_INT, .target = &o.steps, .lo = 1,
		 .hi = 1000000, .expected = "1 to 1000000",
		 .help = "steps per timing (default: about 0.3 s worth)"},
		{.name = "--tile", .value = "NXxNY", .kind = CLI_PARSE, .target = tile,
		 .parse = cli_parse_tile, .expected = "NXxNY, e.g. 256x64",
		 .help = "tile size of the sweep (default 256x128)"},
		{.name = "--json", .kind = CLI_FLAG, .target = &b.json,
		 .help = "one JSON document instead of a table"},
	};
	struct cli_command cmd = {
		.usage = "usage: sandslide bench [--nx N] [--ny N] [--closure NAME|all] "
		         "[--threads 1,2]\n"
		         "                       [--surface NAME|all] [--repeats N] [--steps N] "
		         "[--tile NXxNY]\n"
		         "                       [--json]\n",
		.options = options, .option_count = COUNT(options),
		.outro = "Also measures the memory bandwidth (read+write of one array) in the same run\n"
		         "and reports the fraction of that roofline each case reaches.\n",
		.what = "benchmark", .max_args = 0,
	};
	const int status = cli_parse(&cmd, argc, argv, 2);
	if (status != CLI_GO_ON)
		return status;
	o.tile_nx = tile[0];
	o.tile_ny = tile[1];
	o.on_header = cli_bench_header;
	o.on_result = cli_bench_result;
	o.context = &b;
	const int err = ss_bench_run(&o);
	if (!err)
		cli_bench_done(&b);
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
	fflush(stdout);
	fputs("sandslide: ", stderr);
	fprintf(stderr, fmt, arg);
	fprintf(stderr, "\n\n%s", usage_main);
	return 2;
}

int main(int argc, char **argv)
{
	static const struct {
		const char *name;
		int (*run)(int argc, char **argv);
	} commands[] = {
		{"run", cmd_run}, {"info", cmd_info}, {"bench", cmd_bench},
		{"render", cmd_render}, {"relax", cmd_relax},
	};
	ss_snapshot_library_init();
	if (argc < 2)
		return main_usage_error("%s", "no command given");
	const char *cmd = argv[1];
	if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
		fputs(usage_main, stdout);
		return 0;
	}
	if (!strcmp(cmd, "--version") || !strcmp(cmd, "version")) {
		printf("sandslide %s (OpenMP: %s, %d processors; GDAL: %s)\n", SS_VERSION,
#ifdef _OPENMP
		       "on",
#else
		       "off",
#endif
		       ss_parallel_processors(), ss_dem_gdal_available() ? "on" : "off");
		return 0;
	}
	for (int k = 0; k < COUNT(commands); k++)
		if (!strcmp(cmd, commands[k].name))
			return commands[k].run(argc, argv);
	return main_usage_error("unknown command '%s': expected run, relax, info, render or bench",
	                        cmd);
}
