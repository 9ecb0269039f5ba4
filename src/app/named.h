/*
 * named.h - options set by name and text value, for callers that cannot lay
 * out the options structs (relax_api.c, run_api.c; Python's ctypes).  A
 * table gives each name the field it sets, how its value is parsed and,
 * for the message, what the command line accepts there, so that a bad
 * value reads as the command line says it.
 */
#ifndef SANDSLIDE_APP_NAMED_H
#define SANDSLIDE_APP_NAMED_H

#include <stddef.h>

enum ss_named_kind {
	SS_NAMED_REAL,      /* double in [lo, hi] */
	SS_NAMED_INT,       /* int in [lo, hi] */
	SS_NAMED_FLAG,      /* int, "1" or "0" */
	SS_NAMED_TEXT,      /* const char *, a copy the options own (texts[text]) */
	SS_NAMED_WORD,      /* parse(value, field): an enum from its name */
	SS_NAMED_OWN,       /* set by the caller itself (ss_named_set refuses) */
};

struct ss_named {
	const char *name;            /* the command's option without "--" */
	enum ss_named_kind kind;
	size_t offset;               /* of the field in the options struct */
	double lo, hi;               /* REAL, INT: the accepted range */
	const char *expected;        /* what is accepted, as the command line says */
	int text;                    /* TEXT: its slot in the owner's copies */
	int (*parse)(const char *value, void *field);   /* WORD: 0 when valid */
};

struct ss_named_table {
	const char *command;         /* "relax", for "unknown relax option" */
	const struct ss_named *keys;
	size_t count;
};

/* The entry of key ('_' may stand for '-': "max_time" is "max-time"), or
 * NULL after the message "unknown CMD option 'KEY': expected one of ...". */
const struct ss_named *ss_named_find(const struct ss_named_table *t, const char *key);

/* Parse value into k's field of options; a TEXT value is copied into
 * texts[k->text] (the previous copy freed) and the field points to it.
 * SS_ERR_INPUT "KEY 'VALUE': expected ..." (options unchanged),
 * SS_ERR_FAIL out of memory. */
int ss_named_set(const struct ss_named *k, const char *key, const char *value, void *options,
                 char **texts);

/* A copy of s (ss_free), NULL with the message when out of memory. */
char *ss_named_copy(const char *s);

#endif
