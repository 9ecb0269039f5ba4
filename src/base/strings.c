/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * strings.c - string helpers (see strings.h).
 */
#include "base/strings.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sandslide/error.h"

char *ss_strings_join(const char *const *v, int n, const char *separator, int terminate)
{
	const size_t sep = strlen(separator);
	size_t len = 1;
	for (int k = 0; k < n; k++)
		len += strlen(v[k]) + sep;
	char *s = malloc(len), *end = s;
	if (!s) {
		ss_error_fail("out of memory");
		return NULL;
	}
	for (int k = 0; k < n; k++) {
		const size_t m = strlen(v[k]);
		memcpy(end, v[k], m);
		end += m;
		if (k + 1 < n || terminate) {
			memcpy(end, separator, sep);
			end += sep;
		}
	}
	*end = '\0';
	return s;
}

int ss_parse_int(const char *s, long lo, long hi, int *out)
{
	char *end;
	errno = 0;
	const long v = s ? strtol(s, &end, 10) : 0;
	if (!s || end == s || *end || errno || v < lo || v > hi)
		return -1;
	*out = (int)v;
	return 0;
}

int ss_parse_real(const char *s, double lo, double hi, double *out)
{
	char *end;
	errno = 0;
	const double v = s ? strtod(s, &end) : NAN;
	if (!s || end == s || *end || errno || !isfinite(v) || !(v >= lo && v <= hi))
		return -1;
	*out = v;
	return 0;
}

int ss_parse_numbers(const char *s, int commas, double *out, int max)
{
	int n = 0;
	for (;;) {
		while (isspace((unsigned char)*s) || (commas && n > 0 && *s == ','))
			s++;
		if (!*s)
			return n;
		char *end;
		errno = 0;
		const double v = strtod(s, &end);
		if (end == s || errno == ERANGE || !isfinite(v) ||
		    (*end && !(commas && *end == ',') && !isspace((unsigned char)*end)))
			return -1;
		if (n < max)
			out[n] = v;
		n++;
		s = end;
	}
}

int ss_parse_name(const char *name, const char *const *names, int n)
{
	for (int k = 0; k < n; k++)
		if (strcmp(name, names[k]) == 0)
			return k;
	return -1;
}

int ss_parse_tile(const char *s, int tile[2])
{
	const char *x = strchr(s, 'x');
	char nx[32];
	int a, b;
	if (!x || x - s >= (long)sizeof nx)
		return -1;
	memcpy(nx, s, (size_t)(x - s));
	nx[x - s] = '\0';
	if (ss_parse_int(nx, 1, 1 << 20, &a) || ss_parse_int(x + 1, 1, 1 << 20, &b))
		return -1;
	tile[0] = a;
	tile[1] = b;
	return 0;
}

void ss_strbuf_printf(struct ss_strbuf *b, const char *fmt, ...)
{
	const size_t room = b->len < b->size ? b->size - b->len : 0;
	va_list ap;
	va_start(ap, fmt);
	const int n = vsnprintf(room ? b->buf + b->len : NULL, room, fmt, ap);
	va_end(ap);
	if (n > 0)
		b->len += (size_t)n;
}

void ss_strbuf_json_string(struct ss_strbuf *b, const char *s)
{
	ss_strbuf_printf(b, "\"");
	for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
		if (*p == '"' || *p == '\\')
			ss_strbuf_printf(b, "\\%c", *p);
		else if (*p < 0x20)
			ss_strbuf_printf(b, "\\u%04x", *p);
		else
			ss_strbuf_printf(b, "%c", *p);
	}
	ss_strbuf_printf(b, "\"");
}

/* The fewest digits from `least` to `most` with which x reads back as
 * itself, printed into buf; `most` digits if none does. */
static void shortest(double x, int least, int most, char *buf, size_t size)
{
	for (int digits = least; digits < most; digits++) {
		snprintf(buf, size, "%.*g", digits, x);
		if (strtod(buf, NULL) == x)
			return;
	}
	snprintf(buf, size, "%.*g", most, x);
}

const char *ss_real_text(double x, char buf[SS_REAL_TEXT_SIZE])
{
	shortest(x, 15, 17, buf, SS_REAL_TEXT_SIZE);
	return buf;
}

const char *ss_cell_text(long long i, long long j, double x, double y,
                         char buf[SS_CELL_TEXT_SIZE])
{
	if (isnan(x) || isnan(y))
		snprintf(buf, SS_CELL_TEXT_SIZE, "cell (%lld, %lld)", i, j);
	else
		/* 15 digits: a centre x0 + (i + 0.5) dx is rounded, and the
		 * file's decimals (1.45, not 1.4500000000000002) are what the
		 * user finds the cell by */
		snprintf(buf, SS_CELL_TEXT_SIZE, "cell (%lld, %lld) at x = %.15g m, y = %.15g m", i,
		         j, x, y);
	return buf;
}

void ss_strbuf_json_number(struct ss_strbuf *b, double x, int digits)
{
	if (!isfinite(x)) {
		ss_strbuf_printf(b, "null");
		return;
	}
	/* from 15 digits up (or `digits`, if fewer): a decimal of fewer
	 * digits prints as itself at 15 too, %g dropping the trailing zeros */
	char text[SS_REAL_TEXT_SIZE];
	shortest(x, digits < 15 ? digits : 15, digits, text, sizeof text);
	ss_strbuf_printf(b, "%s", text);
}
