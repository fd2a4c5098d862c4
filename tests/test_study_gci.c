/* Richardson extrapolation and the GCI (bs_study_gci) on synthetic sequences
 * f(h) = f0 + C h^p with known order and limit: exact, with a small
 * perturbation, with non-constant ratios; oscillatory, divergent, converged
 * and bad inputs are flagged, not fitted. */
#include <criterion/criterion.h>
#include <math.h>

#include "bs_study.h"

static void seq(const double h[3], double f0, double C, double p, double f[3]) {
  for (int i = 0; i < 3; i++) f[i] = f0 + C * pow(h[i], p);
}

Test(study_gci, exact_power_law_constant_ratio) {
  const double h[3] = {0.125, 0.25, 0.5};
  double f[3];
  seq(h, 2.0, -0.3, 2.0, f);
  bs_gci g;
  cr_assert_eq(bs_study_gci(h, f, &g), BS_GCI_OK);
  cr_expect(fabs(g.p - 2.0) < 1e-10, "p %.15g", g.p);
  cr_expect(fabs(g.extrapolated - 2.0) < 1e-12, "extrapolated %.15g", g.extrapolated);
  /* GCI_fine = 1.25 |f0 - f1| / |f0| / (r^p - 1) */
  double want = 1.25 * fabs((f[0] - f[1]) / f[0]) / 3.0;
  cr_expect(fabs(g.gci_fine - want) < 1e-12 * want, "GCI %.15g, want %.15g", g.gci_fine, want);
  cr_expect(fabs(g.asymptotic - f[0] / f[1]) < 1e-9, "asymptotic ratio %.15g", g.asymptotic);
  cr_expect(fabs(g.e_ext - fabs((2.0 - f[0]) / 2.0)) < 1e-12);
}

Test(study_gci, non_constant_ratio_and_order_one) {
  const double h[3] = {0.1, 0.15, 0.4}; /* r21 = 1.5, r32 = 2.67 */
  double f[3];
  seq(h, -1.0, 0.7, 1.3, f);
  bs_gci g;
  cr_assert_eq(bs_study_gci(h, f, &g), BS_GCI_OK);
  cr_expect(fabs(g.p - 1.3) < 1e-8, "p %.15g", g.p);
  cr_expect(fabs(g.extrapolated + 1.0) < 1e-9, "extrapolated %.15g", g.extrapolated);
}

Test(study_gci, perturbed_sequence_stays_close) {
  const double h[3] = {0.125, 0.25, 0.5};
  double f[3];
  seq(h, 1.0, 0.5, 2.0, f);
  f[1] *= 1 + 1e-6;
  bs_gci g;
  cr_assert_eq(bs_study_gci(h, f, &g), BS_GCI_OK);
  cr_expect(fabs(g.p - 2.0) < 1e-3, "p %.15g", g.p);
  cr_expect(fabs(g.extrapolated - 1.0) < 1e-5, "extrapolated %.15g", g.extrapolated);
  cr_expect(fabs(g.asymptotic - 1.0) < 0.05, "asymptotic ratio %.15g", g.asymptotic);
}

Test(study_gci, oscillatory_divergent_converged_bad) {
  const double h[3] = {0.25, 0.5, 1.0};
  bs_gci g;
  cr_expect_eq(bs_study_gci(h, (double[3]){1.0, 1.1, 0.9}, &g), BS_GCI_OSCILLATORY);
  cr_expect(isnan(g.p) && isnan(g.extrapolated) && isnan(g.gci_fine), "an oscillatory sequence was fitted");
  cr_expect_eq(bs_study_gci(h, (double[3]){1.0, 1.5, 1.7}, &g), BS_GCI_DIVERGENT);
  cr_expect(isnan(g.p));
  cr_expect_eq(bs_study_gci(h, (double[3]){3.0, 3.0, 3.0}, &g), BS_GCI_CONVERGED);
  cr_expect_eq(g.extrapolated, 3.0);
  cr_expect_eq(g.gci_fine, 0.0);
  cr_expect_eq(bs_study_gci(h, (double[3]){1.0, 1.0, 2.0}, &g), BS_GCI_NO_ORDER);
  cr_expect_eq(bs_study_gci(h, (double[3]){1.0, NAN, 2.0}, &g), BS_GCI_BAD_INPUT);
  cr_expect_eq(bs_study_gci((double[3]){0.5, 0.25, 1.0}, (double[3]){1, 2, 4}, &g), BS_GCI_BAD_INPUT);
  cr_expect_str_eq(bs_gci_status_name(BS_GCI_OSCILLATORY), "oscillatory");
}
