/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * options.c - render's options (render.h): the table of the look of frames
 * (also run --frames's) and the table of `sandslide render`, which the
 * command line's parser and help read.
 */
#include "sandslide/render.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

static int parse_style(const char *value, void *field)
{
	return ss_render_style_parse(value, field);
}

static int parse_cmap(const char *value, void *field)
{
	return ss_render_cmap_parse(value, field);
}

#define LOOK(m) offsetof(struct ss_render_options, m)
/* Any finite number: ss_render_options_check says what a look accepts. */
#define NUMBER(n, v, m, d, h)                                                      \
	{.name = n, .value_name = v, .kind = SS_OPTION_REAL, .offset = LOOK(m),      \
	 .default_value = d, .lo = -INFINITY, .hi = INFINITY,                         \
	 .expected = "a finite number", .help = h}

static const struct ss_option look[] = {
	{.help = "The look of the frames (also for `sandslide run --frames`):\n"},
	{.name = "style", .value_name = "NAME", .kind = SS_OPTION_WORD, .offset = LOOK(style),
	 .default_value = "shaded", .parse = parse_style, .expected = SS_RENDER_STYLE_NAMES,
	 .help = "shaded: colour map x hillshade, 8-bit RGB;\n"
	         "gray16: 16-bit grey heights, zmin..zmax in the PNG text;\n"
	         "oblique: perspective view, walls as raised blocks"},
	{.name = "cmap", .value_name = "NAME", .kind = SS_OPTION_WORD, .offset = LOOK(cmap),
	 .default_value = "dune", .parse = parse_cmap, .expected = SS_RENDER_CMAP_NAMES,
	 .help = "dune (perceptually uniform), terrain, gray"},
	NUMBER("zmin", "Z", zmin, NULL, "bottom of the height scale, m (default: the lowest\n"
	                                "sand of the whole file, so all frames share it)"),
	NUMBER("zmax", "Z", zmax, NULL, "top of the height scale, m (default: the highest sand)"),
	NUMBER("azimuth", "DEG", azimuth_deg, "315",
	       "light from this compass bearing (315: north-west)"),
	NUMBER("altitude", "DEG", altitude_deg, "45", "light above the horizon"),
	NUMBER("zscale", "S", zscale, "1", "vertical exaggeration of shading and of the oblique\n"
	                                   "view"),
	NUMBER("contour", "DZ", contour, "0", "contour lines every DZ m (shaded; 0: none)"),
	{.name = "label", .kind = SS_OPTION_FLAG, .offset = LOOK(label), .expected = "1 or 0",
	 .help = "the simulated time in a strip above each frame"},
	{.name = "colorbar", .kind = SS_OPTION_FLAG, .offset = LOOK(colorbar),
	 .expected = "1 or 0", .help = "add a colour bar with the height scale"},
	{.name = "max-size", .value_name = "PX", .kind = SS_OPTION_INT, .offset = LOOK(max_size),
	 .lo = 8, .hi = 65536, .expected = "8 to 65536 px",
	 .help = "at most PX pixels a side (cells are area-averaged)"},
	{.name = "scale", .value_name = "K", .kind = SS_OPTION_INT, .offset = LOOK(scale), .lo = 1,
	 .hi = 100, .expected = "1 to 100 px per cell",
	 .help = "K pixels per cell (default 1 for gray16, otherwise\n"
	         "enough for a side of 512 px)"},
	NUMBER("view-azimuth", "DEG", view_azimuth_deg, NULL,
	       "oblique: the camera's bearing from the centre (default:\n"
	       "from the open side, away from the walls)"),
	NUMBER("view-elevation", "DEG", view_elevation_deg, "55",
	       "oblique: the camera above the horizon"),
	{.name = "compression", .value_name = "N", .kind = SS_OPTION_INT,
	 .offset = LOOK(compression), .default_value = "6", .lo = 0, .hi = 9, .expected = "0 to 9",
	 .help = "zlib level of the PNGs, 0 to 9"},
};

const struct ss_option_table ss_render_look_option_table = {
	.command = "render", .options = look, .count = sizeof look / sizeof *look,
};

void ss_render_options_default(struct ss_render_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_render_look_option_table, o);
}

#define AT(m) offsetof(struct ss_render_series_options, m)

static const struct ss_option series[] = {
	{.name = "input", .kind = SS_OPTION_TEXT, .offset = AT(input),
	 .flags = SS_OPTION_NAMED_ONLY, .expected = "a path",
	 .help = "the sandslide file (the command line's argument)"},
	{.name = "output", .alias = "-o", .value_name = "DIR", .kind = SS_OPTION_TEXT,
	 .offset = AT(output_dir), .default_value = "frames", .expected = "a folder",
	 .help = "folder of the frames (created if missing; none\n"
	         "for --html or --video alone)"},
	{.name = "frames", .value_name = "A:B:STEP", .kind = SS_OPTION_TEXT, .offset = AT(frames),
	 .expected = "A:B:STEP or A",
	 .help = "snapshots A, A+STEP, ... before B, a Python slice\n"
	         "(negative counts from the end; parts may be left out;\n"
	         "bounds clamped; ::-1 reverses), or one index A"},
	{.name = "time", .value_name = "T", .kind = SS_OPTION_REAL, .offset = AT(time),
	 .lo = -INFINITY, .hi = INFINITY, .expected = "a time in s",
	 .help = "only the snapshot nearest T seconds"},
	{.name = "video", .value_name = "FILE.mp4", .kind = SS_OPTION_TEXT, .offset = AT(video),
	 .expected = "a path",
	 .help = "assemble the frames with ffmpeg (H.264, yuv420p); with\n"
	         "-o the frames are kept (also when ffmpeg is missing)"},
	/* no default: 0 in the options, chosen from the number of frames */
	{.name = "fps", .value_name = "N", .kind = SS_OPTION_INT, .offset = AT(fps),
	 .lo = 1, .hi = 240, .expected = "1 to 240",
	 .help = "frames per second of the video, and the speed the\n"
	         "viewer starts at (default: a quarter of the frames,\n"
	         "1 to 24, so a video lasts 4 s or more: 21 frames at 5)"},
	{.name = "html", .value_name = "FILE.html", .kind = SS_OPTION_TEXT, .offset = AT(html),
	 .expected = "a path",
	 .help = "write a self-contained viewer (frames, slider, play,\n"
	         "height under the mouse) to FILE.html; without -o,\n"
	         "no frame folder is written"},
};

static const struct ss_option_part parts[] = {
	{&ss_job_option_table, AT(job)}, {&ss_render_look_option_table, AT(look)},
};

const struct ss_option_table ss_render_option_table = {
	.command = "render", .options = series, .count = sizeof series / sizeof *series,
	.parts = parts, .part_count = 2,
};

void ss_render_series_options_init(struct ss_render_series_options *o)
{
	memset(o, 0, sizeof *o);
	ss_option_defaults(&ss_render_option_table, o);
}
