/*
 * strings.c - string helpers (see strings.h).
 */
#include "base/strings.h"

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

void ss_strbuf_json_number(struct ss_strbuf *b, double x, int digits)
{
	if (isfinite(x))
		ss_strbuf_printf(b, "%.*g", digits, x);
	else
		ss_strbuf_printf(b, "null");
}
