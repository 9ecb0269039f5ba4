/*
 * named.c - options set by name (named.h): the lookup, the parsing of
 * numbers, flags and texts, and the messages, shared by relax_api.c and
 * run_api.c.
 */
#include "app/named.h"

#include <string.h>

#include "base/strings.h"
#include "sandslide/error.h"

/* key names option name, '_' standing for '-' */
static int same_key(const char *key, const char *name)
{
	for (; *key && *name; key++, name++)
		if (*key != *name && !(*key == '_' && *name == '-'))
			return 0;
	return *key == *name;
}

const struct ss_named *ss_named_find(const struct ss_named_table *t, const char *key)
{
	for (size_t n = 0; n < t->count; n++)
		if (same_key(key, t->keys[n].name))
			return &t->keys[n];
	char names[512];
	struct ss_strbuf b = {names, sizeof names, 0};
	for (size_t n = 0; n < t->count; n++)
		ss_strbuf_printf(&b, "%s%s", n ? ", " : "", t->keys[n].name);
	ss_error_input("unknown %s option '%s': expected one of %s", t->command, key, names);
	return NULL;
}

char *ss_named_copy(const char *s)
{
	const size_t n = strlen(s) + 1;
	char *copy = ss_alloc(n, 1, "an option's text");
	if (copy)
		memcpy(copy, s, n);
	return copy;
}

/* value parsed into field; 0, or -1 when it is not what k takes */
static int parse(const struct ss_named *k, const char *value, void *field)
{
	switch (k->kind) {
	case SS_NAMED_REAL:
		return ss_parse_real(value, k->lo, k->hi, field);
	case SS_NAMED_INT:
		return ss_parse_int(value, (long)k->lo, (long)k->hi, field);
	case SS_NAMED_FLAG:
		if (strcmp(value, "0") && strcmp(value, "1"))
			return -1;
		*(int *)field = value[0] == '1';
		return 0;
	case SS_NAMED_WORD:
		return k->parse(value, field) ? -1 : 0;
	case SS_NAMED_TEXT:
	case SS_NAMED_OWN:
		break;
	}
	return -1;
}

int ss_named_set(const struct ss_named *k, const char *key, const char *value, void *options,
                 char **texts)
{
	if (k->kind == SS_NAMED_OWN)
		SS_BUG("ss_named_set: option '%s' is set by its caller", k->name);
	if (!value || !*value)
		return ss_error_input("%s needs a value: %s", key, k->expected);
	void *field = (char *)options + k->offset;
	if (k->kind != SS_NAMED_TEXT)
		return parse(k, value, field)
		       ? ss_error_input("%s '%s': expected %s", key, value, k->expected) : SS_OK;
	char *copy = ss_named_copy(value);
	if (!copy)
		return SS_ERR_FAIL;
	ss_free(texts[k->text]);
	texts[k->text] = copy;
	*(const char **)field = copy;
	return SS_OK;
}
