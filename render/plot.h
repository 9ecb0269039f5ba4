/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * plot.h - small line plots as PNG figures (render/plot.c), for the
 * figures of `sandslide fit --plot FIT.png`: curves over time, observations
 * as markers, cost profiles with a vertical line at the best value.
 * Private to the library: src/app/fit.c and tests/test_plot.c include it
 * as "render/plot.h"; it is not installed (the public headers are
 * include/sandslide/).
 *
 * A figure is a grid of `columns` x `rows` panels of the same size; panel
 * k is in row k / columns, column k % columns (panel 0 top left).  Each
 * panel has a title, axis titles (the y axis's turned to read upwards),
 * an optional log x axis, series of (x, y) points, vertical lines and a
 * legend.  The axes fit the data that can be drawn (with 5 % to spare on
 * each side) and carry ticks at 1-2-5 steps (decades on a log axis)
 * labelled with short numbers ("0.02", "150", "1e-3") spaced so that
 * neighbours keep an em between them; a panel with nothing to draw shows
 * empty axes and its title.  The legend goes into the first corner of the
 * plot area (upper right, upper left, lower right, lower left) where it
 * covers no drawn data, else under the plot area (its entries in rows),
 * which is shortened for it.
 * Text is the renderer's font (DejaVu Sans through FreeType, antialiased:
 * render/text.c) at about 1/24 of the panel's shorter side, titles a fifth
 * larger; text wider than its panel is cut at the panel's edge.
 *
 * Drawing needs the font file (SANDSLIDE_FONT, else the build's default):
 * ss_plot_check_font says early, before work whose end is a figure,
 * whether it is there.
 *
 * Everything given is copied: the caller's arrays and strings may be freed
 * once a call returns.  A call that fails leaves the figure as it was.
 * Drawing is deterministic: the same calls write the same bytes.  Errors
 * are printed once through error.h and returned as SS_ERR_INPUT (a bad
 * argument) or SS_ERR_FAIL (out of memory, a file that cannot be written).
 */
#ifndef SANDSLIDE_PLOT_H
#define SANDSLIDE_PLOT_H

#include <stdint.h>

/* A figure: a grid of panels (opaque; ss_plot_create, ss_plot_destroy). */
struct ss_plot;

/* How a series is drawn. */
enum ss_plot_style {
	SS_PLOT_LINE,           /* straight segments between successive points */
	SS_PLOT_MARKERS,        /* a filled disc at each point */
	SS_PLOT_LINE_MARKERS,   /* both */
};

/* Colours are indices into a fixed palette of SS_PLOT_COLOURS colours that
 * tell apart well (also for the colour-blind: Okabe and Ito's); any int is
 * taken modulo the palette, negative ones too. */
#define SS_PLOT_COLOURS 6

/* Limits of ss_plot_create. */
#define SS_PLOT_PANEL_MIN_WIDTH  200   /* px: room for the axes and their labels */
#define SS_PLOT_PANEL_MIN_HEIGHT 150   /* px */
#define SS_PLOT_SIDE_MAX 16384         /* px: the whole figure, each side */

/* Values a series or vertical line may hold: finite and at most this in
 * magnitude (so that a range and its margins stay finite), or NaN or an
 * infinity for a gap. */
#define SS_PLOT_VALUE_MAX 1e300

/* The 8-bit sRGB colour of palette entry `colour` (modulo the palette). */
void ss_plot_palette(int colour, uint8_t rgb[3]);

/* A new figure of columns x rows empty panels of panel_width_px x
 * panel_height_px each, into *out (NULL on failure); free it with
 * ss_plot_destroy.  SS_ERR_INPUT for fewer than 1 column or row, a panel
 * below SS_PLOT_PANEL_MIN_WIDTH x SS_PLOT_PANEL_MIN_HEIGHT, or a figure
 * wider or higher than SS_PLOT_SIDE_MAX px; SS_ERR_FAIL out of memory. */
int ss_plot_create(struct ss_plot **out, int columns, int rows, int panel_width_px,
                   int panel_height_px);

/* Free the figure and everything it copied; NULL is a no-op. */
void ss_plot_destroy(struct ss_plot *p);

/* Set panel `panel`'s title (centred at its top), x-axis label (under the
 * axis), y-axis label (above the axis, at its left) and whether its x axis
 * is logarithmic (log_x != 0: decades; points and vertical lines at x <= 0
 * are then not drawn).  NULL or "" for no text.  May be called again to
 * replace all four.  SS_ERR_INPUT for a panel out of range, SS_ERR_FAIL
 * out of memory. */
int ss_plot_panel(struct ss_plot *p, int panel, const char *title, const char *x_label,
                  const char *y_label, int log_x);

/* Add a series of n points (x[i], y[i]) to panel `panel`, drawn in style
 * `style` and palette colour `colour`, with an entry in the panel's legend
 * unless legend is NULL or "".  Series are drawn in the order added, later
 * ones over earlier ones.  x and y are copied (they may be NULL when n is
 * 0).  A point with a NaN or infinite coordinate is not drawn and breaks
 * the line there.  SS_ERR_INPUT for a panel out of range, n < 0, x or y
 * NULL with n > 0, an unknown style, or a finite value beyond
 * SS_PLOT_VALUE_MAX in magnitude (the message names its index);
 * SS_ERR_FAIL out of memory. */
int ss_plot_add(struct ss_plot *p, int panel, const double *x, const double *y, long long n,
                enum ss_plot_style style, int colour, const char *legend);

/* Add a vertical line across panel `panel` at abscissa x (in the data's
 * units), in palette colour `colour`, drawn under the series; the x axis
 * takes it in.  SS_ERR_INPUT for a panel out of range or an x that is not
 * finite or beyond SS_PLOT_VALUE_MAX in magnitude; SS_ERR_FAIL out of
 * memory. */
int ss_plot_vline(struct ss_plot *p, int panel, double x, int colour);

/* SS_OK if the font that figures are drawn with can be opened, else
 * SS_ERR_FAIL with one line naming the file and what to install or set. */
int ss_plot_check_font(void);

/* Draw the figure, (columns * panel_width_px) x (rows * panel_height_px)
 * px of 8-bit RGB on white, and write it to path as a PNG: to
 * "path.partial", renamed to path once complete, so a file by that name is
 * always whole.  The figure is not changed.  SS_ERR_FAIL (naming the file
 * and the system's reason) if it cannot be written, the font cannot be
 * read (ss_plot_check_font), or out of memory. */
int ss_plot_write_png(const struct ss_plot *p, const char *path);

#endif
