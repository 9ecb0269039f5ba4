/*
 * option.c - reading options from their tables (see sandslide/option.h).
 */
#include "sandslide/option.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"

/* name as written by a caller ('_' for '-') against an option's name */
static int same_name(const char *given, const char *name)
{
	for (; *given && *name; given++, name++)
		if (*given != *name && !(*given == '_' && *name == '-'))
			return 0;
	return *given == *name;
}

static const struct ss_option *find(const struct ss_option_table *t, const char *s, int by_key,
                                    size_t *offset)
{
	size_t base = 0;
	for (; t; base += t->more_offset, t = t->more) {
		for (int k = 0; k < t->count; k++) {
			const struct ss_option *o = &t->options[k];
			const char *name = by_key ? o->case_key : o->name;
			if (name && (by_key ? !strcmp(s, name) : same_name(s, name))) {
				if (offset)
					*offset = base;
				return o;
			}
		}
	}
	return NULL;
}

const struct ss_option *ss_option_find(const struct ss_option_table *t, const char *name,
                                       size_t *offset)
{
	return find(t, name, 0, offset);
}

const struct ss_option *ss_option_find_key(const struct ss_option_table *t, const char *key,
                                           size_t *offset)
{
	return find(t, key, 1, offset);
}

int ss_option_parse(const struct ss_option *o, const char *value, void *field)
{
	double x;
	switch (o->kind) {
	case SS_OPTION_INT:
		return ss_parse_int(value, (long)o->lo, (long)o->hi, field);
	case SS_OPTION_REAL:
		if (ss_parse_real(value, o->lo, o->hi, &x) ||
		    ((o->flags & SS_OPTION_LO_OPEN) && x == o->lo) ||
		    ((o->flags & SS_OPTION_HI_OPEN) && x == o->hi))
			return -1;
		*(double *)field = x;
		return 0;
	case SS_OPTION_FLAG:
		if (strcmp(value, "0") && strcmp(value, "1"))
			return -1;
		*(int *)field = value[0] == '1';
		return 0;
	case SS_OPTION_TEXT:
		if (!*value)
			return -1;
		*(const char **)field = value;
		return 0;
	case SS_OPTION_WORD:
		return o->parse(value, field) ? -1 : 0;
	case SS_OPTION_LIST:
	case SS_OPTION_OPTIONAL_INT:
		break;
	}
	return -1;
}

void ss_option_defaults(const struct ss_option_table *t, void *base)
{
	char *at = base;
	for (; t; at += t->more_offset, t = t->more) {
		for (int k = 0; k < t->count; k++) {
			const struct ss_option *o = &t->options[k];
			void *field = at + o->offset;
			if (!o->name && !o->case_key)
				continue;   /* a heading */
			if (o->default_value) {
				if (ss_option_parse(o, o->default_value, field))
					SS_BUG("option '%s': its default '%s' is not one of its values",
					       o->name ? o->name : o->case_key, o->default_value);
				continue;
			}
			switch (o->kind) {
			case SS_OPTION_REAL:
				*(double *)field = NAN;
				break;
			case SS_OPTION_INT:
			case SS_OPTION_FLAG:
			case SS_OPTION_OPTIONAL_INT:
				*(int *)field = 0;
				break;
			case SS_OPTION_TEXT:
				*(const char **)field = NULL;
				break;
			case SS_OPTION_WORD:
			case SS_OPTION_LIST:
				break;   /* their owner's: a WORD without default is zero */
			}
		}
	}
}

void ss_option_names(const struct ss_option_table *t, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	int n = 0;
	if (size)
		buf[0] = '\0';
	for (; t; t = t->more)
		for (int k = 0; k < t->count; k++)
			if (t->options[k].name && !(t->options[k].flags & SS_OPTION_CLI_ONLY))
				ss_strbuf_printf(&b, "%s%s", n++ ? ", " : "", t->options[k].name);
}

void ss_option_texts_release(struct ss_option_texts *texts)
{
	for (int k = 0; k < SS_OPTION_MAX_TEXTS; k++)
		ss_free(texts->copy[k]);
	memset(texts, 0, sizeof *texts);
}

/* value copied into texts, field pointed to the copy */
static int set_text(struct ss_option_texts *texts, void *field, const char *value)
{
	int slot = -1;
	for (int k = 0; k < SS_OPTION_MAX_TEXTS && slot < 0; k++)
		if (texts->field[k] == field || !texts->field[k])
			slot = k;
	if (slot < 0)
		SS_BUG("more than %d text options set by name", SS_OPTION_MAX_TEXTS);
	const size_t n = strlen(value) + 1;
	char *copy = ss_alloc(n, 1, "an option's text");
	if (!copy)
		return SS_ERR_FAIL;
	memcpy(copy, value, n);
	ss_free(texts->copy[slot]);
	texts->copy[slot] = copy;
	texts->field[slot] = field;
	*(const char **)field = copy;
	return SS_OK;
}

int ss_option_set(const struct ss_option_table *t, void *base, const char *key,
                  const char *value, struct ss_option_texts *texts)
{
	size_t offset;
	const struct ss_option *o = ss_option_find(t, key, &offset);
	if (!o || (o->flags & SS_OPTION_CLI_ONLY)) {
		char names[1024];
		ss_option_names(t, names, sizeof names);
		return ss_error_input("unknown %s option '%s': expected one of %s", t->command, key,
		                      names);
	}
	if (o->kind == SS_OPTION_LIST || o->kind == SS_OPTION_OPTIONAL_INT)
		SS_BUG("ss_option_set: option '%s' is set by its caller", o->name);
	if (!value || !*value)
		return ss_error_input("%s needs a value: %s", key, o->expected);
	void *field = (char *)base + offset + o->offset;
	if (o->kind == SS_OPTION_TEXT)
		return set_text(texts, field, value);
	if (ss_option_parse(o, value, field))
		return ss_error_input("%s '%s': expected %s", key, value, o->expected);
	return SS_OK;
}

static const char *const kind_names[] = {
	[SS_OPTION_FLAG] = "flag", [SS_OPTION_INT] = "int", [SS_OPTION_REAL] = "real",
	[SS_OPTION_TEXT] = "text", [SS_OPTION_WORD] = "word", [SS_OPTION_LIST] = "list",
	[SS_OPTION_OPTIONAL_INT] = "optional int",
};

int ss_option_table_json(const struct ss_option_table *t, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	int n = 0;
	ss_strbuf_printf(&b, "[");
	for (const struct ss_option_table *u = t; u; u = u->more) {
		for (int k = 0; k < u->count; k++) {
			const struct ss_option *o = &u->options[k];
			if (!o->name && !o->case_key)
				continue;
			ss_strbuf_printf(&b, "%s\n  {\"name\": ", n++ ? "," : "");
			if (o->name)
				ss_strbuf_json_string(&b, o->name);
			else
				ss_strbuf_printf(&b, "null");
			ss_strbuf_printf(&b, ", \"case_key\": ");
			if (o->case_key)
				ss_strbuf_json_string(&b, o->case_key);
			else
				ss_strbuf_printf(&b, "null");
			ss_strbuf_printf(&b, ", \"kind\": \"%s\", \"default\": ", kind_names[o->kind]);
			if (o->default_value)
				ss_strbuf_json_string(&b, o->default_value);
			else
				ss_strbuf_printf(&b, "null");
			ss_strbuf_printf(&b, ", \"lo\": ");
			ss_strbuf_json_number(&b, o->kind == SS_OPTION_INT || o->kind == SS_OPTION_REAL
			                          ? o->lo : NAN, 17);
			ss_strbuf_printf(&b, ", \"hi\": ");
			ss_strbuf_json_number(&b, o->kind == SS_OPTION_INT || o->kind == SS_OPTION_REAL
			                          ? o->hi : NAN, 17);
			ss_strbuf_printf(&b, ", \"command_line\": %s, \"by_name\": %s, \"expected\": ",
			                 o->name && !(o->flags & SS_OPTION_NAMED_ONLY) ? "true" : "false",
			                 o->name && !(o->flags & SS_OPTION_CLI_ONLY) ? "true" : "false");
			ss_strbuf_json_string(&b, o->expected ? o->expected : "");
			ss_strbuf_printf(&b, ", \"help\": ");
			ss_strbuf_json_string(&b, o->help ? o->help : "");
			ss_strbuf_printf(&b, "}");
		}
	}
	ss_strbuf_printf(&b, "\n]\n");
	if (b.len >= size)
		return ss_error_input("the %s options' JSON needs %zu bytes: the buffer has %zu",
		                      t->command, b.len + 1, size);
	return SS_OK;
}
