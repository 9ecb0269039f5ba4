/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * face.h - the point-wise face flux that every sweep calls (doc/model.md#face-flux):
 *
 *   F = -nu f_sl(s) g_n / s,   s = sqrt(g_n^2 + g_t^2),   0 when s <= tan a_cr
 *
 * rewritten so that a face needs no division and no square root, only the
 * two reciprocal square roots 1/s and 1/w, w = sqrt(1 + s^2):
 *
 *   sin a = s / w,  b = sin a / sin a_cr,  1/b = w sin a_cr / s
 *   coulomb      f/s = max(s - tan a_cr, 0) / (w s)
 *   bingham      f/s = (1/b)(2 + 1/b) e^2 / s,                 e = max(b - 1, 0)
 *   h-bulkley    f/s = (1/b)(1 + gamma + gamma/b) e^(1+1/gamma) / s
 *   casson       f/s = (1/b)^2 (10 b q + 6 b + 3 q + 1) e^3 / s, q = sqrt b,
 *                                                                e = max(q - 1, 0)
 *
 * On the AVX-512 path (cpu.h) the reciprocal square roots are vrsqrt14pd
 * refined by two Newton steps (relative error below 1e-15 against 1/sqrt);
 * on the generic and AVX2 paths they are 1/sqrt, so those two give the same
 * bits and the AVX-512 path bits of its own.  Herschel-Bulkley with
 * gamma = 1/2 (e^3) and gamma = 2 (e sqrt e) avoids pow().
 * tests/test_sweep.c (test_face_formula) holds every path to the formulas
 * of closure.h (doc/model.md#closures).
 *
 * The function works on a row of faces and is compiled once per path
 * (face.c, core/cpu_paths.h); ss_face_fluxes runs the copy of the path in
 * use, so the reference sweep (one face per call) and the fast sweep (a
 * row per call) run the same instructions on every face: the same bits.
 */
#ifndef SANDSLIDE_CORE_FACE_H
#define SANDSLIDE_CORE_FACE_H

#include <stddef.h>
#include <stdint.h>

#include "core/face_point.h"
#include "sandslide/closure.h"

/*
 * The rules of a grid of several materials (doc/model.md#materials), by
 * rule number, as arrays a row of faces gathers from: each face takes the
 * rule of the larger angle of its two cells (ss_face_material).
 */
struct ss_face_table {
	int count;
	unsigned forms;            /* bit 1 << form of each rule's form */
	int one_nu;                /* every rule has nu[0] */
	double *nu, *tan_cr, *tan_cr2, *sin_cr, *inv_sin_cr, *gamma, *power;
	uint8_t *form;             /* enum ss_face_form */
};

struct ss_face_rule {
	enum ss_face_form form;
	double nu;                 /* m^2/s */
	double tan_cr;             /* tan a_cr */
	double tan_cr2;            /* largest s^2 with sqrt(s^2) <= tan a_cr */
	double sin_cr, inv_sin_cr;
	double gamma, power;       /* Herschel-Bulkley */
	/* several materials: the rules, and each cell's rule number by storage
	 * index (halo included); NULL: this one rule everywhere */
	const struct ss_face_table *table;
	const uint16_t *material;
};

void ss_face_rule_init(struct ss_face_rule *r, const struct ss_closure *c);

/* The rule's numbers by value, as the device's kernels and
 * ss_point_flux take them (face_point.h). */
static inline struct ss_point_rule ss_face_point_rule(const struct ss_face_rule *r)
{
	struct ss_point_rule p;
	p.form = (int)r->form;
	p.nu = r->nu;
	p.tan_cr = r->tan_cr;
	p.tan_cr2 = r->tan_cr2;
	p.sin_cr = r->sin_cr;
	p.inv_sin_cr = r->inv_sin_cr;
	p.gamma = r->gamma;
	p.power = r->power;
	return p;
}

/* The table of count closures; SS_ERR_FAIL if out of memory. */
int ss_face_table_create(struct ss_face_table *t, const struct ss_closure *c, int count);
void ss_face_table_release(struct ss_face_table *t);

/* The rule number of the face between cells a and b (storage indices):
 * the larger of the two.  Materials are numbered by angle, smallest first
 * (stepper.h), so a face holds up to the larger angle of its two cells;
 * hysteresis numbers material n's moving sand 2n + 1, above its sand at
 * rest, 2n, so a face beside moving sand of its material slides at the
 * dynamic angle (doc/model.md#materials, #hysteresis). */
static inline uint16_t ss_face_material(const uint16_t *material, ptrdiff_t a, ptrdiff_t b)
{
	return material[b] > material[a] ? material[b] : material[a];
}

/* flux[k] = F of the face with normal gradient g_n[k] and tangential
 * gradient g_t[k], k < n (m^2/s; g dimensionless).  Exactly 0 where
 * s = sqrt(g_n^2 + g_t^2) <= tan a_cr (as closure.h).  Returns 1 if some
 * face is above that slope, else 0. */
int ss_face_fluxes(const struct ss_face_rule *r, int n,
                    const double *restrict g_n, const double *restrict g_t,
                    double *restrict flux);

/* The same with the table's rule rule[k] for face k (ss_face_material):
 * the arithmetic of ss_face_fluxes with that rule's numbers, so one rule
 * everywhere gives ss_face_fluxes' bits. */
int ss_face_fluxes_mixed(const struct ss_face_table *t, int n, const uint16_t *restrict rule,
                         const double *restrict g_n, const double *restrict g_t,
                         double *restrict flux);

/*
 * Non-erodible bedrock: a face takes from the cell it leaves at most a
 * quarter of that cell's sand per step, so that a cell losing sand through
 * all four faces keeps thickness h - b >= 0 (to round-off), while each face
 * still has one flux and the volume balance stays exact.  For an x-face
 * F dt dy <= (h - b) dx dy / 4, i.e. F <= (h - b) limit with
 * limit = dx / (4 dt) (dy for a y-face).  thick_a, thick_b: thickness of
 * the west/south and east/north cell (+infinity where there is no bedrock:
 * walls, open cells, ghosts); positive F flows from a to b.  A NaN flux or
 * thickness stays NaN.
 */
static inline double ss_face_limit(double flux, double thick_a, double thick_b, double limit)
{
	const double out_a = thick_a * limit, out_b = -(thick_b * limit);
	flux = flux > out_a ? out_a : flux;
	return flux < out_b ? out_b : flux;
}

/* y[k] = 1/sqrt(x[k]) for x[k] > 0, k < n, as the face flux computes it on
 * the path in use. */
void ss_face_rsqrt(int n, const double *restrict x, double *restrict y);

/* "vrsqrt14pd + 2 Newton steps (AVX-512)" or "1/sqrt": the path in use
 * (cpu.h), for reports. */
const char *ss_face_rsqrt_method(void);

#endif
