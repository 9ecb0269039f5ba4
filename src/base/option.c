/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * option.c - reading options from their tables (see sandslide/option.h).
 */
#include "sandslide/option.h"

#include <math.h>
#include <stddef.h>
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

int ss_option_flatten(const struct ss_option_table *t, const struct ss_option *option[],
                      size_t offset[])
{
	int n = 0;
	for (int k = 0; k < t->count; k++) {
		if (n == SS_OPTION_MAX)
			SS_BUG("the %s options: more than %d", t->command, SS_OPTION_MAX);
		option[n] = &t->options[k];
		offset[n++] = 0;
	}
	for (int p = 0; p < t->part_count; p++) {
		const struct ss_option_part *part = &t->parts[p];
		const int m = ss_option_flatten(part->table, option + n, offset + n);
		if (n + m > SS_OPTION_MAX)
			SS_BUG("the %s options: more than %d", t->command, SS_OPTION_MAX);
		for (int k = n; k < n + m; k++)
			offset[k] += part->offset;
		n += m;
	}
	return n;
}

static const struct ss_option *find(const struct ss_option_table *t, const char *s, int by_key,
                                    size_t *offset)
{
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(t, option, at);
	for (int k = 0; k < n; k++) {
		const char *name = by_key ? option[k]->case_key : option[k]->name;
		if (name && (by_key ? !strcmp(s, name) : same_name(s, name))) {
			if (offset)
				*offset = at[k];
			return option[k];
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

int ss_option_list_append(struct ss_option_list *l, const char *item)
{
	if (l->count == l->room) {
		const int room = l->room ? 2 * l->room : 8;
		const char **grown = ss_alloc((size_t)room, sizeof *grown, "a list of options");
		if (!grown)
			return SS_ERR_FAIL;
		if (l->count)
			memcpy(grown, l->items, (size_t)l->count * sizeof *grown);
		ss_free(l->items);
		l->items = grown;
		l->room = room;
	}
	l->items[l->count++] = item;
	return SS_OK;
}

void ss_option_list_release(struct ss_option_list *l)
{
	ss_free(l->items);
	memset(l, 0, sizeof *l);
}

int ss_option_parse(const struct ss_option *o, const char *value, void *field)
{
	double x;
	switch (o->kind) {
	case SS_OPTION_INT:
		return ss_parse_int(value, (long)o->lo, (long)o->hi, field);
	case SS_OPTION_REAL: {
		/* OR_FILE: a value that does not start as a number does is a file
		 * (one that does, "30x", is a mistyped number: ./30x is the file) */
		const char **file = (o->flags & SS_OPTION_OR_FILE)
			? (const char **)((char *)field - o->offset + o->value_offset) : NULL;
		char *end;
		(void)strtod(value, &end);
		if (file && end == value) {
			if (!*value)
				return -1;
			*file = value;
			return 0;
		}
		if (ss_parse_real(value, o->lo, o->hi, &x) ||
		    ((o->flags & SS_OPTION_LO_OPEN) && x == o->lo) ||
		    ((o->flags & SS_OPTION_HI_OPEN) && x == o->hi))
			return -1;
		*(double *)field = x;
		if (file)
			*file = NULL;
		return 0;
	}
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
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(t, option, at);
	for (int k = 0; k < n; k++) {
		const struct ss_option *o = option[k];
		void *field = (char *)base + at[k] + o->offset;
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

void ss_option_release(const struct ss_option_table *t, void *base)
{
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(t, option, at);
	for (int k = 0; k < n; k++)
		if (option[k]->kind == SS_OPTION_LIST)
			ss_option_list_release((struct ss_option_list *)((char *)base + at[k] +
			                                                  option[k]->offset));
}

void ss_option_names(const struct ss_option_table *t, char *buf, size_t size)
{
	struct ss_strbuf b = {buf, size, 0};
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int n = ss_option_flatten(t, option, at);
	int named = 0;
	if (size)
		buf[0] = '\0';
	for (int k = 0; k < n; k++)
		if (option[k]->name && !(option[k]->flags & SS_OPTION_CLI_ONLY))
			ss_strbuf_printf(&b, "%s%s", named++ ? ", " : "", option[k]->name);
}

/*
 * An options object: this header, then the table's struct (the caller's
 * pointer), aligned for any type.  The header owns the copies of the texts
 * set by name, which the struct's TEXT fields and LIST items point to.
 */
struct object {
	const struct ss_option_table *table;
	char **copies;
	int copy_count, copy_room;
};

#define OBJECT_HEAD \
	((sizeof(struct object) + _Alignof(max_align_t) - 1) / _Alignof(max_align_t) * \
	 _Alignof(max_align_t))

static struct object *object_of(void *options)
{
	return (struct object *)((char *)options - OBJECT_HEAD);
}

void *ss_option_object_create(const struct ss_option_table *t)
{
	char *block = ss_alloc(OBJECT_HEAD + t->size, 1, "options");
	if (!block)
		return NULL;
	memset(block, 0, OBJECT_HEAD + t->size);
	struct object *head = (struct object *)block;
	head->table = t;
	void *options = block + OBJECT_HEAD;
	if (t->init)
		t->init(options);
	else
		ss_option_defaults(t, options);
	return options;
}

void ss_option_object_destroy(void *options)
{
	if (!options)
		return;
	struct object *head = object_of(options);
	ss_option_release(head->table, options);
	for (int k = 0; k < head->copy_count; k++)
		ss_free(head->copies[k]);
	ss_free(head->copies);
	ss_free(head);
}

/* A copy of value that the object keeps until it is destroyed. */
static const char *keep_copy(struct object *head, const char *value)
{
	if (head->copy_count == head->copy_room) {
		const int room = head->copy_room ? 2 * head->copy_room : 8;
		char **grown = ss_alloc((size_t)room, sizeof *grown, "an option's text");
		if (!grown)
			return NULL;
		if (head->copy_count)
			memcpy(grown, head->copies, (size_t)head->copy_count * sizeof *grown);
		ss_free(head->copies);
		head->copies = grown;
		head->copy_room = room;
	}
	const size_t n = strlen(value) + 1;
	char *copy = ss_alloc(n, 1, "an option's text");
	if (copy) {
		memcpy(copy, value, n);
		head->copies[head->copy_count++] = copy;
	}
	return copy;
}

int ss_option_object_set(void *options, const char *key, const char *value)
{
	struct object *head = object_of(options);
	const struct ss_option_table *t = head->table;
	size_t offset;
	const struct ss_option *o = key ? ss_option_find(t, key, &offset) : NULL;
	if (!o || (o->flags & SS_OPTION_CLI_ONLY)) {
		char names[1024];
		ss_option_names(t, names, sizeof names);
		return ss_error_input("unknown %s option '%s': expected one of %s", t->command,
		                      key ? key : "(null)", names);
	}
	if (o->kind == SS_OPTION_OPTIONAL_INT)
		SS_BUG("ss_option_object_set: option '%s' is the command line's", o->name);
	if (!value || !*value)
		return ss_error_input("%s needs a value: %s", key, o->expected);
	void *field = (char *)options + offset + o->offset;
	if (o->kind == SS_OPTION_LIST ? o->parse && o->parse(value, NULL)
	                              : o->kind != SS_OPTION_TEXT && ss_option_parse(o, value, field))
		return ss_error_input("%s '%s': expected %s", key, value, o->expected);
	if (o->flags & SS_OPTION_OR_FILE) {   /* a file name: the object's copy */
		const char **file = (const char **)((char *)options + offset + o->value_offset);
		if (*file == value && !(*file = keep_copy(head, value)))
			return SS_ERR_FAIL;
		return SS_OK;
	}
	if (o->kind != SS_OPTION_TEXT && o->kind != SS_OPTION_LIST)
		return SS_OK;
	const char *copy = keep_copy(head, value);
	if (!copy)
		return SS_ERR_FAIL;
	if (o->kind == SS_OPTION_LIST)
		return ss_option_list_append(field, copy);
	*(const char **)field = copy;
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
	const struct ss_option *option[SS_OPTION_MAX];
	size_t at[SS_OPTION_MAX];
	const int count = ss_option_flatten(t, option, at);
	int n = 0;
	ss_strbuf_printf(&b, "[");
	for (int k = 0; k < count; k++) {
		const struct ss_option *o = option[k];
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
	ss_strbuf_printf(&b, "\n]\n");
	if (b.len >= size)
		return ss_error_input("the %s options' JSON needs %zu bytes: the buffer has %zu",
		                      t->command, b.len + 1, size);
	return SS_OK;
}
