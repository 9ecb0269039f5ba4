/*
 * integrator.c - integrators by name, and auto's rule (integrator.h).
 */
#include "sandslide/integrator.h"

#include <string.h>

static const char *const integrator_names[] = {
	[SS_INTEGRATOR_EULER] = "euler", [SS_INTEGRATOR_RKL2] = "rkl2",
	[SS_INTEGRATOR_AUTO] = "auto",
};

const char *ss_integrator_name(enum ss_integrator integrator)
{
	return integrator_names[integrator];
}

int ss_integrator_parse(const char *name, enum ss_integrator *out)
{
	for (int k = 0; k < 3; k++) {
		if (strcmp(name, integrator_names[k]) == 0) {
			*out = (enum ss_integrator)k;
			return 0;
		}
	}
	return -1;
}

enum ss_integrator ss_integrator_resolve(enum ss_integrator asked, int has_bedrock)
{
	if (asked != SS_INTEGRATOR_AUTO)
		return asked;
	return has_bedrock ? SS_INTEGRATOR_EULER : SS_INTEGRATOR_RKL2;
}
