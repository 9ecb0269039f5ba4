/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * test_closure.c - the sliding closures of closure.h against doc/model.md#closures:
 * f_sl of every closure against the table formulas written out here
 * independently, exact zeros at and below the critical slope, the degeneracy
 * power near a_cr, bingham == herschel-bulkley(gamma = 1), the derivative
 * against finite differences, the CFL bound (an upper bound of lambda,
 * monotone, 0 when subcritical), face flux signs and symmetries, and the
 * input checks of ss_closure_init / ss_closure_parse / ss_closure_name.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "sandslide/closure.h"
#include "sandslide/error.h"

#define DEG (M_PI / 180.0)
#define NELEM(a) (sizeof(a) / sizeof(*(a)))

/* every closure under test; herschel-bulkley at several exponents */
struct variant {
	enum ss_closure_kind kind;
	double gamma;
	const char *label;
};

static const struct variant variants[] = {
	{ SS_CLOSURE_COULOMB, 1.0, "coulomb" },
	{ SS_CLOSURE_BINGHAM, 1.0, "bingham" },
	{ SS_CLOSURE_HERSCHEL_BULKLEY, 0.3, "herschel-bulkley(0.3)" },
	{ SS_CLOSURE_HERSCHEL_BULKLEY, 0.5, "herschel-bulkley(0.5)" },
	{ SS_CLOSURE_HERSCHEL_BULKLEY, 1.0, "herschel-bulkley(1)" },
	{ SS_CLOSURE_HERSCHEL_BULKLEY, 2.0, "herschel-bulkley(2)" },
	{ SS_CLOSURE_HERSCHEL_BULKLEY, 3.0, "herschel-bulkley(3)" },
	{ SS_CLOSURE_CASSON, 1.0, "casson" },
};

static const double angles[] = { 20.0, 30.0, 35.0, 40.0 };

/* a closure for variant v at repose angle deg (nu = 1); the init must pass */
static struct ss_closure make(const struct variant *v, double deg)
{
	struct ss_closure c;
	memset(&c, 0, sizeof c);
	const int rc = ss_closure_init(&c, v->kind, deg, v->gamma, 1.0);
	CHECK(rc == SS_OK, "ss_closure_init(%s, %g deg) failed with %d",
	      v->label, deg, rc);
	return c;
}

/* f_sl(s) straight from the table of doc/model.md#closures (no shared code) */
static double spec_fsl(const struct variant *v, double deg, double s)
{
	const double a_cr = deg * DEG;
	const double sc = sin(a_cr), tc = tan(a_cr);
	const double sin_a = s / sqrt(1.0 + s * s);
	const double b = sin_a / sc;
	const double g = v->gamma;
	if (!(s > tc))
		return 0.0; /* "f_sl is exactly 0 when s <= tan a_cr" */
	switch (v->kind) {
	case SS_CLOSURE_COULOMB:
		return fmax(s - tc, 0.0) / sqrt(1.0 + s * s);
	case SS_CLOSURE_BINGHAM:
		return (sc / sin_a) * (2.0 + sc / sin_a) * pow(fmax(b - 1.0, 0.0), 2.0);
	case SS_CLOSURE_HERSCHEL_BULKLEY:
		return (sc / sin_a) * (1.0 + g + g * sc / sin_a)
		       * pow(fmax(b - 1.0, 0.0), 1.0 + 1.0 / g);
	case SS_CLOSURE_CASSON:
		return pow(sc / sin_a, 2.0)
		       * (10.0 * pow(b, 1.5) + 6.0 * b + 3.0 * pow(b, 0.5) + 1.0)
		       * pow(fmax(sqrt(b) - 1.0, 0.0), 3.0);
	}
	return NAN;
}

/* 1. f_sl of every closure against the formulas of doc/model.md#closures */
static void test_eval_matches_spec(void)
{
	enum { N = 200 };
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		for (size_t ai = 0; ai < NELEM(angles); ai++) {
			const double deg = angles[ai];
			const struct ss_closure c = make(v, deg);
			CHECK_REL(c.tan_cr, tan(deg * DEG), 4 * DBL_EPSILON,
			          "%s at %g deg: tan_cr is not tan a_cr", v->label, deg);
			CHECK_REL(c.sin_cr, sin(deg * DEG), 4 * DBL_EPSILON,
			          "%s at %g deg: sin_cr is not sin a_cr", v->label, deg);
			/* slopes uniform in s, uniform in angle and just above a_cr */
			double slopes[3 * N + 13];
			int n = 0;
			const double smax = tan(85.0 * DEG);
			for (int i = 0; i < N; i++)
				slopes[n++] = smax * i / (N - 1);
			for (int i = 0; i < N; i++)
				slopes[n++] = tan(85.0 * DEG * i / (N - 1));
			for (int i = 0; i < N; i++)
				slopes[n++] = tan((deg + 5.0 * i / (N - 1)) * DEG);
			for (int k = -6; k <= 6; k++)
				slopes[n++] = tan((deg + pow(10.0, k / 2.0)) * DEG);
			for (int i = 0; i < n; i++) {
				const double s = slopes[i];
				const double got = ss_closure_eval(&c, s);
				const double want = spec_fsl(v, deg, s);
				CHECK_NEAR(got, want,
				           fmax(1e-13 * fmax(fabs(got), fabs(want)), 1e-15),
				           "%s at %g deg: f_sl(s = %.17g) differs from "
				           "the formula", v->label, deg, s);
			}
		}
	}
}

/* 2. exactly 0 at and below the critical slope; face flux 0 when
 * subcritical; f_sl >= 0 and finite just above it */
static void test_exact_zero_subcritical(void)
{
	const double more_angles[] = {
		5.0, 20.0, 30.0, 33.75, 35.0, 40.0, 45.0, 60.0, 75.0, 79.0, 85.0, 89.0,
	};
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		for (size_t ai = 0; ai < NELEM(more_angles); ai++) {
			const double deg = more_angles[ai];
			const struct ss_closure c = make(v, deg);
			const double tc = c.tan_cr;
			CHECK(ss_closure_eval(&c, tc) == 0.0,
			      "%s at %g deg: f_sl(tan a_cr) = %g, not 0", v->label,
			      deg, ss_closure_eval(&c, tc));
			const double below = nextafter(tc, 0.0);
			CHECK(ss_closure_eval(&c, below) == 0.0,
			      "%s at %g deg: f_sl(nextafter below tan a_cr) = %g, not 0",
			      v->label, deg, ss_closure_eval(&c, below));
			CHECK(ss_closure_eval(&c, 0.0) == 0.0,
			      "%s at %g deg: f_sl(0) = %g, not 0", v->label, deg,
			      ss_closure_eval(&c, 0.0));
			const double tc_own = tan(deg * DEG);
			if (tc_own <= tc)
				CHECK(ss_closure_eval(&c, tc_own) == 0.0,
				      "%s at %g deg: f_sl(tan(a_cr)) = %g, not 0",
				      v->label, deg, ss_closure_eval(&c, tc_own));
			int bad = 0;
			double bad_s = 0.0, bad_f = 0.0;
			for (int i = 0; i <= 1000; i++) {
				const double s = tc * i / 1000.0;
				const double f = ss_closure_eval(&c, s);
				if (f != 0.0 && !bad++) {
					bad_s = s;
					bad_f = f;
				}
			}
			double s = below;
			for (int i = 0; i < 1000; i++, s = nextafter(s, 0.0)) {
				const double f = ss_closure_eval(&c, s);
				if (f != 0.0 && !bad++) {
					bad_s = s;
					bad_f = f;
				}
			}
			CHECK(bad == 0, "%s at %g deg: %d subcritical slopes give "
			      "f_sl != 0, first s = %.17g f = %g", v->label, deg,
			      bad, bad_s, bad_f);
			/* the 20000 doubles just above tan a_cr: rounding of
			 * b - 1 (doc/model.md#closures: max(b - 1, 0)) must never give a negative
			 * or NaN f_sl, f_sl', lambda or flux */
			int bad_d = 0, bad_l = 0, bad_fl = 0;
			double bad_sd = 0.0, bad_vd = 0.0;
			bad = 0;
			s = tc;
			for (int i = 0; i < 20000; i++) {
				s = nextafter(s, INFINITY);
				const double f = ss_closure_eval(&c, s);
				if (!(f >= 0.0 && isfinite(f)) && !bad++) {
					bad_s = s;
					bad_f = f;
				}
				const double d = ss_closure_derivative(&c, s);
				if (!(d >= 0.0 && isfinite(d)) && !bad_d++) {
					bad_sd = s;
					bad_vd = d;
				}
				const double l = ss_closure_lambda(&c, s);
				if (!(l >= 0.0 && isfinite(l)))
					bad_l++;
				const double fl = ss_closure_face_flux(&c, s, 0.0);
				if (!(fl <= 0.0 && isfinite(fl)))
					bad_fl++;
			}
			CHECK(bad == 0, "%s at %g deg: %d slopes just above tan "
			      "a_cr give negative or non-finite f_sl, first s = "
			      "%.17g f = %g", v->label, deg, bad, bad_s, bad_f);
			CHECK(bad_d == 0, "%s at %g deg: %d slopes just above tan "
			      "a_cr give negative or non-finite f_sl', first s = "
			      "%.17g f' = %g", v->label, deg, bad_d, bad_sd, bad_vd);
			CHECK(bad_l == 0, "%s at %g deg: %d slopes just above tan "
			      "a_cr give negative or non-finite lambda", v->label,
			      deg, bad_l);
			CHECK(bad_fl == 0, "%s at %g deg: %d gradients (s, 0) just "
			      "above tan a_cr give a positive or non-finite face "
			      "flux", v->label, deg, bad_fl);
			/* face flux: (g_n, g_t) on and inside the critical circle */
			const double pairs[][2] = {
				{ 0.0, 0.0 }, { -0.0, 0.0 }, { 0.0, -0.0 },
				{ tc, 0.0 }, { -tc, 0.0 }, { 0.0, tc }, { 0.0, -tc },
				{ below, 0.0 }, { -below, 0.0 }, { 1e-300, 1e-300 },
			};
			for (size_t p = 0; p < NELEM(pairs); p++) {
				const double fl = ss_closure_face_flux(&c, pairs[p][0], pairs[p][1]);
				CHECK(fl == 0.0, "%s at %g deg: face flux(%g, %g) = %g, "
				      "not 0", v->label, deg, pairs[p][0], pairs[p][1], fl);
			}
			bad = 0;
			int tested = 0;
			double bad_gn = 0.0, bad_gt = 0.0;
			for (int ir = 0; ir <= 50; ir++) {
				for (int it = 0; it < 72; it++) {
					const double r = tc * ir / 50.0, th = it * (M_PI / 36.0);
					const double gn = r * cos(th), gt = r * sin(th);
					if (!(sqrt(gn * gn + gt * gt) <= tc))
						continue; /* rounded outside the circle */
					tested++;
					const double fl = ss_closure_face_flux(&c, gn, gt);
					if (fl != 0.0 && !bad++) {
						bad_gn = gn;
						bad_gt = gt;
						bad_f = fl;
					}
				}
			}
			CHECK(tested > 3000, "%s at %g deg: only %d subcritical "
			      "gradient pairs tested", v->label, deg, tested);
			CHECK(bad == 0, "%s at %g deg: %d subcritical gradients give "
			      "a non-zero face flux, first (%.17g, %.17g) -> %g",
			      v->label, deg, bad, bad_gn, bad_gt, bad_f);
		}
	}
}

/* least-squares slope of y against x */
static double fit_slope(const double *x, const double *y, int n)
{
	double mx = 0.0, my = 0.0;
	for (int i = 0; i < n; i++) {
		mx += x[i];
		my += y[i];
	}
	mx /= n;
	my /= n;
	double sxy = 0.0, sxx = 0.0;
	for (int i = 0; i < n; i++) {
		sxy += (x[i] - mx) * (y[i] - my);
		sxx += (x[i] - mx) * (x[i] - mx);
	}
	return sxy / sxx;
}

/* 3. f_sl ~ (a - a_cr)^p near a_cr with the power of the table in doc/model.md#closures */
static void test_degeneracy_power(void)
{
	enum { N = 41 };
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		double p;
		switch (v->kind) {
		case SS_CLOSURE_COULOMB: p = 1.0; break;
		case SS_CLOSURE_BINGHAM: p = 2.0; break;
		case SS_CLOSURE_HERSCHEL_BULKLEY: p = 1.0 + 1.0 / v->gamma; break;
		case SS_CLOSURE_CASSON: p = 3.0; break;
		default: p = NAN; break;
		}
		for (size_t ai = 0; ai < NELEM(angles); ai++) {
			const double deg = angles[ai];
			const struct ss_closure c = make(v, deg);
			double lx[N], ly[N];
			int positive = 1;
			for (int i = 0; i < N; i++) {
				const double eps = pow(10.0, -4.0 + 2.0 * i / (N - 1));
				const double f = ss_closure_eval(&c, tan((deg + eps) * DEG));
				if (!(f > 0.0)) {
					CHECK(f > 0.0, "%s at %g deg: f_sl = %g at %g deg "
					      "above a_cr", v->label, deg, f, eps);
					positive = 0;
					break;
				}
				lx[i] = log(eps);
				ly[i] = log(f);
			}
			if (!positive)
				continue;
			const double slope = fit_slope(lx, ly, N);
			CHECK_NEAR(slope, p, 0.02, "%s at %g deg: degeneracy power "
			           "near a_cr is %.4f, the model says %g", v->label, deg,
			           slope, p);
		}
	}
}

/* 4. bingham is herschel-bulkley with gamma = 1 (separate code paths) */
static void test_bingham_is_hb1(void)
{
	const struct variant vb = { SS_CLOSURE_BINGHAM, 1.0, "bingham" };
	const struct variant vh = { SS_CLOSURE_HERSCHEL_BULKLEY, 1.0, "hb(1)" };
	const double more_angles[] = { 10.0, 20.0, 30.0, 35.0, 40.0, 60.0 };
	for (size_t ai = 0; ai < NELEM(more_angles); ai++) {
		const double deg = more_angles[ai];
		const struct ss_closure cb = make(&vb, deg), ch = make(&vh, deg);
		for (int i = 0; i <= 400; i++) {
			const double s = i < 200 ? tan(89.0 * DEG * i / 199.0)
			                         : tan((deg + pow(10.0, -6.0 + 7.0 * (i - 200) / 200.0)) * DEG);
			const double fb = ss_closure_eval(&cb, s);
			const double fh = ss_closure_eval(&ch, s);
			CHECK_REL(fb, fh, 1e-14, "%g deg, s = %.17g: bingham f_sl "
			          "differs from herschel-bulkley(gamma = 1)", deg, s);
			const double db = ss_closure_derivative(&cb, s);
			const double dh = ss_closure_derivative(&ch, s);
			CHECK_REL(db, dh, 1e-14, "%g deg, s = %.17g: bingham f_sl' "
			          "differs from herschel-bulkley(gamma = 1)", deg, s);
		}
	}
}

/* 5. the analytic derivative against a central difference of f_sl */
static void test_derivative(void)
{
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		for (size_t ai = 0; ai < NELEM(angles); ai++) {
			const double deg = angles[ai];
			const struct ss_closure c = make(v, deg);
			for (int i = 0; i < 100; i++) {
				const double a = deg + 2.0 + (85.0 - deg - 2.0) * i / 99.0;
				const double s = tan(a * DEG), h = 1e-6 * s;
				const double fd = (ss_closure_eval(&c, s + h)
				                   - ss_closure_eval(&c, s - h)) / (2.0 * h);
				const double d = ss_closure_derivative(&c, s);
				CHECK_REL(d, fd, 1e-6, "%s at %g deg: f_sl'(s = %.17g) "
				          "(slope angle %g deg) disagrees with the "
				          "central difference", v->label, deg, s, a);
			}
			/* zero below, one-sided limit above (Coulomb: cos a_cr) */
			CHECK(ss_closure_derivative(&c, c.tan_cr) == 0.0
			      && ss_closure_derivative(&c, 0.0) == 0.0
			      && ss_closure_derivative(&c, 0.5 * c.tan_cr) == 0.0,
			      "%s at %g deg: f_sl' is not 0 at or below tan a_cr",
			      v->label, deg);
			const double d0 = ss_closure_derivative(&c, nextafter(c.tan_cr, INFINITY));
			if (v->kind == SS_CLOSURE_COULOMB)
				CHECK_REL(d0, cos(deg * DEG), 1e-12, "coulomb at %g deg: "
				          "f_sl'(tan a_cr +) is not cos a_cr", deg);
			else
				CHECK(d0 >= 0.0 && d0 <= ss_closure_derivative(&c, tan((deg + 0.01) * DEG)),
				      "%s at %g deg: f_sl'(tan a_cr +) = %g, expected "
				      "0 <= f' <= f'(a_cr + 0.01 deg) = %g (degenerate)",
				      v->label, deg, d0,
				      ss_closure_derivative(&c, tan((deg + 0.01) * DEG)));
		}
	}
}

/* 6. lambda = max(f', f/s) and the tabulated CFL bound */
static struct ss_cfl_bound cfl_table;

static void test_lambda_and_cfl_bound(void)
{
	const double cfl_angles[] = { 20.0, 30.0, 33.75, 35.0, 40.0, 45.0, 60.0 };
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		for (size_t ai = 0; ai < NELEM(cfl_angles); ai++) {
			const double deg = cfl_angles[ai];
			const struct ss_closure c = make(v, deg);
			const double tc = c.tan_cr;

			/* lambda == max(f', f/s) exactly, 0 when subcritical */
			int bad = 0;
			double bad_s = 0.0;
			for (int i = 1; i <= 2000; i++) {
				const double s = tan(89.9 * DEG * i / 2000.0);
				const double d = ss_closure_derivative(&c, s);
				const double q = ss_closure_eval(&c, s) / s;
				if (ss_closure_lambda(&c, s) != fmax(d, q) && !bad++)
					bad_s = s;
			}
			CHECK(bad == 0, "%s at %g deg: lambda(s) != max(f', f/s) at "
			      "%d slopes, first s = %.17g", v->label, deg, bad, bad_s);
			CHECK(ss_closure_lambda(&c, 0.0) == 0.0
			      && ss_closure_lambda(&c, tc) == 0.0,
			      "%s at %g deg: lambda is not 0 at s = 0 / tan a_cr",
			      v->label, deg);

			ss_cfl_bound_init(&cfl_table, &c);

			/* 0 when subcritical */
			CHECK(ss_cfl_bound_lookup(&cfl_table, 0.0) == 0.0
			      && ss_cfl_bound_lookup(&cfl_table, 0.5 * tc) == 0.0
			      && ss_cfl_bound_lookup(&cfl_table, nextafter(tc, 0.0)) == 0.0
			      && ss_cfl_bound_lookup(&cfl_table, tc) == 0.0,
			      "%s at %g deg: CFL bound is not 0 for S <= tan a_cr",
			      v->label, deg);

			/* an upper bound of lambda over [0, S] */
			const double S_list[] = {
				nextafter(tc, INFINITY), tc * (1.0 + 1e-12),
				tan((deg + 1e-3) * DEG), tan((deg + 0.5) * DEG),
				1.5 * tc, tan(80.0 * DEG), 50.0,
			};
			for (size_t si = 0; si < NELEM(S_list); si++) {
				const double S = S_list[si];
				const double bound = ss_cfl_bound_lookup(&cfl_table, S);
				double worst = 0.0, worst_s = 0.0;
				const double aS = atan(S);
				for (int i = 0; i <= 20000; i++) {
					double s;
					if (i <= 10000)
						s = S * i / 10000.0;
					else
						s = tan(aS * (i - 10000) / 10000.0);
					if (s > S)
						s = S;
					const double lam = ss_closure_lambda(&c, s);
					if (lam > worst) {
						worst = lam;
						worst_s = s;
					}
				}
				const double ends[] = { nextafter(tc, INFINITY), S };
				for (size_t e = 0; e < NELEM(ends); e++) {
					const double lam = ss_closure_lambda(&c, ends[e]);
					if (lam > worst) {
						worst = lam;
						worst_s = ends[e];
					}
				}
				CHECK(bound >= worst, "%s at %g deg: CFL bound(S = %.17g) "
				      "= %.17g < lambda(s = %.17g) = %.17g", v->label,
				      deg, S, bound, worst_s, worst);
			}

			/* non-decreasing in S */
			bad = 0;
			double prev = 0.0, bad_S = 0.0, bad_val = 0.0;
			for (int i = 0; i <= 20000; i++) {
				const double S = i <= 10000
				                 ? tan(89.99 * DEG * i / 10000.0)
				                 : tc * (1.0 + 1e-3 * (i - 10000) / 10000.0);
				if (i == 10001)
					prev = 0.0; /* restart: a second sweep near a_cr */
				const double L = ss_cfl_bound_lookup(&cfl_table, S);
				if (L < prev && !bad++) {
					bad_S = S;
					bad_val = L;
				}
				prev = L;
			}
			CHECK(bad == 0, "%s at %g deg: CFL bound decreases with S "
			      "(%d times), first at S = %.17g -> %g", v->label, deg,
			      bad, bad_S, bad_val);
		}
	}
}

/* 7. face flux opposes g_n, is odd in g_n and even in g_t */
static void test_face_flux_symmetry(void)
{
	const double gns[] = { 1e-3, 0.1, 0.5, 0.8, 1.0, 2.0, 10.0 };
	const double gts[] = { 0.0, 0.01, 0.3, 1.0, 5.0 };
	for (size_t vi = 0; vi < NELEM(variants); vi++) {
		const struct variant *v = &variants[vi];
		for (size_t ai = 0; ai < NELEM(angles); ai++) {
			const double deg = angles[ai];
			const struct ss_closure c = make(v, deg);
			for (size_t i = 0; i < NELEM(gns); i++) {
				for (size_t j = 0; j < NELEM(gts); j++) {
					const double gn = gns[i], gt = gts[j];
					const double f = ss_closure_face_flux(&c, gn, gt);
					const double s = sqrt(gn * gn + gt * gt);
					CHECK(ss_closure_face_flux(&c, -gn, gt) == -f,
					      "%s at %g deg: flux(-g_n, g_t) != -flux(g_n, "
					      "g_t) at (%g, %g)", v->label, deg, gn, gt);
					CHECK(ss_closure_face_flux(&c, gn, -gt) == f
					      && ss_closure_face_flux(&c, -gn, -gt) == -f,
					      "%s at %g deg: flux not even in g_t at "
					      "(%g, %g)", v->label, deg, gn, gt);
					const double want = -spec_fsl(v, deg, s) * gn / s;
					CHECK_NEAR(f, want, fmax(1e-13 * fabs(want), 1e-15),
					           "%s at %g deg: flux(%g, %g) is not "
					           "-f_sl(s) g_n / s", v->label, deg, gn, gt);
					if (s > c.tan_cr && ss_closure_eval(&c, s) > 0.0)
						CHECK(f < 0.0 && ss_closure_face_flux(&c, -gn, gt) > 0.0,
						      "%s at %g deg: supercritical flux(%g, %g) "
						      "= %g does not oppose g_n", v->label, deg,
						      gn, gt, f);
					/* g_n = 0: nothing crosses the face */
					const double f0 = ss_closure_face_flux(&c, 0.0, gn + gt);
					CHECK(f0 == 0.0, "%s at %g deg: flux(0, %g) = %g, not 0",
					      v->label, deg, gn + gt, f0);
				}
			}
		}
	}
}

/* 8. input checks, names */
static void test_init_and_names(void)
{
	struct ss_closure c;
	const double bad_angles[] = { 0.0, 90.0, -5.0, NAN, 90.5, 180.0, INFINITY, -INFINITY };
	for (int k = SS_CLOSURE_COULOMB; k <= SS_CLOSURE_CASSON; k++) {
		for (size_t i = 0; i < NELEM(bad_angles); i++)
			CHECK(ss_closure_init(&c, (enum ss_closure_kind)k, bad_angles[i],
			                      1.0, 1.0) != SS_OK,
			      "%s: repose angle %g accepted", ss_closure_name(k),
			      bad_angles[i]);
		const double bad_nu[] = { 0.0, -1.0, NAN, INFINITY };
		for (size_t i = 0; i < NELEM(bad_nu); i++)
			CHECK(ss_closure_init(&c, (enum ss_closure_kind)k, 30.0, 1.0,
			                      bad_nu[i]) != SS_OK,
			      "%s: nu %g accepted", ss_closure_name(k), bad_nu[i]);
		const double bad_gamma[] = { 0.0, -1.0, -0.5, NAN, INFINITY };
		for (size_t i = 0; i < NELEM(bad_gamma); i++)
			CHECK(ss_closure_init(&c, (enum ss_closure_kind)k, 30.0,
			                      bad_gamma[i], 1.0) != SS_OK,
			      "%s: gamma %g accepted", ss_closure_name(k), bad_gamma[i]);
		CHECK(ss_closure_init(&c, (enum ss_closure_kind)k, 30.0, 2.0, 0.25) == SS_OK,
		      "%s: valid parameters (30 deg, gamma 2, nu 0.25) rejected",
		      ss_closure_name(k));
		CHECK(c.kind == (enum ss_closure_kind)k && c.repose_angle_deg == 30.0
		      && c.nu == 0.25,
		      "%s: init did not store kind/angle/nu", ss_closure_name(k));
		const double g = k == SS_CLOSURE_HERSCHEL_BULKLEY ? 2.0 : 1.0;
		CHECK(c.gamma == g && c.power == 1.0 + 1.0 / g,
		      "%s: gamma %g power %g, expected %g and %g",
		      ss_closure_name(k), c.gamma, c.power, g, 1.0 + 1.0 / g);
		CHECK(ss_closure_init(&c, (enum ss_closure_kind)k, 1e-3, 1.0, 1.0) == SS_OK
		      && ss_closure_init(&c, (enum ss_closure_kind)k, 89.999, 1.0, 1.0) == SS_OK,
		      "%s: angles 0.001 / 89.999 deg rejected", ss_closure_name(k));
	}

	static const struct {
		const char *name;
		enum ss_closure_kind kind;
	} names[] = {
		{ "coulomb", SS_CLOSURE_COULOMB },
		{ "bingham", SS_CLOSURE_BINGHAM },
		{ "herschel-bulkley", SS_CLOSURE_HERSCHEL_BULKLEY },
		{ "casson", SS_CLOSURE_CASSON },
	};
	for (size_t i = 0; i < NELEM(names); i++) {
		enum ss_closure_kind k = (enum ss_closure_kind)-1;
		CHECK(ss_closure_parse(names[i].name, &k) == 0 && k == names[i].kind,
		      "parse(\"%s\") failed or gave kind %d", names[i].name, (int)k);
		CHECK(strcmp(ss_closure_name(names[i].kind), names[i].name) == 0,
		      "name(%d) = \"%s\", expected \"%s\"", (int)names[i].kind,
		      ss_closure_name(names[i].kind), names[i].name);
		enum ss_closure_kind k2 = (enum ss_closure_kind)-1;
		CHECK(ss_closure_parse(ss_closure_name(names[i].kind), &k2) == 0
		      && k2 == names[i].kind,
		      "parse(name(%d)) does not round-trip", (int)names[i].kind);
		CHECK(strstr(SS_CLOSURE_NAMES, names[i].name) != NULL,
		      "SS_CLOSURE_NAMES does not list \"%s\"", names[i].name);
	}
	const char *const rejected[] = {
		"Coulomb ", "foo", "", "Coulomb", "coulomb ", " coulomb",
		"herschel_bulkley", "herschel", "CASSON", "bingham\n",
	};
	for (size_t i = 0; i < NELEM(rejected); i++) {
		enum ss_closure_kind k = SS_CLOSURE_CASSON;
		CHECK(ss_closure_parse(rejected[i], &k) == -1,
		      "parse(\"%s\") accepted an unknown closure name", rejected[i]);
	}
}

int main(void)
{
	RUN(test_eval_matches_spec);
	RUN(test_exact_zero_subcritical);
	RUN(test_degeneracy_power);
	RUN(test_bingham_is_hb1);
	RUN(test_derivative);
	RUN(test_lambda_and_cfl_bound);
	RUN(test_face_flux_symmetry);
	RUN(test_init_and_names);
	return check_report();
}
