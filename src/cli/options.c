/*
 * options.c - table-driven options and their help (see options.h).
 */
#include "cli/options.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "base/strings.h"
#include "sandslide/comm.h"
#include "sandslide/error.h"

/* The help's second column: options on the left, their text from here. */
#define HELP_COLUMN 24

int cli_parse_tile(const char *s, void *tile)
{
	return ss_parse_tile(s, tile);
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

/* One option's lines of help. */
static void help_option(const struct cli_option *o, FILE *f)
{
	char left[64];
	snprintf(left, sizeof left, "%s%s%s%s%s", o->alias ? o->alias : "",
	         o->alias ? ", " : "", o->name, o->value ? " " : "", o->value ? o->value : "");
	if (strlen(left) + 3 <= HELP_COLUMN)
		fprintf(f, "  %-*s", HELP_COLUMN - 2, left);
	else
		fprintf(f, "  %s\n%*s", left, HELP_COLUMN, "");
	help_lines(o->help, f);
}

void cli_help(const struct cli_command *c, FILE *f)
{
	fputs(c->usage, f);
	if (c->intro)
		fprintf(f, "\n%s", c->intro);
	fputc('\n', f);
	for (int g = 0; g < CLI_MAX_GROUPS; g++) {
		const struct cli_group *group = &c->groups[g];
		for (int k = 0; k < group->count && !group->hidden; k++) {
			if (group->options[k].name)
				help_option(&group->options[k], f);
			else
				fprintf(f, "\n%s", group->options[k].help);
		}
	}
	if (c->outro)
		fprintf(f, "\n%s", c->outro);
}

/* One line: the mistake, then where the options are ("sandslide run
 * --help", the command's name taken from its usage line).  The whole help
 * after each mistake buried the line that mattered. */
int cli_usage_error(const struct cli_command *c, const char *fmt, ...)
{
	if (ss_comm_rank() != 0)
		return 2;
	va_list ap;
	fflush(stdout);
	fputs("sandslide: ", stderr);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	const char *name = strstr(c->usage, "sandslide ");
	const int len = name ? (int)strcspn(name + 10, " \n") : 0;
	fprintf(stderr, " (see 'sandslide %.*s%s--help')\n", len, len ? name + 10 : "",
	        len ? " " : "");
	return 2;
}

/* The option that word names ("--name", "--name=value" or the alias) as
 * group *g, index *k; its inline value, if any, into *inline_value. */
static const struct cli_option *find(const struct cli_command *c, const char *word, int *g,
                                     int *k, const char **inline_value)
{
	*inline_value = NULL;
	for (*g = 0; *g < CLI_MAX_GROUPS; ++*g) {
		for (*k = 0; *k < c->groups[*g].count; ++*k) {
			const struct cli_option *o = &c->groups[*g].options[*k];
			const size_t n = o->name ? strlen(o->name) : 0;
			if (!n)
				continue;
			if (!strcmp(word, o->name) || (o->alias && !strcmp(word, o->alias)))
				return o;
			if (o->value && !strncmp(word, o->name, n) && word[n] == '=') {
				*inline_value = word + n + 1;
				return o;
			}
		}
	}
	return NULL;
}

/* Store value into o's target; 0, or 2 after a usage error. */
static int store(struct cli_command *c, const struct cli_option *o, void *target,
                 const char *value)
{
	int bad = 0;
	switch (o->kind) {
	case CLI_INT:
		bad = ss_parse_int(value, (long)o->lo, (long)o->hi, target);
		break;
	case CLI_REAL:
		bad = ss_parse_real(value, o->lo, o->hi, target);
		break;
	case CLI_TEXT:
		*(const char **)target = value;
		break;
	case CLI_LIST: {
		struct cli_list *l = target;
		l->v[l->n++] = value;
		break;
	}
	case CLI_PARSE:
		bad = o->parse(value, target);
		break;
	case CLI_FLAG:
	case CLI_OPTIONAL_INT:
		break;
	}
	if (bad)
		return cli_usage_error(c, "%s '%s': expected %s", o->name, value, o->expected);
	return 0;
}

/* Option k of group g at argv[*k], its value taken from the word or the
 * next one; 0, or 2 after a usage error. */
static int take(struct cli_command *c, int g, int k, const char *inline_value, int argc,
                char **argv, int *at)
{
	const struct cli_option *o = &c->groups[g].options[k];
	char *base = c->groups[g].base;
	c->given[g][k] = argv[*at];
	if (o->kind == CLI_FLAG || o->kind == CLI_OPTIONAL_INT) {
		*(int *)(base + o->offset) = 1;
		if (o->kind == CLI_OPTIONAL_INT && *at + 1 < argc &&
		    ss_parse_int(argv[*at + 1], (long)o->lo, (long)o->hi,
		                  (int *)(base + o->value_offset)) == 0)
			++*at;
		return 0;
	}
	const char *value = inline_value;
	if (!value && *at + 1 < argc)
		value = argv[++*at];
	if (!value || !*value)
		return cli_usage_error(c, "%s needs %s", o->name, o->value);
	return store(c, o, base + o->offset, value);
}

int cli_parse(struct cli_command *c, int argc, char **argv, int first)
{
	c->arg_count = 0;
	memset(c->given, 0, sizeof c->given);
	for (int g = 0; g < CLI_MAX_GROUPS; g++)
		if (c->groups[g].count > CLI_MAX_OPTIONS)
			SS_BUG("an option table of %d entries", c->groups[g].count);
	for (int at = first; at < argc; at++) {
		const char *a = argv[at], *inline_value;
		int g, k;
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
		if (!find(c, a, &g, &k, &inline_value))
			return cli_usage_error(c, "unknown option '%s'", a);
		if (take(c, g, k, inline_value, argc, argv, &at))
			return 2;
	}
	return CLI_GO_ON;
}

const char *cli_given(const struct cli_command *c, const char *name)
{
	for (int g = 0; g < CLI_MAX_GROUPS; g++)
		for (int k = 0; k < c->groups[g].count; k++)
			if (c->groups[g].options[k].name &&
			    !strcmp(c->groups[g].options[k].name, name))
				return c->given[g][k];
	return NULL;
}

const char *cli_given_in(const struct cli_command *c, int g)
{
	for (int k = 0; k < c->groups[g].count; k++)
		if (c->given[g][k])
			return c->given[g][k];
	return NULL;
}
