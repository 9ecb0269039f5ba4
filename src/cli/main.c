/*
 * main.c - the `sandslide` command line (SPEC section 3): parse the
 * arguments, dispatch to the library, turn its status into the exit code
 * (0 success, 1 failure while running, 2 bad usage or bad input).
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sandslide/bench.h"
#include "sandslide/dem.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/relax.h"
#include "sandslide/render.h"
#include "sandslide/run.h"
#include "sandslide/snapshot.h"

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

static const char usage_run[] =
	"usage: sandslide run CASE.ini [-o OUT.h5] [--threads N] [--set SECTION.KEY=VALUE ...]\n"
	"       sandslide run --restart OUT.h5 [CASE.ini] [--threads N]\n"
	"\n"
	"  -o, --output OUT.h5   output file (default out/<case name>.h5; its folder\n"
	"                        must exist unless it is the default out/)\n"
	"  --force               replace OUT.h5 if it exists (else refused)\n"
	"  --restart OUT.h5      continue the run in OUT.h5 from its last snapshot,\n"
	"                        appending to it, with the case stored in it (a\n"
	"                        CASE.ini given too must be that case, and its\n"
	"                        files are found beside it); the snapshots are\n"
	"                        those of a run never interrupted\n"
	"  --threads N           OpenMP threads (default: all processors)\n"
	"  --set S.K=VALUE       override key K of section S of the case, e.g.\n"
	"                        --set model.closure=casson, --set 'source pour.rate=0.002'\n"
	"  --tile NXxNY          cells per tile of the sweep (default 256x128, smaller\n"
	"                        on small grids); results\n"
	"                        are the same bits for any tile size and thread count\n"
	"  --reference-kernel    use the plain two-pass sweep the fast one is tested\n"
	"                        against (same bits, several times slower)\n"
	"  --deflate N           HDF5 deflate level of /height, 0 (off, default) to 9\n"
	"  -q, --quiet           no progress line and no summary\n"
	"  --frames DIR          also draw each snapshot as it is written, to\n"
	"                        DIR/frame_00000.png, ... (shaded; the look options\n"
	"                        of `sandslide render --help` apply, e.g. --label)\n"
	"\n"
	"Writes OUT.h5 (SPEC section 5) and the XDMF sidecar OUT.xmf, flushed after\n"
	"every snapshot.  Ctrl-C (SIGINT) or SIGTERM finish the substep, write a\n"
	"snapshot and exit 130 or 143 naming the command that continues the run.\n"
	"Exit status: 0 done, 1 failure while running, 2 bad input.\n";

static const char usage_relax[] =
	"usage: sandslide relax DEM [-o OUT] [--angle DEG] [--closure NAME] [--nu V]\n"
	"                       [--tol X] [--max-time T] [--threads N] [...]\n"
	"\n"
	"Relaxes a digital elevation model to the repose angle: every slope steeper\n"
	"than it slides until the surface is steady, the volume conserved.\n"
	"\n"
	"  DEM                   .asc (ESRI ASCII grid), .png (16-bit greyscale),\n"
	"                        FILE.h5[:/dataset] (sandslide HDF5, last snapshot),\n"
	"                        .tif and other GDAL rasters (builds with GDAL)\n"
	"  -o, --output OUT      .asc, .png, .tif: the relaxed raster; .h5: the whole\n"
	"                        series with diagnostics (default out/<DEM>-relaxed\n"
	"                        with the input's extension)\n"
	"  --angle DEG           repose angle (default 35)\n"
	"  --closure NAME        " SS_CLOSURE_NAMES " (default coulomb)\n"
	"  --gamma G             herschel-bulkley exponent (default 1)\n"
	"  --nu V                m^2/s (default 1): sets the time scale only\n"
	"  --tol X               steady when max |dh/dt| < X m/s (default 1e-9)\n"
	"  --max-time T          stop at T s even if not steady (default: none)\n"
	"  --threads N           OpenMP threads (default: all processors)\n"
	"  --sides wall|open     the four sides of the DEM (default wall)\n"
	"  --nodata wall|open    cells without data (default open: sand leaves there)\n"
	"  --open-level M        height held on open cells and sides (default: the\n"
	"                        lowest height of the DEM)\n"
	"  --bedrock FILE        non-erodible base, a raster of the DEM's size: only\n"
	"                        the sand above it moves\n"
	"  --add-sand SHAPE      pour sand on rect=X0,Y0,X1,Y1 or disk=X,Y,R (m)\n"
	"  --sand-rate R         at R m/s (needed with --add-sand)\n"
	"  --sand-duration S     for S seconds from t = 0 (needed with --add-sand)\n"
	"  --dx M                cell size, for files that do not give one\n"
	"  --zscale Z            PNG: m per grey level (default: the file's range)\n"
	"  --zoffset Z0          PNG: height of grey 0, m (default 0)\n"
	"  --output-every T      .h5 output: a snapshot every T s\n"
	"  --report FILE.json    write the diagnostics for scripts\n"
	"  --force               replace OUT if it exists (else refused)\n"
	"  -q, --quiet           no progress line and no summary\n"
	"\n"
	"Prints cells and volume moved, steepest face before and after, steps and\n"
	"wall time.  The input is never modified; the output is written under a\n"
	"temporary name and renamed when complete.  Exit status: 0 done, 1\n"
	"failure while running, 2 bad input.\n";

static const char usage_info[] =
	"usage: sandslide info FILE.h5\n"
	"\n"
	"Prints the grid, model, cell counts and the diagnostics of every snapshot\n"
	"(first and last ten when there are more than twenty).\n";

static const char usage_render[] =
	"usage: sandslide render FILE.h5 [-o DIR] [--frames A:B:STEP | --time T] [options]\n"
	"       sandslide render --bench [N]\n"
	"\n"
	"Draws the snapshots of a sandslide output file as PNG pictures,\n"
	"DIR/frame_00000.png, frame_00001.png, ... in time order (SPEC section 6).\n"
	"\n"
	"  -o, --output DIR      folder of the frames (default frames/, created if\n"
	"                        missing)\n"
	"  --frames A:B:STEP     snapshots A, A+STEP, ... before B, as a Python slice\n"
	"                        (negative counts from the end; parts may be left out)\n"
	"  --time T              only the snapshot nearest T seconds\n"
	"  --video FILE.mp4      assemble the frames with ffmpeg (H.264, yuv420p) if it\n"
	"                        is on PATH; without it the frames are kept\n"
	"  --fps N               frames per second of the video (default 24)\n"
	"  --threads N           OpenMP threads (default: all processors)\n"
	"  -q, --quiet           no summary\n"
	"  --bench [N]           time the shaded style on an N x N grid (default 4096)\n"
	"\n"
	"The look of the frames (also for `sandslide run --frames`):\n"
	"  --style NAME          shaded (default): colour map x hillshade, 8-bit RGB;\n"
	"                        gray16: 16-bit grey heights, zmin..zmax in the PNG text;\n"
	"                        oblique: perspective view, walls as raised blocks\n"
	"  --cmap NAME           dune (default; perceptually uniform), terrain, gray\n"
	"  --zmin Z, --zmax Z    height scale, m (default: the lowest and highest sand\n"
	"                        of the whole file, so all frames share it)\n"
	"  --azimuth DEG         light from this compass bearing (default 315: north-west)\n"
	"  --altitude DEG        light above the horizon (default 45)\n"
	"  --zscale S            vertical exaggeration of shading and view (default 1)\n"
	"  --contour DZ          contour lines every DZ m (shaded)\n"
	"  --label               draw the simulated time on each frame\n"
	"  --colorbar            add a colour bar with the height scale\n"
	"  --max-size PX         at most PX pixels a side (cells are area-averaged)\n"
	"  --scale K             K pixels per cell (default 1 for gray16, otherwise\n"
	"                        enough for a side of 512 px)\n"
	"  --view-azimuth DEG    oblique: the camera's bearing from the centre (200)\n"
	"  --view-elevation DEG  oblique: the camera above the horizon (45)\n"
	"  --compression N       zlib level of the PNGs, 0 to 9 (default 6)\n"
	"\n"
	"Each PNG holds the time, the height scale and the snapshot in text chunks;\n"
	"a frame is written under a temporary name and renamed when complete.\n"
	"Exit status: 0 done, 1 failure while rendering, 2 bad input.\n";

static const char usage_bench[] =
	"usage: sandslide bench [--nx N] [--ny N] [--closure NAME|all] [--threads 1,2]\n"
	"                       [--surface NAME|all] [--repeats N] [--steps N] [--tile NXxNY]\n"
	"                       [--json]\n"
	"\n"
	"  --nx N, --ny N        grid size (default 8192 x 8192)\n"
	"  --closure NAME|all    coulomb, bingham, herschel-bulkley (gamma 0.5 and 2),\n"
	"                        casson, or all (default)\n"
	"  --threads LIST        thread counts, comma-separated (default 1,2)\n"
	"  --surface NAME|all    supercritical (every face slides), subcritical (none\n"
	"                        does), patch (a 512 x 512 ramp on a flat floor), all\n"
	"  --repeats N           timings per case (default 5); median, min and max\n"
	"  --steps N             steps per timing (default: about 0.3 s worth)\n"
	"  --tile NXxNY          tile size of the sweep (default 256x128)\n"
	"  --json                one JSON document instead of a table\n"
	"\n"
	"Also measures the memory bandwidth (read+write of one array) in the same run\n"
	"and reports the fraction of that roofline each case reaches.\n";

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

static int usage_error(const char *usage, const char *fmt, const char *arg)
{
	fflush(stdout);
	fputs("sandslide: ", stderr);
	fprintf(stderr, fmt, arg);
	fprintf(stderr, "\n\n%s", usage);
	return 2;
}

static int parse_int(const char *s, int lo, int hi, int *out)
{
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (end == s || *end || errno || v < lo || v > hi)
		return -1;
	*out = (int)v;
	return 0;
}

static int parse_double(const char *s, double *out)
{
	char *end;
	errno = 0;
	double v = s ? strtod(s, &end) : NAN;
	if (!s || end == s || *end || errno || !isfinite(v))
		return -1;
	*out = v;
	return 0;
}

/*
 * One option of the look of frames (`render`, and `run --frames`) at
 * argv[*k]: 1 if it was one (*k then points at its last word), 0 if not,
 * 2 after a usage error.  Ranges are checked by ss_render_options_check.
 */
static int parse_look_option(int argc, char **argv, int *k, struct ss_render_options *o,
                             const char *usage)
{
	const char *a = argv[*k], *next = *k + 1 < argc ? argv[*k + 1] : NULL;
	struct {
		const char *name;
		double *value;
	} const numbers[] = {
		{"--zmin", &o->zmin}, {"--zmax", &o->zmax}, {"--azimuth", &o->azimuth_deg},
		{"--altitude", &o->altitude_deg}, {"--zscale", &o->zscale},
		{"--contour", &o->contour}, {"--view-azimuth", &o->view_azimuth_deg},
		{"--view-elevation", &o->view_elevation_deg},
	};
	for (size_t n = 0; n < sizeof numbers / sizeof numbers[0]; n++) {
		if (strcmp(a, numbers[n].name))
			continue;
		if (parse_double(next, numbers[n].value))
			return usage_error(usage, "%s needs a finite number", a);
		++*k;
		return 1;
	}
	if (!strcmp(a, "--label")) {
		o->label = 1;
	} else if (!strcmp(a, "--colorbar")) {
		o->colorbar = 1;
	} else if (!strcmp(a, "--style")) {
		if (!next || ss_render_style_parse(next, &o->style))
			return usage_error(usage, "--style '%s': expected " SS_RENDER_STYLE_NAMES,
			                   next ? next : "");
		++*k;
	} else if (!strcmp(a, "--cmap")) {
		if (!next || ss_render_cmap_parse(next, &o->cmap))
			return usage_error(usage, "--cmap '%s': expected " SS_RENDER_CMAP_NAMES,
			                   next ? next : "");
		++*k;
	} else if (!strcmp(a, "--max-size")) {
		if (!next || parse_int(next, 8, 65536, &o->max_size))
			return usage_error(usage, "--max-size '%s': expected 8 to 65536 px",
			                   next ? next : "");
		++*k;
	} else if (!strcmp(a, "--scale")) {
		if (!next || parse_int(next, 1, 100, &o->scale))
			return usage_error(usage, "--scale '%s': expected 1 to 100 px per cell",
			                   next ? next : "");
		++*k;
	} else if (!strcmp(a, "--compression")) {
		if (!next || parse_int(next, 0, 9, &o->compression))
			return usage_error(usage, "--compression '%s': expected 0 to 9",
			                   next ? next : "");
		++*k;
	} else {
		return 0;
	}
	return 1;
}

/* The command line as one string, for the history attribute. */
static char *join_args(int argc, char **argv)
{
	size_t n = 1;
	for (int k = 0; k < argc; k++)
		n += strlen(argv[k]) + 1;
	char *s = malloc(n);
	if (!s)
		return NULL;
	s[0] = '\0';
	for (int k = 0; k < argc; k++) {
		if (k)
			strcat(s, " ");
		strcat(s, argv[k]);
	}
	return s;
}

/* "NXxNY" into two positive ints; -1 if malformed. */
static int parse_tile(const char *s, int *tx, int *ty)
{
	const char *x = s ? strchr(s, 'x') : NULL;
	char buf[32];
	if (!x || x - s >= (ptrdiff_t)sizeof buf)
		return -1;
	snprintf(buf, sizeof buf, "%.*s", (int)(x - s), s);
	return parse_int(buf, 1, 1 << 20, tx) || parse_int(x + 1, 1, 1 << 20, ty) ? -1 : 0;
}

static int add_bench_closure(struct ss_bench_options *o, enum ss_closure_kind kind,
                             double gamma)
{
	struct ss_bench_closure *c = &o->closures[o->closure_count++];
	c->kind = kind;
	c->gamma = gamma;
	if (kind == SS_CLOSURE_HERSCHEL_BULKLEY)
		snprintf(c->label, sizeof c->label, "herschel-bulkley(%g)", gamma);
	else
		snprintf(c->label, sizeof c->label, "%s", ss_closure_name(kind));
	return 0;
}

static int cmd_bench(int argc, char **argv)
{
	struct ss_bench_options o = {0};
	const char *closure = "all", *surface = "all", *threads = "1,2";
	o.nx = o.ny = 8192;
	o.repeats = 5;
	for (int k = 2; k < argc; k++) {
		const char *a = argv[k], *next = k + 1 < argc ? argv[k + 1] : NULL;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			fputs(usage_bench, stdout);
			return 0;
		} else if (!strcmp(a, "--json")) {
			o.json = 1;
		} else if (!strcmp(a, "--nx") || !strcmp(a, "--ny")) {
			if (!next || parse_int(next, 1, 1 << 20, a[3] == 'x' ? &o.nx : &o.ny))
				return usage_error(usage_bench, "%s: expected a cell count from 1 to "
				                   "1048576", a);
			k++;
		} else if (!strcmp(a, "--repeats")) {
			if (!next || parse_int(next, 1, 64, &o.repeats))
				return usage_error(usage_bench, "--repeats '%s': expected 1 to 64",
				                   next ? next : "");
			k++;
		} else if (!strcmp(a, "--steps")) {
			if (!next || parse_int(next, 1, 1000000, &o.steps))
				return usage_error(usage_bench, "--steps '%s': expected 1 to 1000000",
				                   next ? next : "");
			k++;
		} else if (!strcmp(a, "--tile")) {
			if (!next || parse_tile(next, &o.tile_nx, &o.tile_ny))
				return usage_error(usage_bench, "--tile '%s': expected NXxNY, e.g. 256x64",
				                   next ? next : "");
			k++;
		} else if (!strcmp(a, "--closure") && next) {
			closure = argv[++k];
		} else if (!strcmp(a, "--surface") && next) {
			surface = argv[++k];
		} else if (!strcmp(a, "--threads") && next) {
			threads = argv[++k];
		} else {
			return usage_error(usage_bench, "unknown option or missing value: '%s'", a);
		}
	}

	enum ss_closure_kind kind;
	if (!strcmp(closure, "all")) {
		add_bench_closure(&o, SS_CLOSURE_COULOMB, 1.0);
		add_bench_closure(&o, SS_CLOSURE_BINGHAM, 1.0);
		add_bench_closure(&o, SS_CLOSURE_HERSCHEL_BULKLEY, 0.5);
		add_bench_closure(&o, SS_CLOSURE_HERSCHEL_BULKLEY, 2.0);
		add_bench_closure(&o, SS_CLOSURE_CASSON, 1.0);
	} else if (!strcmp(closure, "herschel-bulkley")) {
		add_bench_closure(&o, SS_CLOSURE_HERSCHEL_BULKLEY, 0.5);
		add_bench_closure(&o, SS_CLOSURE_HERSCHEL_BULKLEY, 2.0);
	} else if (ss_closure_parse(closure, &kind) == 0) {
		add_bench_closure(&o, kind, 1.0);
	} else {
		return usage_error(usage_bench, "--closure '%s': expected all, "
		                   SS_CLOSURE_NAMES, closure);
	}

	int matched = 0;
	for (int s = 0; s < SS_BENCH_SURFACES; s++) {
		o.surfaces[s] = !strcmp(surface, "all") ||
		                !strcmp(surface, ss_bench_surface_name((enum ss_bench_surface)s));
		matched |= o.surfaces[s];
	}
	if (!matched)
		return usage_error(usage_bench, "--surface '%s': expected all, supercritical, "
		                   "subcritical or patch", surface);

	for (const char *p = threads; *p;) {
		char buf[16];
		size_t len = strcspn(p, ",");
		if (len == 0 || len >= sizeof buf || o.thread_count == SS_BENCH_MAX_CASES)
			return usage_error(usage_bench, "--threads '%s': expected a list such as "
			                   "1,2 (at most 8 entries)", threads);
		memcpy(buf, p, len);
		buf[len] = '\0';
		if (parse_int(buf, 1, 4096, &o.threads[o.thread_count++]))
			return usage_error(usage_bench, "--threads '%s': expected a list such as "
			                   "1,2 (at most 8 entries)", threads);
		p += len + (p[len] == ',');
	}
	return ss_status_exit_code(ss_bench_run(&o));
}

static int cmd_render(int argc, char **argv)
{
	struct ss_render_series_options o = {0};
	ss_render_options_default(&o.look);
	o.output_dir = "frames";
	o.time = NAN;
	o.fps = 24;
	int threads = 0, bench = 0, bench_n = 4096;

	for (int k = 2; k < argc; k++) {
		const char *a = argv[k], *next = k + 1 < argc ? argv[k + 1] : NULL;
		const int look = parse_look_option(argc, argv, &k, &o.look, usage_render);
		if (look == 2)
			return 2;
		if (look)
			continue;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			fputs(usage_render, stdout);
			return 0;
		} else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
			if (!next || !*next)
				return usage_error(usage_render, "%s needs a folder", a);
			o.output_dir = argv[++k];
		} else if (!strcmp(a, "--frames")) {
			if (!next)
				return usage_error(usage_render, "%s needs A:B:STEP", a);
			o.frames = argv[++k];
		} else if (!strcmp(a, "--time")) {
			if (parse_double(next, &o.time))
				return usage_error(usage_render, "--time '%s': expected a time in s",
				                   next ? next : "");
			k++;
		} else if (!strcmp(a, "--video")) {
			if (!next || !*next)
				return usage_error(usage_render, "%s needs a file name", a);
			o.video = argv[++k];
		} else if (!strcmp(a, "--fps")) {
			if (!next || parse_int(next, 1, 240, &o.fps))
				return usage_error(usage_render, "--fps '%s': expected 1 to 240",
				                   next ? next : "");
			k++;
		} else if (!strcmp(a, "--threads")) {
			if (!next || parse_int(next, 1, 4096, &threads))
				return usage_error(usage_render, "--threads '%s': expected an integer "
				                   "from 1 to 4096", next ? next : "");
			k++;
		} else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
			o.quiet = 1;
		} else if (!strcmp(a, "--bench")) {
			bench = 1;
			if (next && parse_int(next, 16, 32768, &bench_n) == 0)
				k++;
		} else if (a[0] == '-' && a[1]) {
			return usage_error(usage_render, "unknown option '%s'", a);
		} else if (o.input) {
			return usage_error(usage_render, "one file only (got a second: '%s')", a);
		} else {
			o.input = a;
		}
	}
	ss_parallel_set_threads(threads > 0 ? threads : ss_parallel_processors());
	if (bench)
		return ss_status_exit_code(ss_render_bench(bench_n, 5));
	if (!o.input)
		return usage_error(usage_render, "%s", "render needs a sandslide output file");
	return ss_status_exit_code(ss_render_series(&o));
}

/* `run --frames`: render each snapshot the run reports. */
static int render_run_snapshot(void *context, const struct ss_run_snapshot *s)
{
	const struct ss_render_frames_bounds b = {s->source_rise, s->open_level,
	                                          s->any_open_side};
	return ss_render_frames_add(context, s->path, s->index, &b);
}

static int cmd_run(int argc, char **argv)
{
	struct ss_run_options o = {0};
	const char **overrides = calloc((size_t)argc, sizeof *overrides);
	if (!overrides)
		return ss_status_exit_code(ss_error_fail("out of memory"));
	int status = 2;
	const char *frames_dir = NULL, *look_option = NULL;
	struct ss_render_options look;
	ss_render_options_default(&look);
	struct ss_render_frames *frames = NULL;

	for (int k = 2; k < argc; k++) {
		const char *a = argv[k];
		const char *next = k + 1 < argc ? argv[k + 1] : NULL;
		const int is_look = parse_look_option(argc, argv, &k, &look, usage_run);
		if (is_look == 2)
			goto out;
		if (is_look) {
			look_option = a;
			continue;
		}
		if (!strcmp(a, "--frames")) {
			if (!next || !*next) {
				status = usage_error(usage_run, "%s needs a folder", a);
				goto out;
			}
			frames_dir = argv[++k];
		} else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			fputs(usage_run, stdout);
			status = 0;
			goto out;
		} else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
			if (!next) {
				status = usage_error(usage_run, "%s needs a file name", a);
				goto out;
			}
			o.output = argv[++k];
		} else if (!strcmp(a, "--threads")) {
			if (!next || parse_int(next, 1, 4096, &o.threads)) {
				status = usage_error(usage_run, "--threads '%s': expected an integer "
				                     "from 1 to 4096", next ? next : "");
				goto out;
			}
			k++;
		} else if (!strcmp(a, "--set") || !strcmp(a, "-P")) {
			if (!next) {
				status = usage_error(usage_run, "%s needs SECTION.KEY=VALUE", a);
				goto out;
			}
			overrides[o.override_count++] = argv[++k];
		} else if (!strncmp(a, "--set=", 6)) {
			overrides[o.override_count++] = a + 6;
		} else if (!strcmp(a, "--tile")) {
			if (!next || parse_tile(next, &o.tile_nx, &o.tile_ny)) {
				status = usage_error(usage_run, "--tile '%s': expected NXxNY, e.g. 256x64",
				                     next ? next : "");
				goto out;
			}
			k++;
		} else if (!strcmp(a, "--deflate")) {
			if (!next || parse_int(next, 0, 9, &o.deflate)) {
				status = usage_error(usage_run, "--deflate '%s': expected 0 to 9",
				                     next ? next : "");
				goto out;
			}
			k++;
		} else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
			o.quiet = 1;
		} else if (!strcmp(a, "--reference-kernel")) {
			o.reference_kernel = 1;
		} else if (!strcmp(a, "--force")) {
			o.force = 1;
		} else if (!strcmp(a, "--restart")) {
			if (!next) {
				status = usage_error(usage_run, "%s needs the output file to continue", a);
				goto out;
			}
			o.restart = argv[++k];
		} else if (a[0] == '-' && a[1]) {
			status = usage_error(usage_run, "unknown option '%s'", a);
			goto out;
		} else if (o.case_path) {
			status = usage_error(usage_run, "one case file only (got a second: '%s')", a);
			goto out;
		} else {
			o.case_path = a;
		}
	}
	if (!o.case_path && !o.restart) {
		status = usage_error(usage_run, "%s", "run needs a case file (or --restart OUT.h5)");
		goto out;
	}
	if (look_option && !frames_dir) {
		status = usage_error(usage_run, "%s sets the look of frames: it needs --frames DIR",
		                     look_option);
		goto out;
	}
	if (frames_dir) {
		if ((status = ss_status_exit_code(ss_render_frames_create(&frames, frames_dir, &look))))
			goto out;
		o.on_snapshot = render_run_snapshot;
		o.snapshot_context = frames;
	}
	o.overrides = overrides;
	char *history = join_args(argc, argv);
	o.history = history;
	o.stop_signal = &stop_signal;
	install_signal_handlers();
	status = ss_status_exit_code(ss_run_case(&o));
	if (status == 0 && stop_signal)
		status = 128 + stop_signal;
	free(history);
	if (frames && !o.quiet)
		printf("wrote %lld frames to %s%s\n", ss_render_frames_count(frames), frames_dir,
		       frames_dir[strlen(frames_dir) - 1] == '/' ? "" : "/");
out:
	ss_render_frames_destroy(frames);
	free(overrides);
	return status;
}

/* A number in [lo, hi]; -1 if malformed. */
static int parse_real(const char *s, double lo, double hi, double *out)
{
	double v;
	if (parse_double(s, &v) || !(v >= lo && v <= hi))
		return -1;
	*out = v;
	return 0;
}

/* rect=X0,Y0,X1,Y1 or disk=X,Y,R into a shape; -1 if malformed. */
static int parse_sand_shape(const char *s, struct ss_shape *shape)
{
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

static int cmd_relax(int argc, char **argv)
{
	struct ss_relax_options o;
	ss_relax_options_init(&o);
	int have_rate = 0, have_duration = 0;
	for (int k = 2; k < argc; k++) {
		const char *a = argv[k], *next = k + 1 < argc ? argv[k + 1] : NULL;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			fputs(usage_relax, stdout);
			return 0;
		} else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
			o.quiet = 1;
			continue;
		} else if (!strcmp(a, "--force")) {
			o.force = 1;
			continue;
		} else if (a[0] != '-' || !a[1]) {
			if (o.dem)
				return usage_error(usage_relax, "one DEM only (got a second: '%s')", a);
			o.dem = a;
			continue;
		}
		if (!next)
			return usage_error(usage_relax, "%s needs a value", a);
		k++;
		if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
			o.output = next;
		} else if (!strcmp(a, "--angle")) {
			if (parse_real(next, 1e-9, 90.0 - 1e-9, &o.angle_deg))
				return usage_error(usage_relax, "--angle '%s': expected degrees in "
				                   "(0, 90)", next);
		} else if (!strcmp(a, "--closure")) {
			if (ss_closure_parse(next, &o.closure))
				return usage_error(usage_relax, "--closure '%s': expected "
				                   SS_CLOSURE_NAMES, next);
		} else if (!strcmp(a, "--gamma")) {
			if (parse_real(next, 1e-6, 1e6, &o.gamma))
				return usage_error(usage_relax, "--gamma '%s': expected a number > 0",
				                   next);
		} else if (!strcmp(a, "--nu")) {
			if (parse_real(next, 1e-300, 1e300, &o.nu))
				return usage_error(usage_relax, "--nu '%s': expected m^2/s > 0", next);
		} else if (!strcmp(a, "--tol")) {
			if (parse_real(next, 1e-300, 1e300, &o.tol))
				return usage_error(usage_relax, "--tol '%s': expected m/s > 0", next);
		} else if (!strcmp(a, "--max-time")) {
			if (parse_real(next, 1e-300, 1e300, &o.max_time))
				return usage_error(usage_relax, "--max-time '%s': expected s > 0", next);
		} else if (!strcmp(a, "--output-every")) {
			if (parse_real(next, 1e-300, 1e300, &o.output_every))
				return usage_error(usage_relax, "--output-every '%s': expected s > 0",
				                   next);
		} else if (!strcmp(a, "--cfl")) {
			if (parse_real(next, 1e-9, 1.0, &o.cfl))
				return usage_error(usage_relax, "--cfl '%s': expected (0, 1]", next);
		} else if (!strcmp(a, "--threads")) {
			if (parse_int(next, 1, 4096, &o.threads))
				return usage_error(usage_relax, "--threads '%s': expected an integer "
				                   "from 1 to 4096", next);
		} else if (!strcmp(a, "--sides")) {
			if (strcmp(next, "wall") && strcmp(next, "open"))
				return usage_error(usage_relax, "--sides '%s': expected wall or open",
				                   next);
			o.sides = !strcmp(next, "wall") ? SS_SIDE_WALL : SS_SIDE_OPEN;
		} else if (!strcmp(a, "--nodata")) {
			if (strcmp(next, "wall") && strcmp(next, "open"))
				return usage_error(usage_relax, "--nodata '%s': expected wall or open",
				                   next);
			o.nodata_type = !strcmp(next, "wall") ? SS_CELL_WALL : SS_CELL_OPEN;
		} else if (!strcmp(a, "--open-level")) {
			if (parse_real(next, -1e300, 1e300, &o.open_level))
				return usage_error(usage_relax, "--open-level '%s': expected a height "
				                   "in m", next);
		} else if (!strcmp(a, "--bedrock")) {
			o.bedrock = next;
		} else if (!strcmp(a, "--add-sand")) {
			if (parse_sand_shape(next, &o.sand_shape))
				return usage_error(usage_relax, "--add-sand '%s': expected "
				                   "rect=X0,Y0,X1,Y1 (X0 < X1, Y0 < Y1) or disk=X,Y,R "
				                   "(R > 0), in m", next);
			o.add_sand = 1;
		} else if (!strcmp(a, "--sand-rate")) {
			if (parse_real(next, 1e-300, 1e300, &o.sand_rate))
				return usage_error(usage_relax, "--sand-rate '%s': expected m/s > 0",
				                   next);
			have_rate = 1;
		} else if (!strcmp(a, "--sand-duration")) {
			if (parse_real(next, 1e-300, 1e300, &o.sand_duration))
				return usage_error(usage_relax, "--sand-duration '%s': expected s > 0",
				                   next);
			have_duration = 1;
		} else if (!strcmp(a, "--dx")) {
			if (parse_real(next, 1e-300, 1e300, &o.read.cellsize))
				return usage_error(usage_relax, "--dx '%s': expected m > 0", next);
		} else if (!strcmp(a, "--zscale")) {
			if (parse_real(next, 1e-300, 1e300, &o.read.zscale))
				return usage_error(usage_relax, "--zscale '%s': expected m per grey "
				                   "level > 0", next);
		} else if (!strcmp(a, "--zoffset")) {
			if (parse_real(next, -1e300, 1e300, &o.read.zoffset))
				return usage_error(usage_relax, "--zoffset '%s': expected m", next);
		} else if (!strcmp(a, "--report")) {
			o.report = next;
		} else {
			return usage_error(usage_relax, "unknown option '%s'", a);
		}
	}
	if (!o.dem)
		return usage_error(usage_relax, "%s", "relax needs a DEM");
	if (o.add_sand != (have_rate && have_duration) || (!o.add_sand && (have_rate || have_duration)))
		return usage_error(usage_relax, "%s", "--add-sand, --sand-rate and "
		                   "--sand-duration go together");
	if (!isnan(o.read.zoffset) && isnan(o.read.zscale))
		return usage_error(usage_relax, "%s", "--zoffset needs --zscale");
	char *history = join_args(argc, argv);
	o.history = history;
	struct ss_relax_report report;
	o.stop_signal = &stop_signal;
	install_signal_handlers();
	int status = ss_status_exit_code(ss_relax_run(&o, &report));
	if (status == 0 && stop_signal)
		status = 128 + stop_signal;
	free(history);
	return status;
}

static void print_diag_row(const struct ss_snapshot_summary *s, long long k)
{
	const struct ss_diagnostics *d = &s->diag[k];
	printf("  %5lld %12.6g %13.6e %11.4e %11.4e %10.5g %9.4f %9.0f %7.3f %9.3f\n", k,
	       s->time[k], d->volume, d->inflow, d->outflow, d->max_height, d->max_slope_deg,
	       d->steps, d->active_fraction, d->wall_seconds);
}

static int cmd_info(int argc, char **argv)
{
	const char *path = NULL;
	for (int k = 2; k < argc; k++) {
		if (!strcmp(argv[k], "-h") || !strcmp(argv[k], "--help")) {
			fputs(usage_info, stdout);
			return 0;
		}
		if (argv[k][0] == '-' && argv[k][1])
			return usage_error(usage_info, "unknown option '%s'", argv[k]);
		if (path)
			return usage_error(usage_info, "one file only (got a second: '%s')", argv[k]);
		path = argv[k];
	}
	if (!path)
		return usage_error(usage_info, "%s", "info needs a file");

	struct ss_snapshot_summary s;
	int err = ss_snapshot_read_summary(path, &s);
	if (err)
		return ss_status_exit_code(err);
	printf("file       %s (%s)\n", path, s.source);
	printf("title      %s\n", s.title);
	printf("grid       %d x %d cells, dx = %g m, dy = %g m, lower-left corner (%g, %g) m\n",
	       s.nx, s.ny, s.dx, s.dy, s.origin_x, s.origin_y);
	printf("cells      %lld flow, %lld wall, %lld open\n", s.flow_cells, s.wall_cells,
	       s.open_cells);
	printf("model      %s, repose angle %g deg, nu = %g m^2/s", s.closure,
	       s.repose_angle_deg, s.nu);
	if (!strcmp(s.closure, "herschel-bulkley"))
		printf(", gamma = %g", s.gamma);
	printf("\n");
	if (s.count == 0) {
		printf("snapshots  none\n");
	} else {
		printf("snapshots  %lld, t = %g .. %g s\n", s.count, s.time[0], s.time[s.count - 1]);
		printf("  %5s %12s %13s %11s %11s %10s %9s %9s %7s %9s\n", "index", "time_s",
		       "volume_m3", "inflow_m3", "outflow_m3", "max_h_m", "slope_deg", "steps",
		       "active", "wall_s");
		for (long long k = 0; k < s.count; k++) {
			if (s.count > 20 && k == 10) {
				printf("  %5s (%lld more)\n", "...", s.count - 20);
				k = s.count - 10;
			}
			print_diag_row(&s, k);
		}
		const struct ss_diagnostics *first = &s.diag[0], *last = &s.diag[s.count - 1];
		const double balance = (last->volume - first->volume) - (last->inflow - last->outflow);
		const double scale = fmax(fmax(fabs(last->volume), fabs(first->volume)),
		                          fmax(last->inflow, last->outflow));
		printf("volume balance  (V_last - V_0) - (inflow - outflow) = %.3e m^3 "
		       "(%.2e relative)\n", balance, scale > 0 ? fabs(balance) / scale : 0.0);
	}
	ss_snapshot_summary_release(&s);
	return 0;
}

int main(int argc, char **argv)
{
	ss_snapshot_library_init();
	if (argc < 2)
		return usage_error(usage_main, "%s", "no command given");
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
	if (!strcmp(cmd, "run"))
		return cmd_run(argc, argv);
	if (!strcmp(cmd, "info"))
		return cmd_info(argc, argv);
	if (!strcmp(cmd, "bench"))
		return cmd_bench(argc, argv);
	if (!strcmp(cmd, "render"))
		return cmd_render(argc, argv);
	if (!strcmp(cmd, "relax"))
		return cmd_relax(argc, argv);
	return usage_error(usage_main, "unknown command '%s': expected run, relax, info, "
	                   "render or bench", cmd);
}
