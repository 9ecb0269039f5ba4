/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * material_table.c - [material NAME] sections (see material_table.h): set
 * key by key, from a case (case.c) or a table file of their own (relax's
 * --material-table), and checked as a whole.
 */
#include "sandslide/material_table.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ini.h>

#include "base/strings.h"
#include "sandslide/error.h"

const char *ss_material_section(const char *section)
{
	static const char prefix[] = "material ";
	if (strncmp(section, prefix, sizeof prefix - 1) != 0)
		return NULL;
	const char *name = section + sizeof prefix - 1;
	while (*name == ' ')
		name++;
	if (!*name || strlen(name) >= SS_MATERIAL_NAME_SIZE)
		return NULL;
	for (const char *q = name; *q; q++)
		if (!isalnum((unsigned char)*q) && *q != '_' && *q != '-')
			return NULL;
	return name;
}

static struct ss_material_spec *find(struct ss_material_table *t, const char *name,
                                     const char *where)
{
	for (int k = 0; k < t->count; k++)
		if (!strcmp(t->item[k].name, name))
			return &t->item[k];
	if (t->count >= SS_MATERIAL_MAX) {
		ss_error_input("%s: more than %d materials", where, SS_MATERIAL_MAX);
		return NULL;
	}
	struct ss_material_spec *m = &t->item[t->count++];
	memset(m, 0, sizeof *m);
	snprintf(m->name, sizeof m->name, "%s", name);
	snprintf(m->where, sizeof m->where, "%s", where);
	m->class_value = -1;
	m->angle_deg = m->static_deg = m->nu = m->gamma = NAN;
	return m;
}

int ss_material_table_set(struct ss_material_table *t, const char *name, const char *key,
                          const char *value, const char *where)
{
	struct ss_material_spec *m = find(t, name, where);
	if (!m)
		return SS_ERR_INPUT;
	double x;
	if (!strcmp(key, "class")) {
		int v;
		if (ss_parse_int(value, 0, 2147483647L, &v))
			return ss_error_input("%s: [material %s] class = '%s': expected an integer >= 0 "
			                      "(the class raster's value of its cells)", where, name,
			                      value);
		m->class_value = v;
	} else if (!strcmp(key, "repose_angle") || !strcmp(key, "static_angle")) {
		if (ss_parse_real(value, 0.0, 90.0, &x) || x == 0.0 || x == 90.0)
			return ss_error_input("%s: [material %s] %s = '%s': expected degrees in (0, 90)",
			                      where, name, key, value);
		*(key[0] == 'r' ? &m->angle_deg : &m->static_deg) = x;
	} else if (!strcmp(key, "closure")) {
		if (ss_closure_parse(value, &m->closure))
			return ss_error_input("%s: [material %s] closure = '%s': expected "
			                      SS_CLOSURE_NAMES, where, name, value);
		m->has_closure = 1;
	} else if (!strcmp(key, "nu") || !strcmp(key, "gamma")) {
		if (ss_parse_real(value, 0.0, INFINITY, &x) || x == 0.0)
			return ss_error_input("%s: [material %s] %s = '%s': expected a finite number "
			                      "> 0", where, name, key, value);
		*(key[0] == 'n' ? &m->nu : &m->gamma) = x;
	} else {
		return ss_error_input("%s: unknown key '%s' in [material %s]: expected class, "
		                      "repose_angle, static_angle, closure, nu, gamma", where, key,
		                      name);
	}
	return SS_OK;
}

struct table_file {
	struct ss_material_table *t;
	const char *path;
	int failed;
};

static int on_key(void *user, const char *section, const char *key, const char *value)
{
	struct table_file *f = user;
	if (f->failed)
		return 1;
	char where[SS_MATERIAL_WHERE_SIZE];
	snprintf(where, sizeof where, "%s", f->path);
	const char *name = ss_material_section(section);
	int err = name ? ss_material_table_set(f->t, name, key, value, where)
	               : ss_error_input("%s: unknown section [%s]: a material table holds "
	                                "[material NAME] sections only", f->path, section);
	f->failed = err != SS_OK;
	return 1;
}

int ss_material_table_read(struct ss_material_table *t, const char *path)
{
	memset(t, 0, sizeof *t);
	FILE *in = fopen(path, "r");
	if (!in)
		return ss_error_input("cannot open the material table '%s': %s", path,
		                      strerror(errno));
	struct table_file f = {t, path, 0};
	const int line = ini_parse_file(in, on_key, &f);
	fclose(in);
	if (f.failed)
		return SS_ERR_INPUT;
	if (line != 0)
		return ss_error_input("%s:%d: not 'key = value' or '[material NAME]'", path, line);
	return t->count ? SS_OK
	                : ss_error_input("%s: no [material NAME] section", path);
}

int ss_material_table_check(const struct ss_material_table *t, const char *what)
{
	for (int k = 0; k < t->count; k++) {
		const struct ss_material_spec *m = &t->item[k];
		if (m->class_value < 0 || isnan(m->angle_deg))
			return ss_error_input("%s: [material %s] needs class and repose_angle (%s)",
			                      m->where, m->name, what);
		for (int e = 0; e < k; e++)
			if (t->item[e].class_value == m->class_value)
				return ss_error_input("%s: [material %s] has class %lld, as [material %s] "
				                      "has: each class one material", m->where, m->name,
				                      m->class_value, t->item[e].name);
		if (m->static_deg < m->angle_deg)
			return ss_error_input("%s: [material %s] static_angle %g is below its "
			                      "repose_angle %g: sand at rest starts to slide at an angle "
			                      "at least the one where moving sand stops "
			                      "(doc/model.md#hysteresis)", m->where, m->name,
			                      m->static_deg, m->angle_deg);
	}
	return t->count ? SS_OK : ss_error_input("%s: no [material NAME] section", what);
}
