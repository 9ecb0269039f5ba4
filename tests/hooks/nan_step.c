/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * nan_step.c - the test hook of the non-finite guard (src/app/drive.h),
 * linked into a second sandslide, build/tests/sandslide-nan, and never
 * into the real one.
 *
 * The CFL bound keeps heights finite, so the guard cannot be reached by any
 * input: this program puts a NaN into a height.  It is linked with
 * -Wl,--wrap=ss_stepper_advance, so every call the library's time loop
 * makes to the stepper comes here first.  With SANDSLIDE_TEST_NAN_STEP=N
 * in the environment, the height of the middle cell becomes NaN right
 * after substep N (in the progress callback, chained before the caller's),
 * as a kernel bug would leave it; without it the program is sandslide.
 * Once only: the progress callback also comes between the stages of a
 * super-step (src/core/stages.h), with the steps before it, and the
 * guard's own replay takes the steps up to the one that was not finite
 * again, which must not meet the NaN again.
 */
#include <math.h>
#include <stdlib.h>

#include "sandslide/stepper.h"

enum ss_advance_end __real_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o);
enum ss_advance_end __wrap_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o);

struct hook {
	struct ss_stepper *st;                /* the stepper being advanced */
	long long nan_step;
	const struct ss_advance_options *caller;
};

static void poison(void *context, const struct ss_stepper *seen)
{
	const struct hook *h = context;
	static int poisoned;
	if (seen->steps == h->nan_step && !poisoned) {
		poisoned = 1;
		const struct ss_grid *g = &h->st->grid;
		h->st->height[ss_grid_index(g, g->nx / 2, g->ny / 2)] = NAN;
	}
	if (h->caller->progress)
		h->caller->progress(h->caller->context, seen);
}

enum ss_advance_end __wrap_ss_stepper_advance(struct ss_stepper *st, double t_target,
                                              const struct ss_advance_options *o)
{
	const char *env = getenv("SANDSLIDE_TEST_NAN_STEP");
	if (!env || !*env)
		return __real_ss_stepper_advance(st, t_target, o);
	struct hook h = {st, atoll(env), o};
	struct ss_advance_options hooked = *o;
	hooked.progress = poison;
	hooked.context = &h;
	return __real_ss_stepper_advance(st, t_target, &hooked);
}
