/*
 * options.h - a command's options as tables: one entry per option (name,
 * kind, where its value goes, range, help), from which its arguments are
 * parsed and its --help is written, so that the two cannot disagree.
 *
 *   --name VALUE, --name=VALUE and the alias (-o VALUE) are accepted; a
 *   word that does not start with '-' (or is "-") is an argument.
 *
 * The tables are static data: a value goes to `offset` bytes into the
 * group's base struct (cli_group), so one table (the look of frames) serves
 * two commands.  Every message is one line, "sandslide: ...", followed by
 * the command's help; a usage error is exit status 2.
 */
#ifndef SANDSLIDE_CLI_OPTIONS_H
#define SANDSLIDE_CLI_OPTIONS_H

#include <stddef.h>
#include <stdio.h>

enum cli_kind {
	CLI_FLAG,          /* int: set to 1 */
	CLI_INT,           /* int: an integer in [lo, hi] */
	CLI_REAL,          /* double: a finite number in [lo, hi] */
	CLI_TEXT,          /* const char *: the word as it is (not empty) */
	CLI_LIST,          /* struct cli_list: each word appended */
	CLI_PARSE,         /* parse(word, target) == 0 */
	CLI_OPTIONAL_INT,  /* int: set to 1 when given; the next word goes to
	                    * `value_offset` when it is an integer in [lo, hi] */
};

/* Where a CLI_LIST option collects its words (v has room for argc). */
struct cli_list {
	const char **v;
	int n;
};

struct cli_option {
	const char *name;           /* "--angle"; NULL: a heading (help only) */
	const char *alias;          /* "-o", or NULL */
	const char *value;          /* the value's name in the help, "DEG" */
	enum cli_kind kind;
	size_t offset;              /* of the target in the group's base */
	double lo, hi;              /* CLI_INT, CLI_REAL, CLI_OPTIONAL_INT */
	const char *expected;       /* what a value must be, for messages */
	const char *help;           /* lines separated by '\n' */
	int (*parse)(const char *word, void *target);   /* CLI_PARSE: 0 or -1 */
	size_t value_offset;        /* CLI_OPTIONAL_INT: where the value goes */
};

/* A table and the struct its offsets point into. */
struct cli_group {
	const struct cli_option *options;
	int count;
	void *base;
	int hidden;                 /* parsed, left out of the help */
};

enum { CLI_MAX_GROUPS = 2, CLI_MAX_OPTIONS = 64 };

struct cli_command {
	const char *usage;          /* "usage: ..." lines */
	const char *intro;          /* a paragraph after the usage, or NULL */
	struct cli_group groups[CLI_MAX_GROUPS];
	const char *outro;          /* a paragraph after the options, or NULL */
	const char *what;           /* an argument, for messages: "case file" */
	const char **args;          /* the arguments found ... */
	int max_args;               /* ... at most this many */
	/* set by cli_parse */
	int arg_count;
	const char *given[CLI_MAX_GROUPS][CLI_MAX_OPTIONS]; /* the word that
	                               gave each option, NULL if none did */
};

/* Parse argv[first..] into the targets.  Returns CLI_GO_ON, or the exit
 * status after printing the help (--help, -h: 0) or a usage error (2). */
#define CLI_GO_ON (-1)
int cli_parse(struct cli_command *c, int argc, char **argv, int first);

/* The word that gave option `name` (NULL if not given), and the first
 * word that gave an option of group g. */
const char *cli_given(const struct cli_command *c, const char *name);
const char *cli_given_in(const struct cli_command *c, int g);

/* The command's help: usage, intro, one line or more per option, outro. */
void cli_help(const struct cli_command *c, FILE *f);

/* "sandslide: MESSAGE" and the help on stderr; returns 2. */
int cli_usage_error(const struct cli_command *c, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

/* "NXxNY" into int[2], as CLI_PARSE calls it (ss_parse_tile); the
 * numbers are ss_parse_int and ss_parse_real of base/strings.h. */
int cli_parse_tile(const char *s, void *tile);

#endif
