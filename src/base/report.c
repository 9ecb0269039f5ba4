/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * report.c - reports as JSON from their field tables (see report.h).
 */
#include "base/report.h"

#include "base/strings.h"
#include "sandslide/error.h"

static void value(struct ss_strbuf *b, const struct ss_field *f, const char *at)
{
	switch (f->kind) {
	case SS_FIELD_INT:
		ss_strbuf_printf(b, "%d", *(const int *)at);
		break;
	case SS_FIELD_COUNT:
		ss_strbuf_printf(b, "%lld", *(const long long *)at);
		break;
	case SS_FIELD_REAL:
		ss_strbuf_json_number(b, *(const double *)at, 17);
		break;
	case SS_FIELD_SECONDS:
		ss_strbuf_json_number(b, *(const double *)at, 6);
		break;
	case SS_FIELD_BOOL:
		ss_strbuf_printf(b, "%s", *(const int *)at ? "true" : "false");
		break;
	case SS_FIELD_TEXT: {
		const char *s = *(const char *const *)at;
		ss_strbuf_json_string(b, s ? s : "");
		break;
	}
	case SS_FIELD_CHARS:
		ss_strbuf_json_string(b, at);
		break;
	case SS_FIELD_NAME:
		ss_strbuf_json_string(b, f->name_of(*(const int *)at));
		break;
	case SS_FIELD_CHARS_LIST: {
		const int n = *(const int *)(at - f->offset + f->count_offset);
		ss_strbuf_printf(b, "[");
		for (int k = 0; k < n; k++) {
			ss_strbuf_printf(b, "%s", k ? ", " : "");
			ss_strbuf_json_string(b, at + (size_t)k * f->item_size);
		}
		ss_strbuf_printf(b, "]");
		break;
	}
	}
}

int ss_report_json(const struct ss_field *fields, int count, const void *base,
                   const char *what, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	ss_strbuf_printf(&b, "{");
	for (int k = 0; k < count; k++) {
		const struct ss_field *f = &fields[k];
		ss_strbuf_printf(&b, "%s\"%s\": ", k == 0 ? "\n  " : f->line ? ",\n  " : ", ",
		                 f->name);
		value(&b, f, (const char *)base + f->offset);
	}
	ss_strbuf_printf(&b, "\n}\n");
	if (b.len >= size)
		return ss_error_input("%s needs %zu bytes: the buffer has %zu", what, b.len + 1,
		                      size);
	return SS_OK;
}
