/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * options.h - parsing a command's arguments from its option tables (the
 * library's, sandslide/option.h, and the command line's own few: --quiet,
 * --json, ...), and the --help made from the same tables, so that the two
 * cannot disagree; the man page's options are that help as roff.
 *
 *   --name VALUE, --name=VALUE and the alias (-o VALUE) are accepted; a
 *   word that does not start with '-' (or is "-") is an argument.
 *
 * Options flagged SS_OPTION_NAMED_ONLY are not on the command line.  Every
 * message is one line, "sandslide: ... (see 'sandslide CMD --help')"; a
 * usage error is exit status 2.
 */
#ifndef SANDSLIDE_CLI_OPTIONS_H
#define SANDSLIDE_CLI_OPTIONS_H

#include <stddef.h>
#include <stdio.h>

#include "sandslide/option.h"

/* A table and the struct its offsets point into. */
struct cli_group {
	const struct ss_option_table *table;   /* its parts become groups of
	                                        * their own */
	void *base;
	int hidden;                 /* parsed, left out of the help */
};

enum { CLI_MAX_GROUPS = 6, CLI_MAX_OPTIONS = 64 };

struct cli_command {
	const char *usage;          /* "usage: ..." lines */
	const char *intro;          /* a paragraph after the usage, or NULL */
	struct cli_group groups[CLI_MAX_GROUPS];
	const char *outro;          /* a paragraph after the options, or NULL */
	const char *what;           /* an argument, for messages: "case file" */
	const char **args;          /* the arguments found ... */
	int max_args;               /* ... at most this many */
	/* set by cli_parse */
	int group_count;
	int arg_count;
	const char *given[CLI_MAX_GROUPS][CLI_MAX_OPTIONS]; /* the word that
	                               gave each option, NULL if none did */
};

/* Parse argv[first..] into the targets.  Returns CLI_GO_ON, or the exit
 * status after printing the help (--help, -h: 0) or a usage error (2). */
#define CLI_GO_ON (-1)
int cli_parse(struct cli_command *c, int argc, char **argv, int first);

/* The word that gave option `name` ("--output"; NULL if not given), and
 * the first word that gave an option of table t (a group of the command). */
const char *cli_given(const struct cli_command *c, const char *name);
const char *cli_given_in(const struct cli_command *c, const struct ss_option_table *t);

/* The command's help: usage, intro, one line or more per option with its
 * default, outro. */
void cli_help(const struct cli_command *c, FILE *f);

/* The command's options as man(7) roff, for its man page: each option the
 * help shows a .TP entry (bold names, the value in italics, its text and
 * default as the help gives them), each heading a paragraph, in the
 * help's order, each after a comment that names it (.\" option --NAME,
 * .\" heading) for doc/manpage.awk, which puts the page's notes after
 * their options.  The usage, intro and outro are left to the page's own
 * words (doc/sandslide.1.in). */
void cli_help_roff(const struct cli_command *c, FILE *f);

/* What -h and --help print from then on: cli_help (roff 0, the default) or
 * cli_help_roff (1: `sandslide help --roff CMD`, which the Makefile runs to
 * make the man page). */
void cli_help_set_roff(int roff);

/* "sandslide: MESSAGE (see 'sandslide CMD --help')" on stderr; returns 2. */
int cli_usage_error(const struct cli_command *c, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

#endif
