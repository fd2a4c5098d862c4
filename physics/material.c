/* material.c — constitutive models in singular-value space (see bs_material.h).
 *
 * An isotropic model is Psi(F) = psi(s) with s the signed singular values of
 * F = U diag(s) V^T. Then
 *   P     = U diag(dpsi/ds) V^T,
 *   dP/dF = sum_ij H_ij d_i d_j^T + sum_{pairs p=(i,j)} lp_p S_p S_p^T / 2 + lm_p T_p T_p^T / 2
 * with d_i = vec(u_i v_i^T), S_p = vec(u_i v_j^T + u_j v_i^T),
 * T_p = vec(u_i v_j^T - u_j v_i^T) (orthogonal, |S| = |T| = sqrt 2), H the
 * Hessian of psi, lp = (psi_i - psi_j)/(s_i - s_j), lm = (psi_i + psi_j)/(s_i + s_j).
 * Each model below states psi, its gradient, H, lp and lm in closed form.
 *
 * Near rest the formulas use d_i = s_i - 1 (exact for s_i in [0.5, 2]) so that
 * Psi keeps its relative accuracy for small strains: J - 1, I_C - 3 and
 * s^2 - 1 - 2 ln s are expanded in d rather than formed by cancellation.
 */
#include "bs_material.h"

#include <math.h>
#include <string.h>

#include "bs_svd.h"

/* pair p = (pi[p], pj[p]), third index pk[p] */
static const int pi_[3] = {0, 0, 1}, pj_[3] = {1, 2, 2}, pk_[3] = {2, 1, 0};

static const char *const model_names[] = {"fixed_corotated", "corotated", "neo_hookean", "stable_neo_hookean",
                                          "linear"};
enum { N_MODELS = 5 };

const char *bs_model_name(bs_model model) {
  if ((int)model < 0 || (int)model >= N_MODELS) return "unknown";
  return model_names[model];
}

int bs_model_parse(const char *name, bs_model *out, bs_error *err) {
  if (name)
    for (int i = 0; i < N_MODELS; i++)
      if (strcmp(name, model_names[i]) == 0) {
        *out = (bs_model)i;
        return BS_OK;
      }
  return bs_error_set(err, BS_EINPUT,
                      "material model \"%s\" is unknown (expected fixed_corotated, corotated, neo_hookean, "
                      "stable_neo_hookean or linear)",
                      name ? name : "(null)");
}

int bs_material_init(bs_model model, double youngs, double poisson, double density, bs_material *out,
                     bs_error *err) {
  if ((int)model < 0 || (int)model >= N_MODELS)
    return bs_error_set(err, BS_EINPUT, "material model %d is not a bs_model", (int)model);
  if (!isfinite(youngs) || !(youngs > 0))
    return bs_error_set(err, BS_EINPUT, "youngs = %g: Young's modulus must be finite and > 0 (Pa)", youngs);
  if (!isfinite(poisson) || !(poisson > -1.0) || !(poisson < 0.5))
    return bs_error_set(err, BS_EINPUT,
                        "poisson = %g: Poisson's ratio must satisfy -1 < poisson < 0.5 "
                        "(0.5 is incompressible: lambda would be infinite)",
                        poisson);
  if (!isfinite(density) || !(density > 0))
    return bs_error_set(err, BS_EINPUT, "density = %g: must be finite and > 0 (kg/m^3)", density);
  bs_material m;
  m.model = model;
  m.youngs = youngs;
  m.poisson = poisson;
  m.density = density;
  m.mu = youngs / (2.0 * (1.0 + poisson));
  m.lambda = youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
  m.J0 = BS_NEO_HOOKEAN_J0;
  if (model == BS_MODEL_FIXED_COROTATED && m.lambda < 0)
    return bs_error_set(err, BS_EINPUT,
                        "poisson = %g: fixed_corotated needs poisson >= 0 (lambda = %g < 0 makes the energy "
                        "unbounded below)",
                        poisson, m.lambda);
  if (model == BS_MODEL_NEO_HOOKEAN && !(m.mu + m.lambda * (1.0 - log(m.J0)) > 0))
    return bs_error_set(err, BS_EINPUT,
                        "poisson = %g: neo_hookean needs mu + lambda (1 - ln J0) > 0 (poisson > about -0.31) "
                        "for its extension below J0 = %g to be convex and bounded below",
                        poisson, m.J0);
  *out = m;
  return BS_OK;
}

/* d - log1p(d), accurate also for small |d| (where the difference cancels):
 * with u = d / (2 + d), log1p(d) = 2 atanh(u) = 2 (u + u^3/3 + u^5/5 + ...)
 * and d - 2u = u d, so d - log1p(d) = u d - 2u (u^2/3 + u^4/5 + ...). */
static double d_minus_log1p(double d) {
  if (fabs(d) >= 0.25) return d - log1p(d);
  const double u = d / (2.0 + d), u2 = u * u; /* |u| <= 1/7: 10 terms reach 1e-17 */
  double s = 1.0 / 21.0;
  for (int k = 9; k >= 1; k--) s = 1.0 / (2 * k + 1) + u2 * s;
  return u * d - 2.0 * u * u2 * s;
}

/* psi(s) of an isotropic model. level 0: energy only; 1: and g = dpsi/ds;
 * 2: and the Hessian H (3x3) and the pair quotients lp, lm. */
static double sv_eval(const bs_material *m, const double s[3], int level, double g[3], double H[9], double lp[3],
                      double lm[3]) {
  const double mu = m->mu, la = m->lambda;
  const double d[3] = {s[0] - 1.0, s[1] - 1.0, s[2] - 1.0};
  const double Jk[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]}; /* dJ/ds_i */
  const double J = s[0] * s[1] * s[2];
  /* J - 1 expanded in d (no cancellation near rest) */
  const double Jm1 = d[0] + d[1] + d[2] + d[0] * d[1] + d[0] * d[2] + d[1] * d[2] + d[0] * d[1] * d[2];
  double psi = 0;

  switch (m->model) {
  case BS_MODEL_FIXED_COROTATED: {
    psi = mu * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 0.5 * la * Jm1 * Jm1;
    if (level < 1) break;
    for (int i = 0; i < 3; i++) g[i] = 2.0 * mu * d[i] + la * Jm1 * Jk[i];
    if (level < 2) break;
    for (int i = 0; i < 3; i++) H[4 * i] = 2.0 * mu + la * Jk[i] * Jk[i];
    for (int p = 0; p < 3; p++) {
      const int i = pi_[p], j = pj_[p], k = pk_[p];
      H[3 * i + j] = H[3 * j + i] = la * Jk[i] * Jk[j] + la * Jm1 * s[k];
      lp[p] = 2.0 * mu - la * Jm1 * s[k];
      lm[p] = 2.0 * mu + la * Jm1 * s[k] - 4.0 * mu / fmax(s[i] + s[j], BS_SIGMA_SUM_MIN);
    }
    break;
  }
  case BS_MODEL_COROTATED: {
    const double S = d[0] + d[1] + d[2]; /* tr(R^T F - I) */
    psi = mu * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 0.5 * la * S * S;
    if (level < 1) break;
    for (int i = 0; i < 3; i++) g[i] = 2.0 * mu * d[i] + la * S;
    if (level < 2) break;
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) H[3 * i + j] = (i == j ? 2.0 * mu : 0.0) + la;
    for (int p = 0; p < 3; p++) {
      const int i = pi_[p], j = pj_[p];
      lp[p] = 2.0 * mu;
      lm[p] = 2.0 * mu + (2.0 * la * S - 4.0 * mu) / fmax(s[i] + s[j], BS_SIGMA_SUM_MIN);
    }
    break;
  }
  case BS_MODEL_NEO_HOOKEAN: {
    /* psi = mu/2 sum (s_i^2 - 1) + g(J); gp = g'(J), gpp = g''(J). */
    double gp, gpp;
    const double J0 = m->J0;
    if (J >= J0) { /* then every s_i > 0 */
      const double lnJ = log1p(d[0]) + log1p(d[1]) + log1p(d[2]);
      /* mu/2 (I_C - 3) - mu ln J = mu/2 sum (s^2 - 1 - 2 ln s), s = 1 + d */
      double h = 0;
      for (int i = 0; i < 3; i++) h += d[i] * d[i] + 2.0 * d_minus_log1p(d[i]);
      psi = 0.5 * mu * h + 0.5 * la * lnJ * lnJ;
      gp = (-mu + la * lnJ) / J;
      gpp = (mu + la - la * lnJ) / (J * J);
    } else {
      const double l0 = log(J0);
      const double g0 = -mu * l0 + 0.5 * la * l0 * l0, g1 = (-mu + la * l0) / J0, g2 = (mu + la - la * l0) / (J0 * J0);
      const double dJ = J - J0;
      psi = 0.5 * mu * (d[0] * (d[0] + 2.0) + d[1] * (d[1] + 2.0) + d[2] * (d[2] + 2.0)) + g0 + g1 * dJ +
            0.5 * g2 * dJ * dJ;
      gp = g1 + g2 * dJ;
      gpp = g2;
    }
    if (level < 1) break;
    for (int i = 0; i < 3; i++) g[i] = mu * s[i] + gp * Jk[i];
    if (level < 2) break;
    for (int i = 0; i < 3; i++) H[4 * i] = mu + gpp * Jk[i] * Jk[i];
    for (int p = 0; p < 3; p++) {
      const int i = pi_[p], j = pj_[p], k = pk_[p];
      H[3 * i + j] = H[3 * j + i] = gpp * Jk[i] * Jk[j] + gp * s[k];
      lp[p] = mu - gp * s[k];
      lm[p] = mu + gp * s[k];
    }
    break;
  }
  case BS_MODEL_STABLE_NEO_HOOKEAN: {
    const double mu2 = 4.0 * mu / 3.0, la2 = la + 5.0 * mu / 6.0;
    const double kappa = 0.75 * mu2; /* = la2 (alpha - 1) */
    const double e = d[0] * (d[0] + 2.0) + d[1] * (d[1] + 2.0) + d[2] * (d[2] + 2.0); /* I_C - 3 */
    const double Ic1 = e + 4.0;                                                       /* I_C + 1 */
    /* mu2/2 (I_C - 3 - ln((I_C + 1)/4)) + la2/2 ((J - alpha)^2 - (1 - alpha)^2) */
    psi = 0.5 * mu2 * (e - log1p(0.25 * e)) + 0.5 * Jm1 * (la2 * Jm1 - 2.0 * kappa);
    if (level < 1) break;
    const double q = mu2 * (1.0 - 1.0 / Ic1); /* d/ds_i of the I_C terms, over s_i */
    const double r = la2 * Jm1 - kappa;       /* la2 (J - alpha) */
    for (int i = 0; i < 3; i++) g[i] = q * s[i] + r * Jk[i];
    if (level < 2) break;
    const double c = 2.0 * mu2 / (Ic1 * Ic1);
    for (int i = 0; i < 3; i++) H[4 * i] = q + c * s[i] * s[i] + la2 * Jk[i] * Jk[i];
    for (int p = 0; p < 3; p++) {
      const int i = pi_[p], j = pj_[p], k = pk_[p];
      H[3 * i + j] = H[3 * j + i] = c * s[i] * s[j] + la2 * Jk[i] * Jk[j] + r * s[k];
      lp[p] = q - r * s[k];
      lm[p] = q + r * s[k];
    }
    break;
  }
  case BS_MODEL_LINEAR: break; /* not handled here */
  }
  return psi;
}

/* Linear elasticity, directly in F. */
static double linear_psi_P(const bs_material *m, const double F[9], double P[9]) {
  double eps[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) eps[3 * i + j] = 0.5 * (F[3 * i + j] + F[3 * j + i]) - (i == j ? 1.0 : 0.0);
  const double tr = eps[0] + eps[4] + eps[8];
  double ee = 0;
  for (int i = 0; i < 9; i++) ee += eps[i] * eps[i];
  if (P)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) P[3 * i + j] = 2.0 * m->mu * eps[3 * i + j] + (i == j ? m->lambda * tr : 0.0);
  return m->mu * ee + 0.5 * m->lambda * tr * tr;
}

/* The corotated models need only the rotation R of F = R S: with
 * D = F - R = U diag(s - 1) V^T (det F > 0),
 *   sum (s_i - 1)^2 = |D|^2,   sum (s_i - 1) = tr(R^T D),   cof F = U diag(dJ/ds) V^T,
 * so Psi and P follow from R (bs_polar3, a fraction of the SVD's cost) without
 * cancellation near rest; J - 1 is expanded in G = F - I. Where bs_polar3
 * declines (inverted, flat or far-out F), the SVD path below is taken. */
static int uses_polar(const bs_material *m) {
  return m->model == BS_MODEL_FIXED_COROTATED || m->model == BS_MODEL_COROTATED;
}

static double polar_psi_P(const bs_material *m, const double F[9], const double R[9], double *P) {
  double D[9], dd = 0.0, rd = 0.0;
  for (int i = 0; i < 9; i++) {
    D[i] = F[i] - R[i];
    dd += D[i] * D[i];
    rd += R[i] * D[i];
  }
  if (m->model == BS_MODEL_COROTATED) {
    if (P)
      for (int i = 0; i < 9; i++) P[i] = 2.0 * m->mu * D[i] + m->lambda * rd * R[i];
    return m->mu * dd + 0.5 * m->lambda * rd * rd;
  }
  const double G[9] = {F[0] - 1.0, F[1], F[2], F[3], F[4] - 1.0, F[5], F[6], F[7], F[8] - 1.0};
  const double minors = (G[0] * G[4] - G[1] * G[3]) + (G[0] * G[8] - G[2] * G[6]) + (G[4] * G[8] - G[5] * G[7]);
  const double detG = G[0] * (G[4] * G[8] - G[5] * G[7]) + G[1] * (G[5] * G[6] - G[3] * G[8]) +
                      G[2] * (G[3] * G[7] - G[4] * G[6]);
  const double Jm1 = (G[0] + G[4] + G[8]) + minors + detG;
  if (P) {
    const double c[9] = {F[4] * F[8] - F[5] * F[7], F[5] * F[6] - F[3] * F[8], F[3] * F[7] - F[4] * F[6],
                         F[2] * F[7] - F[1] * F[8], F[0] * F[8] - F[2] * F[6], F[1] * F[6] - F[0] * F[7],
                         F[1] * F[5] - F[2] * F[4], F[2] * F[3] - F[0] * F[5], F[0] * F[4] - F[1] * F[3]};
    for (int i = 0; i < 9; i++) P[i] = 2.0 * m->mu * D[i] + m->lambda * Jm1 * c[i];
  }
  return m->mu * dd + 0.5 * m->lambda * Jm1 * Jm1;
}

double bs_material_psi(const bs_material *m, const double F[9]) {
  if (m->model == BS_MODEL_LINEAR) return linear_psi_P(m, F, NULL);
  double R[9];
  if (uses_polar(m) && bs_polar3(F, R)) return polar_psi_P(m, F, R, NULL);
  double U[9], s[3], V[9];
  bs_svd3(F, U, s, V);
  return sv_eval(m, s, 0, NULL, NULL, NULL, NULL);
}

/* Psi and P from the SVD of F. */
static double psi_P_from_svd(const bs_material *m, const double U[9], const double s[3], const double V[9],
                             double P[9]) {
  double g[3];
  const double psi = sv_eval(m, s, 1, g, NULL, NULL, NULL);
  for (int r = 0; r < 3; r++) {
    const double a0 = U[3 * r] * g[0], a1 = U[3 * r + 1] * g[1], a2 = U[3 * r + 2] * g[2];
    for (int c = 0; c < 3; c++) P[3 * r + c] = a0 * V[3 * c] + a1 * V[3 * c + 1] + a2 * V[3 * c + 2];
  }
  return psi;
}

double bs_material_psi_P(const bs_material *m, const double F[9], double P[9]) {
  if (m->model == BS_MODEL_LINEAR) return linear_psi_P(m, F, P);
  double R[9];
  if (uses_polar(m) && bs_polar3(F, R)) return polar_psi_P(m, F, R, P);
  double U[9], s[3], V[9];
  bs_svd3(F, U, s, V);
  return psi_P_from_svd(m, U, s, V, P);
}

/* Psi (and P when P is not NULL) of nb <= BS_MATERIAL_BATCH matrices: the
 * corotated models by bs_polar3_batch, the matrices it declines (and every
 * matrix of the other models) by one bs_svd3_batch on those alone. */
static void psi_P_batch(const bs_material *m, int nb, const double *F, double *psi, double *P) {
  enum { B = BS_MATERIAL_BATCH };
  int ok[B], idx[B], ns = 0;
  if (uses_polar(m)) {
    double R[9 * B];
    bs_polar3_batch(nb, F, R, ok);
    for (int i = 0; i < nb; i++)
      if (ok[i])
        psi[i] = polar_psi_P(m, F + 9 * i, R + 9 * i, P ? P + 9 * i : NULL);
      else
        idx[ns++] = i;
  } else
    for (int i = 0; i < nb; i++) idx[ns++] = i;
  if (ns == 0) return;
  double Fs[9 * B], U[9 * B], s[3 * B], V[9 * B];
  for (int k = 0; k < ns; k++) memcpy(Fs + 9 * k, F + 9 * idx[k], 9 * sizeof(double));
  bs_svd3_batch(ns, Fs, U, s, V);
  for (int k = 0; k < ns; k++) {
    const int i = idx[k];
    psi[i] = P ? psi_P_from_svd(m, U + 9 * k, s + 3 * k, V + 9 * k, P + 9 * i)
               : sv_eval(m, s + 3 * k, 0, NULL, NULL, NULL, NULL);
  }
}

void bs_material_psi_batch(const bs_material *m, int n, const double *F, double *psi) {
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    if (m->model == BS_MODEL_LINEAR)
      for (int i = 0; i < nb; i++) psi[i0 + i] = linear_psi_P(m, F + 9 * (i0 + i), NULL);
    else
      psi_P_batch(m, nb, F + 9 * i0, psi + i0, NULL);
  }
}

void bs_material_psi_P_batch(const bs_material *m, int n, const double *F, double *psi, double *P) {
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    if (m->model == BS_MODEL_LINEAR)
      for (int i = 0; i < nb; i++) psi[i0 + i] = linear_psi_P(m, F + 9 * (i0 + i), P + 9 * (i0 + i));
    else
      psi_P_batch(m, nb, F + 9 * i0, psi + i0, P + 9 * i0);
  }
}

/* dP/dF from the singular-value-space blocks (see the top of this file). */
static void assemble_dPdF(const double U[9], const double V[9], const double H[9], const double lp[3],
                          const double lm[3], double K[81]) {
  double D[3][9], S[3][9], T[3][9], W[3][9], Sl[3][9], Tl[3][9];
  for (int i = 0; i < 3; i++)
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) D[i][3 * r + c] = U[3 * r + i] * V[3 * c + i];
  for (int p = 0; p < 3; p++) {
    const int i = pi_[p], j = pj_[p];
    const double hp = 0.5 * lp[p], hm = 0.5 * lm[p];
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) {
        const double x = U[3 * r + i] * V[3 * c + j], y = U[3 * r + j] * V[3 * c + i];
        S[p][3 * r + c] = x + y;
        T[p][3 * r + c] = x - y;
        Sl[p][3 * r + c] = hp * (x + y);
        Tl[p][3 * r + c] = hm * (x - y);
      }
  }
  for (int i = 0; i < 3; i++)
    for (int a = 0; a < 9; a++) W[i][a] = H[3 * i] * D[0][a] + H[3 * i + 1] * D[1][a] + H[3 * i + 2] * D[2][a];
  for (int a = 0; a < 9; a++)
    for (int b = a; b < 9; b++) {
      double v = 0;
      for (int i = 0; i < 3; i++) v += W[i][a] * D[i][b] + Sl[i][a] * S[i][b] + Tl[i][a] * T[i][b];
      K[9 * a + b] = K[9 * b + a] = v;
    }
}

/* The exact PSD projection of the blocks: eigenvalues clamped at zero. A
 * block with no negative eigenvalue is left untouched (bit for bit). */
static void project_blocks(double H[9], double lp[3], double lm[3]) {
  for (int p = 0; p < 3; p++) {
    if (lp[p] < 0) lp[p] = 0;
    if (lm[p] < 0) lm[p] = 0;
  }
  /* Cholesky pivots first: when they are all positive, H is positive definite
   * up to a backward error of a few ulps of |H| (the common case), and the
   * eigen-decomposition is skipped. */
  const double d0 = H[0];
  if (d0 > 0) {
    const double l1 = H[1] / d0, l2 = H[2] / d0;
    const double d1 = H[4] - l1 * H[1];
    if (d1 > 0) {
      const double e12 = H[5] - l1 * H[2];
      const double d2 = H[8] - l2 * H[2] - e12 * e12 / d1;
      if (d2 > 0) return;
    }
  }
  double lam[3], Q[9];
  bs_sym3_eig(H, lam, Q);
  if (lam[2] < 0) {
    for (int k = 0; k < 3; k++)
      if (lam[k] < 0) lam[k] = 0;
    bs_sym3_from_eig(lam, Q, H);
  }
}

/* The modal form of dP/dF from the SVD of F. */
static void modes_from_svd(const bs_material *m, const double U[9], const double s[3], const double V[9],
                           bs_psd_mode project_psd, bs_dPdF_modes *md) {
  double g[3];
  sv_eval(m, s, 2, g, md->H, md->lp, md->lm);
  /* sign(s[2]) = sign(det F) (bs_svd.h) */
  if (project_psd == BS_PSD_ALL || (project_psd == BS_PSD_INVERTED && !(s[2] > 0)))
    project_blocks(md->H, md->lp, md->lm);
  memcpy(md->U, U, sizeof md->U);
  memcpy(md->V, V, sizeof md->V);
}

void bs_material_dPdF_modes(const bs_material *m, const double F[9], bs_psd_mode project_psd, bs_dPdF_modes *out) {
  if (m->model == BS_MODEL_LINEAR) { /* no modal form: NaN, loudly */
    double *o = (double *)out;
    for (size_t i = 0; i < sizeof *out / sizeof(double); i++) o[i] = NAN;
    return;
  }
  double U[9], s[3], V[9];
  bs_svd3(F, U, s, V);
  modes_from_svd(m, U, s, V, project_psd, out);
}

void bs_material_dPdF(const bs_material *m, const double F[9], bs_psd_mode project_psd, double dPdF[81]) {
  if (m->model == BS_MODEL_LINEAR) {
    /* mu (d_ik d_jl + d_il d_jk) + lambda d_ij d_kl: constant, and PSD for
     * every admissible nu (eigenvalues 2 mu, 0 and 3 lambda + 2 mu = 3K > 0). */
    for (int a = 0; a < 81; a++) dPdF[a] = 0.0;
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        dPdF[9 * (3 * i + j) + 3 * i + j] += m->mu;
        dPdF[9 * (3 * i + j) + 3 * j + i] += m->mu;
      }
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) dPdF[9 * (4 * i) + 4 * k] += m->lambda;
    return;
  }
  bs_dPdF_modes md;
  bs_material_dPdF_modes(m, F, project_psd, &md);
  assemble_dPdF(md.U, md.V, md.H, md.lp, md.lm, dPdF);
}

void bs_material_dPdF_modes_batch(const bs_material *m, int n, const double *F, bs_psd_mode project_psd,
                                  bs_dPdF_modes *out) {
  if (m->model == BS_MODEL_LINEAR) {
    for (int i = 0; i < n; i++) bs_material_dPdF_modes(m, F + 9 * i, project_psd, out + i);
    return;
  }
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    double U[9 * BS_MATERIAL_BATCH], s[3 * BS_MATERIAL_BATCH], V[9 * BS_MATERIAL_BATCH];
    bs_svd3_batch(nb, F + 9 * i0, U, s, V);
    for (int i = 0; i < nb; i++) modes_from_svd(m, U + 9 * i, s + 3 * i, V + 9 * i, project_psd, out + i0 + i);
  }
}
