/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * cpu_paths.h - the kernel's hot loops compiled once per instruction-set
 * path (include/sandslide/cpu.h), and the calls that choose one.
 *
 * face.c and sweep_fast.c are compiled as themselves for the generic path
 * (the build's baseline instruction set) and, on x86-64, twice more
 * (Makefile, KERNEL_PATHS): with -DSS_PATH=SS_PATH_AVX2 and -mavx2 into
 * FILE-avx2.o, with -DSS_PATH=SS_PATH_AVX512 and AVX-512 F, CD, VL, BW, DQ
 * into FILE-avx512.o.  Each copy names its entry points with its suffix
 * (SS_PATH_FN: ss_sweep_fast_step_avx2, ...); the generic copy also holds
 * the public functions, which call the copy of the path in use
 * (SS_PATH_CALL), once per sweep or per row of faces, never per face of a
 * fast sweep.
 *
 * The bits: the face flux of the AVX-512 copy takes its reciprocal square
 * roots from vrsqrt14pd and two Newton steps, the others from 1/sqrt (face.h).
 * Everything else is the same IEEE operations, each rounded once, in every
 * copy (no FMA contraction: -ffp-contract=off), whatever instructions carry
 * them: the generic and AVX2 paths give the same bits, the AVX-512 path its
 * own, and each the same for any thread count and tile size.
 */
#ifndef SANDSLIDE_CORE_CPU_PATHS_H
#define SANDSLIDE_CORE_CPU_PATHS_H

#include "sandslide/cpu.h"
#include "core/face.h"
#include "core/sweep.h"

#define SS_PATH_GENERIC 0
#define SS_PATH_AVX2 1
#define SS_PATH_AVX512 2

/* the path this copy is compiled for (the Makefile sets it) */
#ifndef SS_PATH
#define SS_PATH SS_PATH_GENERIC
#endif

/* name_generic, name_avx2 or name_avx512: this copy's entry point */
#if SS_PATH == SS_PATH_AVX512
#define SS_PATH_FN(name) name##_avx512
#elif SS_PATH == SS_PATH_AVX2
#define SS_PATH_FN(name) name##_avx2
#else
#define SS_PATH_FN(name) name##_generic
#endif

/*
 * fn_PATH(...) of the path p (an enum ss_cpu_path), for the generic copy's
 * public functions.  SS_KERNEL_PATHS: the Makefile compiled the AVX2 and
 * AVX-512 copies (x86-64); without it only the generic one exists, and
 * ss_cpu_path() is always generic.
 */
#ifdef SS_KERNEL_PATHS
#define SS_PATH_CALL(p, fn, ...) \
	((p) == SS_CPU_AVX512 ? fn##_avx512(__VA_ARGS__) \
	 : (p) == SS_CPU_AVX2 ? fn##_avx2(__VA_ARGS__) : fn##_generic(__VA_ARGS__))
#else
#define SS_PATH_CALL(p, fn, ...) ((void)(p), fn##_generic(__VA_ARGS__))
#endif

/* Each path's entry points: those of face.h and sweep.h of the same name
 * without the suffix. */
#define SS_PATH_PROTOTYPES(sfx)                                                          \
	int ss_face_fluxes##sfx(const struct ss_face_rule *r, int n,                         \
	                        const double *restrict g_n, const double *restrict g_t,      \
	                        double *restrict flux);                                      \
	int ss_face_fluxes_mixed##sfx(const struct ss_face_table *t, int n,                  \
	                              const uint16_t *restrict rule,                         \
	                              const double *restrict g_n, const double *restrict g_t, \
	                              double *restrict flux);                                \
	void ss_face_rsqrt##sfx(int n, const double *restrict x, double *restrict y);        \
	double ss_sweep_max_slope##sfx(const struct ss_grid *g, const double *restrict height, \
	                               const uint8_t *restrict cell_types);                  \
	double ss_sweep_max_sand_slope##sfx(const struct ss_grid *g,                         \
	                                    const double *restrict height,                   \
	                                    const uint8_t *restrict cell_types,              \
	                                    const double *restrict bedrock, double bare);    \
	void ss_sweep_fast_wake_all##sfx(struct ss_sweep_fast *f, const struct ss_grid *g,   \
	                                 const double *height, const uint8_t *cell_types);   \
	double ss_sweep_fast_begin##sfx(struct ss_sweep_fast *f, const struct ss_grid *g,    \
	                                const double *height, const uint8_t *cell_types);    \
	double ss_sweep_fast_step##sfx(struct ss_sweep_fast *f, const struct ss_grid *g,     \
	                               const struct ss_face_rule *rule, double dt,           \
	                               const double *restrict source_rate,                   \
	                               const double *restrict bedrock,                       \
	                               const uint8_t *restrict cell_types,                   \
	                               double *restrict height, double *restrict open_flux); \
	double ss_sweep_fast_stage##sfx(struct ss_sweep_fast *f, const struct ss_grid *g,    \
	                                const struct ss_face_rule *rule,                     \
	                                const struct ss_sweep_stage *stage, int last,        \
	                                const double *restrict source_rate,                  \
	                                const uint8_t *restrict cell_types,                  \
	                                double *restrict height, double *restrict open_flux);

SS_PATH_PROTOTYPES(_generic)
SS_PATH_PROTOTYPES(_avx2)
SS_PATH_PROTOTYPES(_avx512)

#endif
