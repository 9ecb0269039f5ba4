/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * strings.h - the few string helpers more than one tier needs.
 */
#ifndef SANDSLIDE_BASE_STRINGS_H
#define SANDSLIDE_BASE_STRINGS_H

#include <stddef.h>

/* The n strings of v joined into one new string (free it), separator
 * between them, and after the last one too when terminate is set; NULL
 * (after a message) when out of memory. */
char *ss_strings_join(const char *const *v, int n, const char *separator, int terminate);

/* All of s as a number in [lo, hi] (a finite one for reals) into *out:
 * 0, or -1 when it is not one (out unchanged).  The command line's
 * options and the options set by name (app/named.c) parse with these. */
int ss_parse_int(const char *s, long lo, long hi, int *out);
int ss_parse_real(const char *s, double lo, double hi, double *out);
/* Finite numbers separated by white space (and by commas when commas is
 * set: "0,0,1,1"), the first max of them into out (out may be NULL when
 * max is 0): the count of numbers in s, or -1 when something in it is not
 * one.  Case files' pairs and polygons, and the shapes of case and
 * command line (shape.h), are read with it. */
int ss_parse_numbers(const char *s, int commas, double *out, int max);
/* "NXxNY", each 1 to 2^20, into tile[0], tile[1] (--tile); 0 or -1. */
int ss_parse_tile(const char *s, int tile[2]);
/* The index of name among the n names (an enum's, in its order), or -1:
 * the parsers of closures, sides, integrators and the approach to rest. */
int ss_parse_name(const char *name, const char *const *names, int n);

/* Text appended to a caller's buffer (the JSON of relax's report and run's
 * summary): always NUL-terminated, cut when full, and len counts what was
 * asked even past size, as snprintf does, so the formatter's caller can
 * tell that it was cut and how much it needed. */
struct ss_strbuf {
	char *buf;          /* size bytes; may be NULL when size is 0 */
	size_t size;
	size_t len;         /* bytes asked for so far, without the NUL */
};

void ss_strbuf_printf(struct ss_strbuf *b, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));
/* s in double quotes with '"', '\\' and control characters escaped: a
 * path may hold any of them and the JSON must still parse. */
void ss_strbuf_json_string(struct ss_strbuf *b, const char *s);
/* x with at most `digits` significant digits, and no more than it takes
 * to read back as x: 17 gives the shortest text that reads back bit for
 * bit (1e-09, not 1.0000000000000001e-09; ss_real_text); null when x is
 * NaN or infinite, which JSON cannot write. */
void ss_strbuf_json_number(struct ss_strbuf *b, double x, int digits);

/* x as the shortest of "%.15g", "%.16g" and "%.17g" that reads back as x
 * (strtod): 5479330.25, not %g's 5.47933e+06; 1e-09, not %.17g's
 * 1.0000000000000001e-09.  15 digits print any decimal of up to 15
 * significant digits as written (DBL_DIG), so a number that came from
 * such a decimal prints as it did; "nan", "inf", "-inf" otherwise.
 * Returns buf.  For numbers people read that must be exact: coordinates,
 * cell sizes, tolerances. */
#define SS_REAL_TEXT_SIZE 32
const char *ss_real_text(double x, char buf[SS_REAL_TEXT_SIZE]);
/* ss_real_text into a buffer that lives to the end of the enclosing
 * block, for printf's arguments: printf("x = %s m", SS_REAL(x)). */
#define SS_REAL(x) ss_real_text((x), (char[SS_REAL_TEXT_SIZE]){0})

/* The one way a message names a cell: "cell (i, j) at x = X m, y = Y m",
 * i the column from the west and j the row from the south, both from 0
 * (doc/model.md's indices), and x, y its centre in the grid's or the
 * raster's own coordinates (a DEM's map coordinates), to 15 digits.
 * Without coordinates (x or y NaN: a raster that gives none) just
 * "cell (i, j)".  Returns buf. */
#define SS_CELL_TEXT_SIZE (32 + 2 * SS_REAL_TEXT_SIZE + 2 * 24)
const char *ss_cell_text(long long i, long long j, double x, double y,
                         char buf[SS_CELL_TEXT_SIZE]);
#define SS_CELL(i, j, x, y) \
	ss_cell_text((i), (j), (x), (y), (char[SS_CELL_TEXT_SIZE]){0})
/* SS_CELL of cell (i, j) of a rank's block of struct ss_grid *g (grid.h,
 * included where it is used): its index in the whole grid, its centre. */
#define SS_GRID_CELL(g, i, j)                                               \
	SS_CELL((g)->offset_i + (i), (g)->offset_j + (j), ss_grid_x((g), (i)), \
	        ss_grid_y((g), (j)))

#endif
