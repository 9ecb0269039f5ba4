/*
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
/* "NXxNY", each 1 to 2^20, into tile[0], tile[1] (--tile); 0 or -1. */
int ss_parse_tile(const char *s, int tile[2]);

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
/* x with `digits` significant digits (17: read back bit for bit); null when
 * x is NaN or infinite, which JSON cannot write. */
void ss_strbuf_json_number(struct ss_strbuf *b, double x, int digits);

#endif
