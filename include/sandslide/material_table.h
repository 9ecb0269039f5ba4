/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * material_table.h - materials by class (doc/model.md#materials): a table of
 * [material NAME] sections, each the law of the cells of one class of a
 * class raster (`[model] materials = FILE` of a case, whose [material NAME]
 * sections are the table; relax's --materials FILE --material-table
 * FILE.ini).  A section's keys:
 *
 *   class = N            the raster's value of its cells, an integer >= 0
 *   repose_angle = DEG   its angle, degrees in (0, 90)
 *   closure = NAME       its law (default: the model's)
 *   nu = V               m^2/s > 0 (default: the model's)
 *   gamma = G            Herschel-Bulkley exponent > 0 (default: the model's)
 */
#ifndef SANDSLIDE_MATERIAL_TABLE_H
#define SANDSLIDE_MATERIAL_TABLE_H

#include "sandslide/closure.h"

enum { SS_MATERIAL_MAX = 256, SS_MATERIAL_NAME_SIZE = 64, SS_MATERIAL_WHERE_SIZE = 512 };

struct ss_material_spec {
	char name[SS_MATERIAL_NAME_SIZE];
	char where[SS_MATERIAL_WHERE_SIZE];   /* "file:line" of its section */
	long long class_value;                /* -1: not given */
	double angle_deg;                     /* NaN: not given */
	double static_deg;                    /* hysteresis; NaN: angle_deg */
	int has_closure;
	enum ss_closure_kind closure;
	double nu, gamma;                     /* NaN: the model's */
};

struct ss_material_table {
	struct ss_material_spec item[SS_MATERIAL_MAX];
	int count;
};

/* key = value of section [material NAME] (name: NAME) at `where`: the
 * material is made on its first key.  SS_ERR_INPUT with a message naming
 * where, the key and what it accepts. */
int ss_material_table_set(struct ss_material_table *t, const char *name, const char *key,
                          const char *value, const char *where);

/* "material NAME" -> NAME (letters, digits, _ and -), or NULL. */
const char *ss_material_section(const char *section);

/* A table file of [material NAME] sections only (relax's --material-table)
 * into *t (zeroed first). */
int ss_material_table_read(struct ss_material_table *t, const char *path);

/* Every material has class and repose_angle, and no two the same class;
 * `what` names the table in messages. */
int ss_material_table_check(const struct ss_material_table *t, const char *what);

#endif
