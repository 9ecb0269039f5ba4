/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * sandslide.h - the whole public interface in one include, for programs
 * that link the library (pkg-config --cflags --libs sandslide):
 *
 *     #include <sandslide/sandslide.h>
 *
 * Each header says what its part does; the tiers they belong to are in
 * src/README.md.  The commands as functions (run.h, relax.h, render.h,
 * bench.h) are the usual entry points, which watch.h lets another thread
 * stop and follow; the kernel (grid.h, boundary.h, closure.h, stepper.h)
 * is for programs that drive the time loop themselves.  Every function
 * returns a status (error.h) and prints only error messages, which
 * ss_error_set_quiet() turns off in favour of ss_error_last_message() (the
 * calling thread's).
 */
#ifndef SANDSLIDE_SANDSLIDE_H
#define SANDSLIDE_SANDSLIDE_H

#include "sandslide/version.h"
#include "sandslide/error.h"
#include "sandslide/parallel.h"
#include "sandslide/option.h"
#include "sandslide/comm.h"
#include "sandslide/cpu.h"
#include "sandslide/device.h"

#include "sandslide/grid.h"
#include "sandslide/boundary.h"
#include "sandslide/closure.h"
#include "sandslide/diagnostics.h"
#include "sandslide/integrator.h"
#include "sandslide/stepper.h"
#include "sandslide/material_table.h"
#include "sandslide/model_options.h"

#include "sandslide/dem.h"
#include "sandslide/snapshot.h"
#include "sandslide/shape.h"
#include "sandslide/case.h"
#include "sandslide/progress.h"
#include "sandslide/job.h"
#include "sandslide/watch.h"

#include "sandslide/run.h"
#include "sandslide/relax.h"
#include "sandslide/fit.h"
#include "sandslide/bench.h"
#include "sandslide/render.h"
#include "sandslide/bmi.h"

#endif
