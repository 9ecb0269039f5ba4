/*
 * options.h - a command's options as a table: one entry per option (name,
 * kind, target, range, help), from which its arguments are parsed and its
 * --help is written, so that the two cannot disagree.
 *
 *   --name VALUE, --name=VALUE, and the alias (-o VALUE) are accepted;
 *   a word that does not start with '-' (or is "-") is an argument.
 *
 * Every message is one line, "sandslide: ...", followed by the command's
 * help; the exit status of a usage error is 2.
 */
#ifndef SANDSLIDE_CLI_OPTIONS_H
#define SANDSLIDE_CLI_OPTIONS_H

#include <stdio.h>

enum cli_kind {
	CLI_FLAG,          /* int *: set to 1 */
	CLI_INT,           /* int *: an integer in [lo, hi] */
	CLI_REAL,          /* double *: a finite number in [lo, hi] */
	CLI_TEXT,          /* const char **: the word as it is (not empty) */
	CLI_LIST,          /* struct cli_list *: each word appended */
	CLI_PARSE,         /* parse(word, target) == 0 */
	CLI_OPTIONAL_INT,  /* struct cli_optional_int *: the next word is the
	                    * value when it is an integer in [lo, hi] */
};

struct cli_optional_int {
	int given;
	int value;          /* left as it was when no value follows */
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
	void *target;
	double lo, hi;              /* CLI_INT, CLI_REAL, CLI_OPTIONAL_INT */
	const char *expected;       /* what a value must be, for messages */
	const char *help;           /* lines separated by '\n' */
	int (*parse)(const char *word, void *target);   /* CLI_PARSE: 0 or -1 */
	int *given;                 /* set to 1 when the option is given */
	int hidden;                 /* parsed, left out of the help */
};

struct cli_command {
	const char *usage;          /* "usage: ..." lines */
	const char *intro;          /* a paragraph after the usage, or NULL */
	const struct cli_option *options;
	int option_count;
	const char *outro;          /* a paragraph after the options, or NULL */
	const char *what;           /* the arguments, for messages: "a case file" */
	const char **args;          /* the arguments found ... */
	int max_args;               /* ... at most this many */
	int arg_count;
};

/* Parse argv[first..] into the targets.  Returns CLI_GO_ON, or the exit
 * status after printing the help (--help, -h: 0) or a usage error (2). */
#define CLI_GO_ON (-1)
int cli_parse(struct cli_command *c, int argc, char **argv, int first);

/* The command's help: usage, intro, one line or more per option, outro. */
void cli_help(const struct cli_command *c, FILE *f);

/* "sandslide: MESSAGE" and the help on stderr; returns 2. */
int cli_usage_error(const struct cli_command *c, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

/* Parsers for CLI_PARSE and the command code: 0, or -1 if malformed. */
int cli_parse_int(const char *s, long lo, long hi, int *out);
int cli_parse_real(const char *s, double lo, double hi, double *out);
int cli_parse_tile(const char *s, void *tile);   /* "NXxNY" into int[2] */

#endif
