/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * colormap.c - colour maps of height and the names of styles and maps.
 *
 * dune     perceptually uniform: built in CIELAB so that lightness L* rises
 *          linearly from 30 to 92 (equal height steps look equally far
 *          apart, and the map still reads in greyscale print), while the
 *          hue turns from violet (300 deg) through blue and teal to yellow
 *          (95 deg), the path of viridis.  Chroma grows from 45 to 90 and
 *          is lowered where a colour would leave the sRGB gamut, which
 *          keeps L* and hue exact.
 * terrain  the atlas convention: blue, green, sand, brown, white, linear in
 *          sRGB between six stops; not perceptually uniform.
 * gray     black to white.
 * Index 0 is zmin.  The dune start (L* 30) stays clear of the walls' colour
 * (L* 17) and its end (yellow) of the open cells' pale blue.
 */
#include "internal.h"

#include <math.h>
#include <string.h>

static const char *const style_names[] = {"shaded", "gray16", "oblique"};
static const char *const cmap_names[] = {"dune", "terrain", "gray"};

/* The index of name among the three names, -1 if it is none of them. */
static int index_of(const char *const names[3], const char *name)
{
	for (int k = 0; k < 3; k++)
		if (!strcmp(name, names[k]))
			return k;
	return -1;
}

const char *ss_render_style_name(enum ss_render_style s)
{
	return (unsigned)s < 3 ? style_names[s] : "?";
}

int ss_render_style_parse(const char *name, enum ss_render_style *s)
{
	const int k = index_of(style_names, name);
	if (k >= 0)
		*s = (enum ss_render_style)k;
	return k >= 0 ? 0 : -1;
}

const char *ss_render_cmap_name(enum ss_render_cmap c)
{
	return (unsigned)c < 3 ? cmap_names[c] : "?";
}

int ss_render_cmap_parse(const char *name, enum ss_render_cmap *c)
{
	const int k = index_of(cmap_names, name);
	if (k >= 0)
		*c = (enum ss_render_cmap)k;
	return k >= 0 ? 0 : -1;
}

/* CIELAB (D65) to linear sRGB. */
static void lab_to_linear_rgb(double L, double a, double b, double rgb[3])
{
	const double fy = (L + 16.0) / 116.0, fx = fy + a / 500.0, fz = fy - b / 200.0;
	const double d = 6.0 / 29.0;
	const double f[3] = {fx, fy, fz};
	double xyz[3];
	static const double white[3] = {0.95047, 1.0, 1.08883};
	for (int k = 0; k < 3; k++)
		xyz[k] = white[k] * (f[k] > d ? f[k] * f[k] * f[k] : 3.0 * d * d * (f[k] - 4.0 / 29.0));
	rgb[0] = 3.2404542 * xyz[0] - 1.5371385 * xyz[1] - 0.4985314 * xyz[2];
	rgb[1] = -0.9692660 * xyz[0] + 1.8760108 * xyz[1] + 0.0415560 * xyz[2];
	rgb[2] = 0.0556434 * xyz[0] - 0.2040259 * xyz[1] + 1.0572252 * xyz[2];
}

static int in_gamut(const double rgb[3])
{
	const double eps = 1e-9;
	return rgb[0] >= -eps && rgb[0] <= 1 + eps && rgb[1] >= -eps && rgb[1] <= 1 + eps &&
	       rgb[2] >= -eps && rgb[2] <= 1 + eps;
}

static uint8_t srgb_byte(double linear)
{
	const double c = linear <= 0.0 ? 0.0 : linear >= 1.0 ? 1.0 : linear;
	const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
	return (uint8_t)(255.0 * s + 0.5);
}

/* L*, C*, h (degrees) to sRGB bytes, lowering the chroma into the gamut. */
static void lch_to_srgb(double L, double C, double h_deg, uint8_t out[3])
{
	const double h = h_deg * (M_PI / 180.0);
	double rgb[3];
	lab_to_linear_rgb(L, C * cos(h), C * sin(h), rgb);
	if (!in_gamut(rgb)) {
		double lo = 0.0, hi = C;   /* chroma 0 (grey) is always in gamut */
		for (int it = 0; it < 40; it++) {
			const double mid = 0.5 * (lo + hi);
			lab_to_linear_rgb(L, mid * cos(h), mid * sin(h), rgb);
			if (in_gamut(rgb))
				lo = mid;
			else
				hi = mid;
		}
		lab_to_linear_rgb(L, lo * cos(h), lo * sin(h), rgb);
	}
	for (int k = 0; k < 3; k++)
		out[k] = srgb_byte(rgb[k]);
}

static void table_dune(uint8_t table[256][3])
{
	for (int k = 0; k < 256; k++) {
		const double t = k / 255.0;
		lch_to_srgb(30.0 + 62.0 * t, 45.0 + 45.0 * t * t * t, 300.0 - 205.0 * t, table[k]);
	}
}

static void table_terrain(uint8_t table[256][3])
{
	static const double stop[6][4] = {
		{0.00, 0.20, 0.25, 0.55},   /* deep water blue */
		{0.15, 0.10, 0.55, 0.85},
		{0.28, 0.15, 0.70, 0.45},   /* green */
		{0.50, 0.95, 0.90, 0.60},   /* sand */
		{0.75, 0.55, 0.40, 0.30},   /* brown */
		{1.00, 1.00, 1.00, 1.00},   /* white */
	};
	for (int k = 0; k < 256; k++) {
		const double t = k / 255.0;
		int s = 0;
		while (s < 4 && t > stop[s + 1][0])
			s++;
		const double u = (t - stop[s][0]) / (stop[s + 1][0] - stop[s][0]);
		for (int c = 0; c < 3; c++)
			table[k][c] = (uint8_t)(255.0 * ((1 - u) * stop[s][c + 1] + u * stop[s + 1][c + 1])
			                        + 0.5);
	}
}

void ss_render_cmap_table(enum ss_render_cmap c, uint8_t table[256][3])
{
	switch (c) {
	case SS_RENDER_CMAP_TERRAIN:
		table_terrain(table);
		break;
	case SS_RENDER_CMAP_GRAY:
		for (int k = 0; k < 256; k++)
			table[k][0] = table[k][1] = table[k][2] = (uint8_t)k;
		break;
	case SS_RENDER_CMAP_DUNE:
	default:
		table_dune(table);
		break;
	}
}
