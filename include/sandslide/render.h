/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * render.h - pictures of snapshots (doc/rendering.md): PNG heightmaps, frame
 * sequences and videos.  The code is in render/; `sandslide render` and
 * `sandslide run --frames` reach it.  The numerical kernel knows nothing of
 * it: the renderer reads the HDF5 output (doc/output.md) itself.
 *
 * A frame is made in three steps, each its own function:
 *
 *   1. resample   the cells (nx x ny, dx x dy) onto the picture's pixels:
 *                 area averaging when the picture is smaller than the grid
 *                 (--max-size), bilinear between cell centres when it is
 *                 larger (small grids are drawn at K pixels per cell); wall
 *                 cells and cells without data never enter an average.
 *   2. colour     shaded:  colour map of height x hillshade (Horn's method),
 *                          walls dark, open cells light, optional contours;
 *                 gray16:  16-bit grey, linear between zmin and zmax;
 *                 oblique: a perspective view, z-buffered triangles, walls
 *                          as raised blocks.
 *                 Cells without data (SS_RENDER_CELL_NODATA) are absent in
 *                 every style: the background (white) in shaded and
 *                 oblique, transparent in gray16, as if the grid ended
 *                 there; a wall side of the grid with no data all along it
 *                 is not drawn either.
 *                 Then the optional time label and colour bar.
 *   3. encode     libpng, to a temporary name renamed into place, with the
 *                 time, the height scale and the snapshot in text chunks.
 *
 * Rows are split between OpenMP threads within a frame, or frames between
 * threads in a series of small frames; the bits are the same either way.
 */
#ifndef SANDSLIDE_RENDER_H
#define SANDSLIDE_RENDER_H

#include <stddef.h>
#include <stdint.h>
#include "sandslide/job.h"
#include "sandslide/option.h"

enum ss_render_style {
	SS_RENDER_SHADED,   /* colour map x hillshade, 8-bit RGB */
	SS_RENDER_GRAY16,   /* 16-bit grey heights, for data */
	SS_RENDER_OBLIQUE,  /* perspective view, 8-bit RGB */
};

enum ss_render_cmap {
	SS_RENDER_CMAP_DUNE,     /* perceptually uniform (CIELAB lightness linear),
	                          * violet - teal - green - yellow, like viridis */
	SS_RENDER_CMAP_TERRAIN,  /* blue - green - sand - brown - white */
	SS_RENDER_CMAP_GRAY,     /* black to white */
};

/* A cell_type (struct ss_render_field) of a cell without data, such as
 * the nodata cells of a DEM: /cell_type 3 of a sandslide file
 * (SS_SNAPSHOT_CELL_NODATA, snapshot.h). */
#define SS_RENDER_CELL_NODATA 3

/* Colours of the shaded style for cells that are not sand, and for
 * heights that are not numbers (R, G, B). */
#define SS_RENDER_WALL_RGB   0x2b, 0x2b, 0x30   /* dark slate */
#define SS_RENDER_OPEN_RGB   0xc4, 0xdc, 0xf0   /* pale sky blue */
#define SS_RENDER_NODATA_RGB 0xff, 0x00, 0xff   /* magenta */

/* How frames look.  ss_render_options_default() sets every field. */
struct ss_render_options {
	enum ss_render_style style;
	enum ss_render_cmap cmap;
	double zmin, zmax;          /* m, the height scale; NAN: from the data */
	double azimuth_deg;         /* light comes from, clockwise from north (315) */
	double altitude_deg;        /* light above the horizon, (0, 90] (45) */
	double zscale;              /* vertical exaggeration of shading and view (1) */
	double contour;             /* m between contour lines; 0: none */
	int label;                  /* draw "t = ... s" on the picture */
	int colorbar;               /* add a colour bar with the scale on the right */
	int max_size;               /* longest side at most this many px; 0: no cap */
	int scale;                  /* px per cell; 0: 1 for gray16, otherwise the
	                             * smallest giving a side of at least 512 px */
	double view_azimuth_deg;    /* oblique: camera's compass bearing from the
	                             * centre of the grid; NAN (default): from the
	                             * open side, away from the walls */
	double view_elevation_deg;  /* oblique: camera above the horizon, (0, 90) (55) */
	int compression;            /* zlib level of the PNG, 0..9 (6) */
};

/* The look's options (option.h): the command line's parser and help read
 * them; also run --frames's. */
extern const struct ss_option_table ss_render_look_option_table;

/* Every field at the table's default. */
void ss_render_options_default(struct ss_render_options *o);

/* SS_ERR_INPUT (with a message naming the option) for values out of range,
 * zmin >= zmax when both are given, or label/colorbar with gray16. */
int ss_render_options_check(const struct ss_render_options *o);

/* Names of styles and colour maps, and parsing them (0, or -1 if unknown). */
const char *ss_render_style_name(enum ss_render_style s);
int ss_render_style_parse(const char *name, enum ss_render_style *s);
const char *ss_render_cmap_name(enum ss_render_cmap c);
int ss_render_cmap_parse(const char *name, enum ss_render_cmap *c);
#define SS_RENDER_STYLE_NAMES "shaded, gray16, oblique"
#define SS_RENDER_CMAP_NAMES "dune, terrain, gray"

/* The 256-entry RGB table of a colour map, index 0 at zmin. */
void ss_render_cmap_table(enum ss_render_cmap c, uint8_t table[256][3]);

/* One snapshot in memory. */
struct ss_render_field {
	int nx, ny;                 /* cells */
	double dx, dy;              /* cell size, m */
	ptrdiff_t stride;           /* elements between rows, >= nx */
	const double *height;       /* m: cell (i, j) at height[j * stride + i],
	                             * i west to east, j = 0 the south row */
	const uint8_t *cell_type;   /* enum ss_cell_type (grid.h) or
	                             * SS_RENDER_CELL_NODATA, same layout;
	                             * NULL: every cell is a flow cell */
	double time;                /* s */
	unsigned wall_sides;        /* bit 1 << enum ss_side (boundary.h) for each
	                             * grid side that is a wall, drawn as one */
};

/* A picture: rows from the top (north), samples interleaved. */
struct ss_render_image {
	int width, height;          /* px */
	int channels;               /* 3 (RGB) or 1 (grey) */
	int bit_depth;              /* 8, or 16 (samples are native uint16_t) */
	size_t row_bytes;
	unsigned char *pixels;      /* height * row_bytes, owned */
	/* written as PNG text chunks */
	double time;                /* s */
	double zmin, zmax;          /* m, the scale the picture was made with */
	long long snapshot;         /* index in its file, -1 if none */
	double px_dx, px_dy;        /* m per pixel (map styles; NAN for oblique) */
	double x0, y0;              /* lower-left corner of the map, m; NAN if unknown */
	enum ss_render_style style;
	char source[4096];          /* file the snapshot came from, "" if none */
};

/* Allocate a picture (its pixels are not cleared); SS_ERR_FAIL if out of
 * memory. */
int ss_render_image_init(struct ss_render_image *img, int width, int height,
                         int channels, int bit_depth);
void ss_render_image_release(struct ss_render_image *img);

/* Picture size for a grid of nx x ny cells of dx x dy under o (scale,
 * max_size, style): the cells' pixels, before any colour bar. */
void ss_render_picture_size(int nx, int ny, double dx, double dy,
                            const struct ss_render_options *o, int *width, int *height);

/*
 * Render one field into img (initialised here; release it).  NAN zmin or
 * zmax are taken from this field's flow and open cells.  Rows are split
 * between the OpenMP threads.  SS_ERR_INPUT for bad options or a field
 * with no cells, SS_ERR_FAIL when out of memory.
 */
int ss_render_field(const struct ss_render_field *f, const struct ss_render_options *o,
                    struct ss_render_image *img);

/* Write img as a PNG: to "path.partial", renamed to path when complete,
 * so a picture that exists is whole.  compression is the zlib level. */
int ss_render_write_png(const struct ss_render_image *img, const char *path,
                        int compression);

/* `sandslide render`: a series of frames from a sandslide HDF5 file. */
struct ss_render_series_options {
	const char *input;          /* the .h5 file */
	const char *output_dir;     /* frames go here (created if missing); NULL:
	                             * none are kept (with html or video: a video's
	                             * frames go to a temporary folder beside it,
	                             * removed once the video is made) */
	const char *frames;         /* "A:B:STEP", a Python slice of the snapshots
	                             * (B exclusive, negative counts from the end,
	                             * parts optional, bounds clamped to the series,
	                             * a negative STEP going backwards, STEP 0
	                             * refused), drawn in its order; "A", one index;
	                             * NULL: all, in time order */
	double time;                /* s: the snapshot nearest this; NAN: unused */
	const char *video;          /* FILE.mp4 to assemble with ffmpeg, or NULL */
	int fps;                    /* frames per second of the video, and the
	                             * speed the viewer starts at; 0: chosen from
	                             * the number of frames n, n / 4 (whole) within
	                             * 1 .. 24, so that a video lasts 4 s or more
	                             * (ss_render_fps_for) */
	const char *html;           /* FILE.html: a self-contained viewer of the
	                             * frames (PNG frames embedded as base64, a
	                             * slider, play/pause, the colour bar, and
	                             * the height under the mouse from heights
	                             * embedded quantised to 16 bits), or NULL */
	struct ss_job job;          /* force: replace frames, a video and a viewer
	                             * that exist (else SS_ERR_INPUT before
	                             * anything is written); threads (job.h) */
	struct ss_render_options look;
};

/* `sandslide render`'s options (option.h), continued by the job's at job
 * and the look's at look; the command line's parser and help read them. */
extern const struct ss_option_table ss_render_option_table;

/* Every field at the table's default (look too). */
void ss_render_series_options_init(struct ss_render_series_options *o);

/* What became of a video that was asked for. */
enum ss_render_video_made {
	SS_RENDER_VIDEO_NONE,       /* none was asked for */
	SS_RENDER_VIDEO_MADE,
	SS_RENDER_VIDEO_NO_FFMPEG,  /* ffmpeg is not on PATH: the frames are kept */
};

/* What ss_render_series did, for the caller to print. */
struct ss_render_series_report {
	long long frames;           /* written */
	int width, height;          /* px, with the colour bar */
	double t_first, t_last;     /* s, of the first and last frame */
	double zmin, zmax;          /* m, the scale the frames share */
	double seconds;             /* the frames, from the start of the call, s */
	double render_seconds;      /* rendering and writing the frames, s */
	int threads;
	char stale[4200];           /* the frame file after the last, left by an
	                             * earlier render; "" if there is none */
	enum ss_render_video_made video;
	long long html_bytes;       /* size of the viewer written, 0 if none */
	int fps;                    /* of the video and the viewer: the options',
	                             * or chosen from the frames */
};

/* The frame rate of a video of n frames when none is given: n / 4 frames
 * per second (whole), at least 1 and at most 24, so that it lasts at
 * least 4 s (n >= 4), and a long series plays at film speed. */
int ss_render_fps_for(long long frames);

/*
 * Render the chosen snapshots of o->input to output_dir/frame_00000.png,
 * frame_00001.png, ... in the order chosen, then the video if asked for
 * (without ffmpeg on PATH the frames in output_dir are kept, and that is
 * success), and the viewer o->html if asked for (the same frames, rendered
 * once for all).  Everything is checked before the first frame is
 * written.  Returns SS_OK (*report filled), SS_ERR_INPUT (not a sandslide
 * file, no snapshots, an index outside the series or an empty slice, an
 * unwritable folder, zmin >= zmax, frames, a video or a viewer there
 * already without force, a video without output_dir and without ffmpeg)
 * or SS_ERR_FAIL.
 */
int ss_render_series(const struct ss_render_series_options *o,
                     struct ss_render_series_report *report);

/* Name of frame k in dir: "dir/frame_%05lld.png". */
void ss_render_frame_path(const char *dir, long long k, char *out, size_t size);

/*
 * Frames of a run as it writes them (`sandslide run --frames DIR`): each
 * snapshot is read back from the output file just flushed and rendered to
 * DIR/frame_<k>.png.  The height scale, unless look gives it, is fixed at
 * snapshot 0 so that all frames share it: from the lowest to the highest
 * height the run can reach by the maximum principle, i.e. the range of the
 * initial surface (and of open_level when something is open) with
 * `source_rise` (the most the sources can add to a cell over the run, m)
 * added at the top.
 */
struct ss_render_frames;

/* Check that dir is or can be made a writable folder (SS_ERR_INPUT) and
 * the look (ss_render_options_check); nothing is created yet. */
int ss_render_frames_create(struct ss_render_frames **out, const char *dir,
                            const struct ss_render_options *look);

struct ss_render_frames_bounds {
	double source_rise;         /* m, INFINITY: no bound (each frame its own scale) */
	double open_level;          /* m */
	int any_open_side;          /* an open side holds heights at open_level */
};

/* Render snapshot `index` of the file at path as the next frame. */
int ss_render_frames_add(struct ss_render_frames *fr, const char *path, long long index,
                         const struct ss_render_frames_bounds *bounds);

/* Frames written so far. */
long long ss_render_frames_count(const struct ss_render_frames *fr);

/* ss_render_frames_destroy(NULL) is a no-op. */
void ss_render_frames_destroy(struct ss_render_frames *fr);

/*
 * Assemble dir/frame_00000.png .. frame_<count-1>.png into a video with
 * ffmpeg (H.264, yuv420p, fps frames per second), written to a temporary
 * name and renamed.  Returns SS_OK, with *made SS_RENDER_VIDEO_MADE, or
 * SS_RENDER_VIDEO_NO_FFMPEG when ffmpeg is not on PATH (nothing is done);
 * SS_ERR_FAIL when ffmpeg fails.
 */
int ss_render_video(const char *dir, long long count, int fps, const char *video,
                    enum ss_render_video_made *made);

/* What ss_render_bench measured, s. */
struct ss_render_bench_report {
	int n, repeats, threads;
	double median, min, max;    /* colouring one frame (plan made once) */
	double field;               /* ss_render_field: plan, scale and colouring */
	int png_levels[2];          /* zlib levels timed */
	double png[2];              /* encoding the frame at each level (serial) */
	double png_bytes[2];        /* the file it made */
};

/*
 * Throughput of the shaded style on an n x n synthetic grid (walls, open
 * cells, slopes), one frame rendered `repeats` times, and of the PNG
 * encoding, into *report (the caller prints it).
 */
int ss_render_bench(int n, int repeats, struct ss_render_bench_report *report);

#endif
