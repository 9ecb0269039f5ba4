/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * report.h - a command's report as JSON, written from a table of its
 * fields (name, kind, place in the report's struct, where a line breaks),
 * as the option tables describe the options: each report is a table in its
 * command's *_report.c, and this one writer formats them all.
 */
#ifndef SANDSLIDE_BASE_REPORT_H
#define SANDSLIDE_BASE_REPORT_H

#include <stddef.h>

enum ss_field_kind {
	SS_FIELD_INT,           /* int */
	SS_FIELD_COUNT,         /* long long */
	SS_FIELD_REAL,          /* double, as many digits as read back (null:
	                         * not finite) */
	SS_FIELD_SECONDS,       /* double, 6 significant digits (timings) */
	SS_FIELD_BOOL,          /* int: true or false */
	SS_FIELD_TEXT,          /* const char * (NULL: "") */
	SS_FIELD_CHARS,         /* char[] in the struct */
	SS_FIELD_NAME,          /* an enum (int), written as name_of gives it */
	SS_FIELD_CHARS_LIST,    /* char[][item_size], count at count_offset (int) */
};

struct ss_field {
	const char *name;
	enum ss_field_kind kind;
	size_t offset;
	int line;                          /* a line break before it */
	const char *(*name_of)(int value); /* NAME */
	size_t count_offset, item_size;    /* CHARS_LIST */
};

/* The fields of the struct at base as one JSON object into buf (size
 * bytes, NUL-terminated), "{\n  " and a line for each field that starts
 * one; SS_ERR_INPUT when it does not fit, saying how many bytes `what`
 * ("the relax report") needs. */
int ss_report_json(const struct ss_field *fields, int count, const void *base,
                   const char *what, char *buf, size_t size);

#endif
