/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * option.h - a command's options as one table: for each option its name,
 * kind, where its value goes, default, range, help, and the case-file key
 * it also is.  Everything else is made from the tables: the command line's
 * parser and --help (src/cli/), the options objects set by name of the
 * library's foreign-function callers (ss_option_object_set),
 * the case file's keys that are the same options (model_options.h), the
 * Python module's defaults (it asks ss_option_table_json), and the man
 * page's options (the --help as roff, filled into doc/sandslide.1.in).
 * doc/running.md#options says what users see of it.
 *
 * A value is always text, as a user types it ("35", "coulomb", "1e-9"), so
 * that a default, a command-line word, a case-file value and a Python
 * keyword are read by the same code and refused with the same message.
 */
#ifndef SANDSLIDE_OPTION_H
#define SANDSLIDE_OPTION_H

#include <stddef.h>

enum ss_option_kind {
	SS_OPTION_FLAG,    /* int 0 or 1: a bare --name on the command line,
	                    * "1" or "0" by name */
	SS_OPTION_INT,     /* int in lo..hi */
	SS_OPTION_REAL,    /* finite double in lo..hi (each end open or closed) */
	SS_OPTION_TEXT,    /* const char *, not empty (a path, a text) */
	SS_OPTION_WORD,    /* parse(value, field) == 0: a name from a list, a
	                    * shape, a pair of numbers */
	SS_OPTION_LIST,    /* may be given many times: each word, when
	                    * parse(value, NULL) == 0 (or there is no parse),
	                    * is appended to the struct ss_option_list at
	                    * offset (run's --set) */
	SS_OPTION_OPTIONAL_INT, /* int set to 1 when given; the next word, when
	                    * an integer in lo..hi, goes to value_offset
	                    * (render --bench [N]) */
};

/* Bits of ss_option.flags. */
enum {
	SS_OPTION_LO_OPEN = 1,     /* REAL: lo itself is not accepted */
	SS_OPTION_HI_OPEN = 2,     /* REAL: hi itself is not accepted */
	SS_OPTION_CLI_ONLY = 4,    /* not settable by name (foreign callers) */
	SS_OPTION_NAMED_ONLY = 8,  /* not on the command line (e.g. history) */
	SS_OPTION_CASE_REQUIRED = 16, /* a case file must give it (the
	                            * command line's default does not apply
	                            * there) */
	SS_OPTION_FITTABLE = 32,   /* `sandslide fit` may free it (--param
	                            * NAME=LO:HI, NAME its case key's); the
	                            * model's table */
	SS_OPTION_OR_FILE = 64,    /* REAL: a value that does not start as a
	                            * number is a file name, kept (const
	                            * char *) at value_offset; a number
	                            * clears it ("30x" is refused: ./30x is
	                            * the file) */
};

struct ss_option {
	const char *name;          /* "max-time": --max-time on the command line,
	                            * "max-time" or "max_time" by name; NULL: a
	                            * heading in the help (help holds it) */
	const char *alias;         /* "-o", or NULL */
	const char *case_key;      /* "time.max_time": the case file's key for the
	                            * same option, or NULL */
	const char *value_name;    /* "T" in "--max-time T"; NULL for a flag */
	enum ss_option_kind kind;
	size_t offset;             /* of the value in the table's struct */
	const char *default_value; /* as a user would type it, or NULL: none
	                            * (REAL: NaN, INT and FLAG: 0, TEXT: NULL;
	                            * the help says what none means) */
	double lo, hi;             /* INT, REAL */
	unsigned flags;
	const char *expected;      /* what a value must be, for messages */
	const char *help;          /* lines separated by '\n', without the
	                            * default (the help adds it) */
	int (*parse)(const char *value, void *field); /* WORD: 0 when valid */
	size_t value_offset;       /* OPTIONAL_INT: where its value goes;
	                            * REAL with SS_OPTION_OR_FILE: its file */
	unsigned applies_to;       /* bit k: it means something for variant k
	                            * of its table's model (the model's: closure
	                            * k, closure.h); 0: for every variant */
};

/* The range of a REAL option that takes any finite number > 0, for a
 * table's designated initialiser: {..., SS_OPTION_POSITIVE, ...} (with no
 * other .flags). */
#define SS_OPTION_POSITIVE .lo = 0.0, .hi = INFINITY, .flags = SS_OPTION_LO_OPEN

/* A table that continues another at the offset of its struct in the
 * other's: relax's table goes on with the model's (at relax's `model`) and
 * the job's (at its `job`), so that a group of options shared by commands
 * is written once. */
struct ss_option_part {
	const struct ss_option_table *table;
	size_t offset;
};

struct ss_option_table {
	const char *command;       /* "relax", for "unknown relax option" */
	const struct ss_option *options;
	int count;
	const struct ss_option_part *parts;  /* tables that continue this one,
	                                      * in order (their own parts too) */
	int part_count;
	/* for options objects on the heap (ss_option_object_create): the
	 * size of the table's struct and what sets it to its defaults (NULL:
	 * zeros, then the table's defaults) */
	size_t size;
	void (*init)(void *base);
};

/* The tables are objects beside each command's options struct:
 * ss_relax_option_table (relax.h), ss_run_option_table (run.h),
 * ss_fit_option_table (fit.h), ss_bench_option_table (bench.h),
 * ss_render_option_table and ss_render_look_option_table (render.h),
 * ss_model_option_table (model_options.h), ss_job_option_table (job.h),
 * ss_case_option_table (case.h). */

/* Every option of t and of the tables that continue it, in order (t's own
 * first, then each part's, depth first) into option[], with the offset of
 * its struct in t's struct into offset[]; returns how many (SS_BUG beyond
 * SS_OPTION_MAX: the tables are the library's). */
enum { SS_OPTION_MAX = 160 };
int ss_option_flatten(const struct ss_option_table *t, const struct ss_option *option[],
                      size_t offset[]);

/* A LIST option's field: the words given, in order (the caller's
 * strings, or an options object's copies). */
struct ss_option_list {
	const char **items;
	int count, room;
};
/* item appended (the pointer kept, not a copy); SS_ERR_FAIL out of memory. */
int ss_option_list_append(struct ss_option_list *l, const char *item);
void ss_option_list_release(struct ss_option_list *l);

/* The option named name ('_' may stand for '-': "max_time") of t or of the
 * tables that continue it, with the offset of its table's struct in t's
 * (*offset); NULL if none has that name. */
const struct ss_option *ss_option_find(const struct ss_option_table *t, const char *name,
                                       size_t *offset);

/* The option whose case_key is key ("model.repose_angle"), as
 * ss_option_find; NULL if none. */
const struct ss_option *ss_option_find_key(const struct ss_option_table *t, const char *key,
                                           size_t *offset);

/* value read as o reads it into field (the option's place in its struct):
 * 0, or -1 when it is not a value o accepts (field unchanged).  TEXT
 * stores the pointer itself (its owner copies it if it must); LIST and
 * FLAG by name ("1" or "0") are the caller's, as are an empty value. */
int ss_option_parse(const struct ss_option *o, const char *value, void *field);

/* Every option of t (and of the tables that continue it) that has a
 * default set to it in base, the others to none (see default_value).
 * SS_BUG when a default is not a value of its option: the tables are
 * tested. */
void ss_option_defaults(const struct ss_option_table *t, void *base);

/* The LIST options of the struct at base released (their lists' storage,
 * not the strings): what a caller that parsed into a struct of its own
 * (the command line) does when done with it. */
void ss_option_release(const struct ss_option_table *t, void *base);

/*
 * Options on the heap, set by name, for callers that cannot lay out the
 * struct (a foreign-function interface such as Python's ctypes; the
 * structs change between versions, the names do not).  create returns
 * t's struct (t->size bytes) at its defaults (t->init, else the table's),
 * or NULL (message printed) when out of memory; the caller passes it to
 * the command's function (ss_relax_run, ss_run_case_json, ...).
 *
 * set checks value as the command line does: SS_ERR_INPUT "unknown relax
 * option 'x': expected one of ..." or "KEY 'VALUE': expected ...", the
 * options unchanged; SS_ERR_FAIL out of memory.  Keys are the options'
 * names ('_' may stand for '-'); a flag takes "1" or "0"; a LIST option
 * (run's set and unset, fit's param) adds one more word each time; TEXT
 * and LIST values are copied.  An option flagged SS_OPTION_CLI_ONLY is
 * unknown by name.  destroy(NULL) does nothing.
 */
void *ss_option_object_create(const struct ss_option_table *t);
int ss_option_object_set(void *options, const char *key, const char *value);
void ss_option_object_destroy(void *options);

/* "angle, closure, ..." of t and the tables that continue it (the names
 * settable by name), into buf: what "unknown option" messages list. */
void ss_option_names(const struct ss_option_table *t, char *buf, size_t size);

/* The table as JSON into buf (size bytes, NUL-terminated): a list of
 * {"name", "case_key", "kind", "default", "lo", "hi", "expected",
 * "help"}, one per option of t and of the tables that continue it, for a
 * foreign caller that takes its defaults and checks from the library (the
 * Python module).  SS_ERR_INPUT when it does not fit (the message says how
 * many bytes it needs). */
int ss_option_table_json(const struct ss_option_table *t, char *buf, size_t size);


#endif
