/*
 * options.c - table-driven options and their help (see options.h).
 */
#include "cli/options.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* The help's second column: options on the left, their text from here. */
#define HELP_COLUMN 24

int cli_parse_int(const char *s, long lo, long hi, int *out)
{
	char *end;
	errno = 0;
	const long v = s ? strtol(s, &end, 10) : 0;
	if (!s || end == s || *end || errno || v < lo || v > hi)
		return -1;
	*out = (int)v;
	return 0;
}

int cli_parse_real(const char *s, double lo, double hi, double *out)
{
	char *end;
	errno = 0;
	const double v = s ? strtod(s, &end) : NAN;
	if (!s || end == s || *end || errno || !isfinite(v) || !(v >= lo && v <= hi))
		return -1;
	*out = v;
	return 0;
}

int cli_parse_tile(const char *s, void *tile)
{
	int *t = tile;
	const char *x = strchr(s, 'x');
	char buf[32];
	if (!x || x - s >= (long)sizeof buf)
		return -1;
	snprintf(buf, sizeof buf, "%.*s", (int)(x - s), s);
	return cli_parse_int(buf, 1, 1 << 20, &t[0]) || cli_parse_int(x + 1, 1, 1 << 20, &t[1])
	       ? -1 : 0;
}

/* The option's text over the continuation lines, HELP_COLUMN indented. */
static void help_lines(const char *text, FILE *f)
{
	for (const char *p = text; *p;) {
		const size_t n = strcspn(p, "\n");
		fprintf(f, "%.*s\n", (int)n, p);
		p += n;
		if (*p == '\n' && *++p)
			fprintf(f, "%*s", HELP_COLUMN, "");
	}
}

void cli_help(const struct cli_command *c, FILE *f)
{
	fputs(c->usage, f);
	if (c->intro)
		fprintf(f, "\n%s", c->intro);
	fputc('\n', f);
	for (int k = 0; k < c->option_count; k++) {
		const struct cli_option *o = &c->options[k];
		if (o->hidden)
			continue;
		if (!o->name) {
			fprintf(f, "\n%s", o->help);
			continue;
		}
		char left[64];
		snprintf(left, sizeof left, "%s%s%s%s%s", o->alias ? o->alias : "",
		         o->alias ? ", " : "", o->name, o->value ? " " : "", o->value ? o->value : "");
		if (strlen(left) + 3 <= HELP_COLUMN)
			fprintf(f, "  %-*s", HELP_COLUMN - 2, left);
		else
			fprintf(f, "  %s\n%*s", left, HELP_COLUMN, "");
		help_lines(o->help, f);
	}
	if (c->outro)
		fprintf(f, "\n%s", c->outro);
}

int cli_usage_error(const struct cli_command *c, const char *fmt, ...)
{
	va_list ap;
	fflush(stdout);
	fputs("sandslide: ", stderr);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fputs("\n\n", stderr);
	cli_help(c, stderr);
	return 2;
}

/* The option that word names ("--name", "--name=value" or the alias); its
 * inline value, if any, into *inline_value. */
static const struct cli_option *find(const struct cli_command *c, const char *word,
                                     const char **inline_value)
{
	*inline_value = NULL;
	for (int k = 0; k < c->option_count; k++) {
		const struct cli_option *o = &c->options[k];
		if (!o->name)
			continue;
		const size_t n = strlen(o->name);
		if (!strcmp(word, o->name) || (o->alias && !strcmp(word, o->alias)))
			return o;
		if (o->value && !strncmp(word, o->name, n) && word[n] == '=') {
			*inline_value = word + n + 1;
			return o;
		}
	}
	return NULL;
}

/* Store value into o's target; 0, or 2 after a usage error. */
static int store(struct cli_command *c, const struct cli_option *o, const char *value)
{
	int bad = 0;
	switch (o->kind) {
	case CLI_INT:
		bad = cli_parse_int(value, (long)o->lo, (long)o->hi, o->target);
		break;
	case CLI_REAL:
		bad = cli_parse_real(value, o->lo, o->hi, o->target);
		break;
	case CLI_TEXT:
		*(const char **)o->target = value;
		break;
	case CLI_LIST: {
		struct cli_list *l = o->target;
		l->v[l->n++] = value;
		break;
	}
	case CLI_PARSE:
		bad = o->parse(value, o->target);
		break;
	case CLI_FLAG:
	case CLI_OPTIONAL_INT:
		break;
	}
	if (bad)
		return cli_usage_error(c, "%s '%s': expected %s", o->name, value, o->expected);
	return 0;
}

/* The option at argv[*k] (which it was found to name), its value taken
 * from the word or the next one; 0, or 2 after a usage error. */
static int take(struct cli_command *c, const struct cli_option *o, const char *inline_value,
                int argc, char **argv, int *k)
{
	if (o->given)
		*o->given = 1;
	if (o->kind == CLI_FLAG) {
		*(int *)o->target = 1;
		return 0;
	}
	if (o->kind == CLI_OPTIONAL_INT) {
		struct cli_optional_int *v = o->target;
		v->given = 1;
		if (*k + 1 < argc && cli_parse_int(argv[*k + 1], (long)o->lo, (long)o->hi,
		                                   &v->value) == 0)
			++*k;
		return 0;
	}
	const char *value = inline_value;
	if (!value && *k + 1 < argc)
		value = argv[++*k];
	if (!value || !*value)
		return cli_usage_error(c, "%s needs %s", o->name, o->value);
	return store(c, o, value);
}

int cli_parse(struct cli_command *c, int argc, char **argv, int first)
{
	c->arg_count = 0;
	for (int k = first; k < argc; k++) {
		const char *a = argv[k], *inline_value;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			cli_help(c, stdout);
			return 0;
		}
		if (a[0] != '-' || !a[1]) {
			if (c->max_args == 0)
				return cli_usage_error(c, "unexpected argument '%s'", a);
			if (c->arg_count == c->max_args)
				return cli_usage_error(c, "one %s only (got a second: '%s')", c->what, a);
			c->args[c->arg_count++] = a;
			continue;
		}
		const struct cli_option *o = find(c, a, &inline_value);
		if (!o)
			return cli_usage_error(c, "unknown option '%s'", a);
		if (take(c, o, inline_value, argc, argv, &k))
			return 2;
	}
	return CLI_GO_ON;
}
