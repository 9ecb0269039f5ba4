/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * options.c - arguments parsed from the option tables, and their help (see
 * options.h).
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
/* Lines of help end before this column. */
#define HELP_WIDTH 80

static int on_command_line(const struct ss_option *o)
{
	return o->name && !(o->flags & SS_OPTION_NAMED_ONLY);
}

/* The tables that continue each group's, as groups of their own, right
 * after it (depth first): a table's parts are parsed and shown like its
 * own options. */
static void expand(struct cli_command *c)
{
	if (c->group_count)
		return;
	struct cli_group given[CLI_MAX_GROUPS];
	int count = 0, n = 0;
	while (count < CLI_MAX_GROUPS && c->groups[count].table)
		count++;
	memcpy(given, c->groups, (size_t)count * sizeof *given);
	/* a stack of the groups still to place, the next on top */
	struct cli_group stack[CLI_MAX_GROUPS];
	int top = 0;
	for (int g = count - 1; g >= 0; g--)
		stack[top++] = given[g];
	while (top > 0) {
		const struct cli_group from = stack[--top];
		if (n == CLI_MAX_GROUPS)
			SS_BUG("a command of more than %d option groups", CLI_MAX_GROUPS);
		c->groups[n++] = from;
		for (int p = from.table->part_count - 1; p >= 0; p--) {
			if (top == CLI_MAX_GROUPS)
				SS_BUG("a command of more than %d option groups", CLI_MAX_GROUPS);
			stack[top++] = (struct cli_group){
				from.table->parts[p].table,
				(char *)from.base + from.table->parts[p].offset, from.hidden,
			};
		}
	}
	c->group_count = n;
}

/* The option's text over the continuation lines, HELP_COLUMN indented,
 * with " (default X)" after it, on the last line if it fits there. */
static void help_lines(const struct ss_option *o, FILE *f)
{
	const char *text = o->help ? o->help : "";
	char last[256];
	const char *p = text;
	for (;;) {
		const size_t n = strcspn(p, "\n");
		if (!p[n] || !p[n + 1]) {   /* the last line */
			snprintf(last, sizeof last, "%.*s", (int)n, p);
			break;
		}
		fprintf(f, "%.*s\n%*s", (int)n, p, HELP_COLUMN, "");
		p += n + 1;
	}
	if (!o->default_value) {
		fprintf(f, "%s\n", last);
		return;
	}
	char tail[128];
	snprintf(tail, sizeof tail, "(default %s)", o->default_value);
	if (HELP_COLUMN + strlen(last) + 1 + strlen(tail) < HELP_WIDTH)
		fprintf(f, "%s%s%s\n", last, *last ? " " : "", tail);
	else
		fprintf(f, "%s\n%*s%s\n", last, HELP_COLUMN, "", tail);
}

/* One option's lines of help. */
static void help_option(const struct ss_option *o, FILE *f)
{
	char left[64];
	snprintf(left, sizeof left, "%s%s--%s%s%s", o->alias ? o->alias : "",
	         o->alias ? ", " : "", o->name, o->value_name ? " " : "",
	         o->value_name ? o->value_name : "");
	if (strlen(left) + 3 <= HELP_COLUMN)
		fprintf(f, "  %-*s", HELP_COLUMN - 2, left);
	else
		fprintf(f, "  %s\n%*s", left, HELP_COLUMN, "");
	help_lines(o, f);
}

/* What the help shows of the options, in order: each option of the
 * command line and each heading of the groups not hidden.  The plain help
 * and the man page's roff are this one walk. */
static void help_walk(const struct cli_command *c, FILE *f,
                      void (*option)(const struct ss_option *o, FILE *f),
                      void (*heading)(const char *text, FILE *f))
{
	for (int g = 0; g < c->group_count; g++) {
		const struct cli_group *group = &c->groups[g];
		for (int k = 0; k < group->table->count && !group->hidden; k++) {
			const struct ss_option *o = &group->table->options[k];
			if (on_command_line(o))
				option(o, f);
			else if (!o->name && !o->case_key)
				heading(o->help, f);
		}
	}
}

static void help_heading(const char *text, FILE *f)
{
	fprintf(f, "\n%s", text);
}

void cli_help(const struct cli_command *c, FILE *f)
{
	fputs(c->usage, f);
	if (c->intro)
		fprintf(f, "\n%s", c->intro);
	fputc('\n', f);
	help_walk(c, f, help_option, help_heading);
	if (c->outro)
		fprintf(f, "\n%s", c->outro);
}

/* ---- the same as man(7) roff ---------------------------------------------- */

/* n characters of s, escaped for roff: a backslash, every hyphen as \-
 * (an option's name must copy as ASCII, not as a typographic hyphen), and
 * quotes that must stay straight for a shell. */
static void roff_put(const char *s, size_t n, FILE *f)
{
	for (size_t k = 0; k < n; k++) {
		const char c = s[k];
		const char *escape = c == '\\' ? "\\e" : c == '-' ? "\\-"
		                   : c == '\'' ? "\\(aq" : c == '`' ? "\\(ga" : NULL;
		if (escape)
			fputs(escape, f);
		else
			fputc(c, f);
	}
}

/* text's '\n'-separated lines (the help's, laid out for a terminal) as
 * one line of roff text, without the line's end: the indentation dropped,
 * the lines joined by a blank, so that roff fills them and takes no line's
 * last word for the end of a sentence ("e.g."); \& first when roff would
 * take the line for a request.  Returns how many lines it wrote. */
static int roff_line(const char *text, FILE *f)
{
	int words = 0;
	for (const char *p = text; *p;) {
		p += strspn(p, " \t");
		const size_t n = strcspn(p, "\n");
		if (n) {
			if (words++)
				fputc(' ', f);
			else if (*p == '.' || *p == '\'')
				fputs("\\&", f);
			roff_put(p, n, f);
		}
		p += n + (p[n] == '\n');
	}
	return words;
}

/* ".TP" with the names in bold and the value in italics, then the text
 * and the default as the help gives them. */
static void roff_option(const struct ss_option *o, FILE *f)
{
	fprintf(f, ".\\\" option --%s\n.TP\n", o->name);
	if (o->alias) {
		fputs("\\fB", f);
		roff_put(o->alias, strlen(o->alias), f);
		fputs("\\fR, ", f);
	}
	fputs("\\fB\\-\\-", f);
	roff_put(o->name, strlen(o->name), f);
	fputs("\\fR", f);
	if (o->value_name) {
		fputs(" \\fI", f);
		roff_put(o->value_name, strlen(o->value_name), f);
		fputs("\\fR", f);
	}
	fputc('\n', f);
	const int text = roff_line(o->help ? o->help : "", f);
	if (o->default_value) {
		fputs(text ? " (default " : "(default ", f);
		roff_put(o->default_value, strlen(o->default_value), f);
		fputc(')', f);
	}
	if (text || o->default_value)
		fputc('\n', f);
}

static void roff_heading(const char *text, FILE *f)
{
	fputs(".\\\" heading\n.PP\n", f);
	if (roff_line(text, f))
		fputc('\n', f);
}

void cli_help_roff(const struct cli_command *c, FILE *f)
{
	help_walk(c, f, roff_option, roff_heading);
}

/* What -h and --help print: cli_help, or cli_help_roff after
 * cli_help_set_roff(1).  The program's, set before a command parses. */
static int help_roff;

void cli_help_set_roff(int roff)
{
	help_roff = roff;
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
static const struct ss_option *find(const struct cli_command *c, const char *word, int *g,
                                    int *k, const char **inline_value)
{
	*inline_value = NULL;
	for (*g = 0; *g < c->group_count; ++*g) {
		const struct ss_option_table *t = c->groups[*g].table;
		for (*k = 0; *k < t->count; ++*k) {
			const struct ss_option *o = &t->options[*k];
			if (!on_command_line(o))
				continue;
			const size_t n = strlen(o->name);
			if (o->alias && !strcmp(word, o->alias))
				return o;
			if (strncmp(word, "--", 2) || strncmp(word + 2, o->name, n))
				continue;
			if (!word[2 + n])
				return o;
			if (o->value_name && word[2 + n] == '=') {
				*inline_value = word + 3 + n;
				return o;
			}
		}
	}
	return NULL;
}

/* Store value into o's field; 0, or 2 after a usage error. */
static int store(struct cli_command *c, const struct ss_option *o, void *field,
                 const char *value)
{
	if (o->kind == SS_OPTION_LIST ? o->parse && o->parse(value, NULL)
	                              : ss_option_parse(o, value, field))
		return cli_usage_error(c, "--%s '%s': expected %s", o->name, value, o->expected);
	if (o->kind == SS_OPTION_LIST && ss_option_list_append(field, value))
		return 1;   /* out of memory, printed */
	return 0;
}

/* Option k of group g at argv[*at], its value taken from the word or the
 * next one; 0, or 2 after a usage error. */
static int take(struct cli_command *c, int g, int k, const char *inline_value, int argc,
                char **argv, int *at)
{
	const struct ss_option *o = &c->groups[g].table->options[k];
	char *base = c->groups[g].base;
	c->given[g][k] = argv[*at];
	if (o->kind == SS_OPTION_FLAG || o->kind == SS_OPTION_OPTIONAL_INT) {
		*(int *)(base + o->offset) = 1;
		if (o->kind == SS_OPTION_OPTIONAL_INT && *at + 1 < argc &&
		    ss_parse_int(argv[*at + 1], (long)o->lo, (long)o->hi,
		                 (int *)(base + o->value_offset)) == 0)
			++*at;
		return 0;
	}
	const char *value = inline_value;
	if (!value && *at + 1 < argc)
		value = argv[++*at];
	if (!value || !*value)
		return cli_usage_error(c, "--%s needs %s", o->name, o->value_name);
	return store(c, o, base + o->offset, value);
}

int cli_parse(struct cli_command *c, int argc, char **argv, int first)
{
	expand(c);
	c->arg_count = 0;
	memset(c->given, 0, sizeof c->given);
	for (int g = 0; g < c->group_count; g++)
		if (c->groups[g].table->count > CLI_MAX_OPTIONS)
			SS_BUG("an option table of %d entries", c->groups[g].table->count);
	for (int at = first; at < argc; at++) {
		const char *a = argv[at], *inline_value;
		int g, k;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			(help_roff ? cli_help_roff : cli_help)(c, stdout);
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
	for (int g = 0; g < c->group_count; g++) {
		const struct ss_option_table *t = c->groups[g].table;
		for (int k = 0; k < t->count; k++)
			if (t->options[k].name && !strncmp(name, "--", 2) &&
			    !strcmp(t->options[k].name, name + 2))
				return c->given[g][k];
	}
	return NULL;
}

const char *cli_given_in(const struct cli_command *c, const struct ss_option_table *t)
{
	for (int g = 0; g < c->group_count; g++)
		for (int k = 0; k < c->groups[g].table->count && c->groups[g].table == t; k++)
			if (c->given[g][k])
				return c->given[g][k];
	return NULL;
}
