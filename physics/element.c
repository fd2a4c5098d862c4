/* element.c — the P1 tet kernel (see bs_element.h). */
#include "bs_element.h"

#include <math.h>
#include <string.h>

#include "polar_avx2.h"

void bs_tet_rest(const double X[12], double Dm_inv[9], double *volume) {
  double D[9];
  for (int m = 0; m < 3; m++)
    for (int k = 0; k < 3; k++) D[3 * m + k] = X[3 * (k + 1) + m] - X[m];
  /* cofactors (transposed: the adjugate) */
  const double c00 = D[4] * D[8] - D[5] * D[7], c01 = D[5] * D[6] - D[3] * D[8], c02 = D[3] * D[7] - D[4] * D[6];
  const double det = D[0] * c00 + D[1] * c01 + D[2] * c02;
  *volume = det / 6.0;
  if (det == 0.0 || !isfinite(det)) {
    for (int i = 0; i < 9; i++) Dm_inv[i] = 0.0;
    return;
  }
  const double id = 1.0 / det;
  Dm_inv[0] = c00 * id;
  Dm_inv[3] = c01 * id;
  Dm_inv[6] = c02 * id;
  Dm_inv[1] = (D[2] * D[7] - D[1] * D[8]) * id;
  Dm_inv[4] = (D[0] * D[8] - D[2] * D[6]) * id;
  Dm_inv[7] = (D[1] * D[6] - D[0] * D[7]) * id;
  Dm_inv[2] = (D[1] * D[5] - D[2] * D[4]) * id;
  Dm_inv[5] = (D[2] * D[3] - D[0] * D[5]) * id;
  Dm_inv[8] = (D[0] * D[4] - D[1] * D[3]) * id;
}

void bs_tet_F(const double x[12], const double Dm_inv[9], double F[9]) {
  for (int m = 0; m < 3; m++) {
    const double d1 = x[3 + m] - x[m], d2 = x[6 + m] - x[m], d3 = x[9 + m] - x[m];
    for (int j = 0; j < 3; j++) F[3 * m + j] = d1 * Dm_inv[j] + d2 * Dm_inv[3 + j] + d3 * Dm_inv[6 + j];
  }
}

/* w[a][j] = dF_mj / dx_{a,m}. */
static void shape_weights(const double Dm_inv[9], double w[4][3]) {
  for (int j = 0; j < 3; j++) {
    w[1][j] = Dm_inv[j];
    w[2][j] = Dm_inv[3 + j];
    w[3][j] = Dm_inv[6 + j];
    w[0][j] = -(w[1][j] + w[2][j] + w[3][j]);
  }
}

/* g = vol G^T P. */
static void grad_from_P(const double P[9], const double Dm_inv[9], double vol, double g[12]) {
  double w[4][3];
  shape_weights(Dm_inv, w);
  for (int a = 0; a < 4; a++)
    for (int c = 0; c < 3; c++)
      g[3 * a + c] = vol * (P[3 * c] * w[a][0] + P[3 * c + 1] * w[a][1] + P[3 * c + 2] * w[a][2]);
}

/* H = vol G^T K G. */
static void hessian_from_K(const double K[81], const double Dm_inv[9], double vol, double H[144]);

double bs_tet_energy(const bs_material *m, const double x[12], const double Dm_inv[9], double vol) {
  double F[9];
  bs_tet_F(x, Dm_inv, F);
  return vol * bs_material_psi(m, F);
}

double bs_tet_energy_grad(const bs_material *m, const double x[12], const double Dm_inv[9], double vol,
                          double g[12]) {
  double F[9], P[9];
  bs_tet_F(x, Dm_inv, F);
  const double psi = bs_material_psi_P(m, F, P);
  grad_from_P(P, Dm_inv, vol, g);
  return vol * psi;
}

/* H = vol G^T dP/dF G from the modal form of dP/dF (bs_dPdF_modes). Every
 * mode's 3-vector at a vertex a lies in span(u_0, u_1, u_2): with
 * x_i = v_i . w_a and y_i = v_i . w_b, block (a, b) of H is vol U N U^T, where
 *   N_ii = H_ii x_i y_i + sum over the pairs p = {i, j}: (lp_p + lm_p)/2 x_j y_j,
 *   N_ij = H_ij x_i y_j + (lp_p - lm_p)/2 x_j y_i   (i != j, p = {i, j}).
 * The blocks among vertices 1..3 are formed so; those with vertex 0 are
 * minus the sums of the others (w_0 = -(w_1 + w_2 + w_3)). Diagonal blocks
 * are made exactly symmetric, and block (b, a) is block (a, b) transposed. */
#ifdef BS_POLAR_AVX2
static void hessian_from_modes_x4(const bs_dPdF_modes *md, const double *Dm, const double *vol, double *H);
static int have_fma(void) { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }
#endif

static void hessian_from_modes(const bs_dPdF_modes *md, const double Dm_inv[9], double vol, double H[144]) {
#ifdef BS_POLAR_AVX2
  if (have_fma()) { /* the 4-lane kernel's arithmetic (lane 0), see hessian_from_modes_x4 */
    const bs_dPdF_modes m4[4] = {*md, *md, *md, *md};
    double D4[36], v4[4] = {vol, vol, vol, vol}, H4[576];
    for (int l = 0; l < 4; l++) memcpy(D4 + 9 * l, Dm_inv, 9 * sizeof(double));
    hessian_from_modes_x4(m4, D4, v4, H4);
    memcpy(H, H4, 144 * sizeof(double));
    return;
  }
#endif
  const double *U = md->U, *V = md->V, *Hs = md->H;
  double x[4][3]; /* x[a][i] = v_i . w_a, a = 1..3 (w_a = row a-1 of Dm_inv) */
  for (int a = 1; a < 4; a++)
    for (int i = 0; i < 3; i++)
      x[a][i] = V[i] * Dm_inv[3 * (a - 1)] + V[3 + i] * Dm_inv[3 * (a - 1) + 1] + V[6 + i] * Dm_inv[3 * (a - 1) + 2];
  /* pairs (0,1), (0,2), (1,2): halves of the sums and differences, times vol */
  double sp[3], dm[3], h[9];
  for (int p = 0; p < 3; p++) {
    sp[p] = 0.5 * vol * (md->lp[p] + md->lm[p]);
    dm[p] = 0.5 * vol * (md->lp[p] - md->lm[p]);
  }
  for (int i = 0; i < 9; i++) h[i] = vol * Hs[i];
  double B[4][4][9]; /* B[a][b]: block (a, b), row-major */
  for (int a = 1; a < 4; a++)
    for (int b = a; b < 4; b++) {
      double xy[9];
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) xy[3 * i + j] = x[a][i] * x[b][j];
      const double N[9] = {h[0] * xy[0] + sp[0] * xy[4] + sp[1] * xy[8],
                           h[1] * xy[1] + dm[0] * xy[3],
                           h[2] * xy[2] + dm[1] * xy[6],
                           h[1] * xy[3] + dm[0] * xy[1],
                           h[4] * xy[4] + sp[0] * xy[0] + sp[2] * xy[8],
                           h[5] * xy[5] + dm[2] * xy[7],
                           h[2] * xy[6] + dm[1] * xy[2],
                           h[5] * xy[7] + dm[2] * xy[5],
                           h[8] * xy[8] + sp[1] * xy[0] + sp[2] * xy[4]};
      double M[9]; /* U N */
      for (int r = 0; r < 3; r++)
        for (int j = 0; j < 3; j++) M[3 * r + j] = U[3 * r] * N[j] + U[3 * r + 1] * N[3 + j] + U[3 * r + 2] * N[6 + j];
      double *Bab = B[a][b];
      for (int r = 0; r < 3; r++)
        for (int c = (a == b ? r : 0); c < 3; c++)
          Bab[3 * r + c] = M[3 * r] * U[3 * c] + M[3 * r + 1] * U[3 * c + 1] + M[3 * r + 2] * U[3 * c + 2];
      if (a == b)
        for (int r = 0; r < 3; r++)
          for (int c = r + 1; c < 3; c++) Bab[3 * c + r] = Bab[3 * r + c];
    }
  for (int a = 2; a < 4; a++)
    for (int b = 1; b < a; b++)
      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) B[a][b][3 * r + c] = B[b][a][3 * c + r];
  for (int b = 1; b < 4; b++)
    for (int k = 0; k < 9; k++) B[0][b][k] = -(B[1][b][k] + B[2][b][k] + B[3][b][k]);
  for (int r = 0; r < 3; r++)
    for (int c = r; c < 3; c++)
      B[0][0][3 * r + c] = B[0][0][3 * c + r] = -(B[0][1][3 * r + c] + B[0][2][3 * r + c] + B[0][3][3 * r + c]);
  for (int b = 1; b < 4; b++)
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) B[b][0][3 * r + c] = B[0][b][3 * c + r];
  for (int a = 0; a < 4; a++)
    for (int b = 0; b < 4; b++)
      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) H[12 * (3 * a + r) + 3 * b + c] = B[a][b][3 * r + c];
}

void bs_tet_hessian(const bs_material *m, const double x[12], const double Dm_inv[9], double vol, bs_psd_mode project_psd,
                    double H[144]) {
  double F[9];
  bs_tet_F(x, Dm_inv, F);
  if (m->model == BS_MODEL_LINEAR) {
    double K[81];
    bs_material_dPdF(m, F, project_psd, K);
    hessian_from_K(K, Dm_inv, vol, H);
    return;
  }
  bs_dPdF_modes md;
  bs_material_dPdF_modes(m, F, project_psd, &md);
  hessian_from_modes(&md, Dm_inv, vol, H);
}

static void hessian_from_K(const double K[81], const double Dm_inv[9], double vol, double H[144]) {
  double w[4][3];
  shape_weights(Dm_inv, w);
  /* H[(a,c),(b,e)] = vol sum_{j,l} w[a][j] K[(c,j),(e,l)] w[b][l], by 3x3
   * blocks K_ce of K; only c <= e (and a <= b when c = e), then mirrored. */
  for (int c = 0; c < 3; c++)
    for (int e = c; e < 3; e++) {
      double T[4][3];
      for (int a = 0; a < 4; a++)
        for (int l = 0; l < 3; l++)
          T[a][l] = vol * (w[a][0] * K[9 * (3 * c) + 3 * e + l] + w[a][1] * K[9 * (3 * c + 1) + 3 * e + l] +
                           w[a][2] * K[9 * (3 * c + 2) + 3 * e + l]);
      for (int a = 0; a < 4; a++)
        for (int b = (c == e ? a : 0); b < 4; b++) {
          const double v = T[a][0] * w[b][0] + T[a][1] * w[b][1] + T[a][2] * w[b][2];
          H[12 * (3 * a + c) + 3 * b + e] = H[12 * (3 * b + e) + 3 * a + c] = v;
        }
    }
}

/* ---- fused kernels of the corotated models (AVX2) ---------------------------
 * Energy (and gradient) of 4 tets in the lanes of AVX2 registers: bs_tet_F,
 * bs_polar3 (polar_avx2.h), the polar formulas of material.c's polar_psi_P and
 * grad_from_P, each operation in the order of the scalar code and without
 * FMA, so every lane is bs_tet_energy(_grad) bit for bit (test_element's
 * batch_bitwise). This saves the transposes between the stages: F, R, P and
 * the gradient never leave the registers. Lanes that bs_polar3 declines
 * (inverted or extreme F) are returned to the caller, which takes them
 * through bs_material_psi_P_batch like any other model. */
#ifdef BS_POLAR_AVX2
typedef __m256d v4;
#define VADD _mm256_add_pd
#define VSUB _mm256_sub_pd
#define VMUL _mm256_mul_pd

/* Returns the mask of the lanes done (e, g written); F of every lane is
 * written to Fout (9 per tet). g == NULL: energy only. */
BS_AVX2_FN static int corotated_x4(const bs_material *m, const double *x, const double *Dm, const double *vol,
                                   double *e, double *g, double *Fout) {
  v4 X[12], W[9], F[9], R[9];
  for (int i = 0; i < 12; i++) X[i] = _mm256_set_pd(x[36 + i], x[24 + i], x[12 + i], x[i]);
  for (int i = 0; i < 9; i++) W[i] = _mm256_set_pd(Dm[27 + i], Dm[18 + i], Dm[9 + i], Dm[i]);
  const v4 V = _mm256_set_pd(vol[3], vol[2], vol[1], vol[0]);
  for (int r = 0; r < 3; r++) { /* bs_tet_F */
    const v4 d1 = VSUB(X[3 + r], X[r]), d2 = VSUB(X[6 + r], X[r]), d3 = VSUB(X[9 + r], X[r]);
    for (int j = 0; j < 3; j++) F[3 * r + j] = VADD(VADD(VMUL(d1, W[j]), VMUL(d2, W[3 + j])), VMUL(d3, W[6 + j]));
  }
  for (int i = 0; i < 9; i++) R[i] = F[i];
  const int done = _mm256_movemask_pd(bs_polar_avx2(R));
  double o[13][4];
  for (int i = 0; i < 9; i++) _mm256_storeu_pd(o[i], F[i]);
  for (int l = 0; l < 4; l++)
    for (int i = 0; i < 9; i++) Fout[9 * l + i] = o[i][l];
  if (!done) return 0;
  /* polar_psi_P */
  v4 D[9], dd = _mm256_setzero_pd(), rd = _mm256_setzero_pd();
  for (int i = 0; i < 9; i++) {
    D[i] = VSUB(F[i], R[i]);
    dd = VADD(dd, VMUL(D[i], D[i]));
    rd = VADD(rd, VMUL(R[i], D[i]));
  }
  const v4 mu = _mm256_set1_pd(m->mu), la = _mm256_set1_pd(m->lambda), hla = _mm256_set1_pd(0.5 * m->lambda);
  const v4 mu2 = _mm256_set1_pd(2.0 * m->mu), one = _mm256_set1_pd(1.0);
  v4 psi, P[9], s, Q[9]; /* P = mu2 D + s Q */
  if (m->model == BS_MODEL_COROTATED) {
    psi = VADD(VMUL(mu, dd), VMUL(VMUL(hla, rd), rd));
    s = VMUL(la, rd);
    for (int i = 0; i < 9; i++) Q[i] = R[i];
  } else {
    v4 G[9];
    for (int i = 0; i < 9; i++) G[i] = i % 4 == 0 ? VSUB(F[i], one) : F[i];
    const v4 minors = VADD(VADD(VSUB(VMUL(G[0], G[4]), VMUL(G[1], G[3])), VSUB(VMUL(G[0], G[8]), VMUL(G[2], G[6]))),
                           VSUB(VMUL(G[4], G[8]), VMUL(G[5], G[7])));
    const v4 detG = VADD(VADD(VMUL(G[0], VSUB(VMUL(G[4], G[8]), VMUL(G[5], G[7]))),
                              VMUL(G[1], VSUB(VMUL(G[5], G[6]), VMUL(G[3], G[8])))),
                         VMUL(G[2], VSUB(VMUL(G[3], G[7]), VMUL(G[4], G[6]))));
    const v4 Jm1 = VADD(VADD(VADD(VADD(G[0], G[4]), G[8]), minors), detG);
    psi = VADD(VMUL(mu, dd), VMUL(VMUL(hla, Jm1), Jm1));
    s = VMUL(la, Jm1);
    bs_avx2_cof(F, Q);
  }
  _mm256_storeu_pd(o[12], VMUL(V, psi));
  if (g) {
    for (int i = 0; i < 9; i++) P[i] = VADD(VMUL(mu2, D[i]), VMUL(s, Q[i]));
    /* grad_from_P: w_a = row a-1 of Dm_inv, w_0 = -(w_1 + w_2 + w_3) */
    v4 w0[3];
    for (int j = 0; j < 3; j++)
      w0[j] = _mm256_xor_pd(VADD(VADD(W[j], W[3 + j]), W[6 + j]), _mm256_set1_pd(-0.0));
    for (int a = 0; a < 4; a++) {
      const v4 *w = a == 0 ? w0 : W + 3 * (a - 1);
      for (int c = 0; c < 3; c++)
        _mm256_storeu_pd(o[3 * a + c],
                         VMUL(V, VADD(VADD(VMUL(P[3 * c], w[0]), VMUL(P[3 * c + 1], w[1])), VMUL(P[3 * c + 2], w[2]))));
    }
  }
  for (int l = 0; l < 4; l++) {
    if (!((done >> l) & 1)) continue;
    e[l] = o[12][l];
    if (g)
      for (int i = 0; i < 12; i++) g[12 * l + i] = o[i][l];
  }
  return done;
}

#define FMA _mm256_fmadd_pd
/* hessian_from_modes on 4 tets in the lanes of AVX2 registers, with FMA:
 * hessian_from_modes itself uses it on CPUs with AVX2 and FMA (one tet in
 * lane 0), so the batched and single-tet Hessians agree bit for bit
 * (test_element's batch_bitwise); the portable code below is for the others.
 * O holds H entry by entry (lanes = tets) and is transposed out 4 entries
 * at a time. */
__attribute__((target("avx2,fma"))) static void hessian_from_modes_x4(const bs_dPdF_modes *md, const double *Dm, const double *vol,
                                             double *H) {
  v4 U[9], V[9], W[9], h[9], sp[3], dm[3], x[4][3], O[144];
  const v4 vl = _mm256_set_pd(vol[3], vol[2], vol[1], vol[0]), hv = VMUL(_mm256_set1_pd(0.5), vl);
  for (int i = 0; i < 9; i++) {
    U[i] = _mm256_set_pd(md[3].U[i], md[2].U[i], md[1].U[i], md[0].U[i]);
    V[i] = _mm256_set_pd(md[3].V[i], md[2].V[i], md[1].V[i], md[0].V[i]);
    W[i] = _mm256_set_pd(Dm[27 + i], Dm[18 + i], Dm[9 + i], Dm[i]);
    h[i] = VMUL(vl, _mm256_set_pd(md[3].H[i], md[2].H[i], md[1].H[i], md[0].H[i]));
  }
  for (int p = 0; p < 3; p++) {
    const v4 lp = _mm256_set_pd(md[3].lp[p], md[2].lp[p], md[1].lp[p], md[0].lp[p]);
    const v4 lm = _mm256_set_pd(md[3].lm[p], md[2].lm[p], md[1].lm[p], md[0].lm[p]);
    sp[p] = VMUL(hv, VADD(lp, lm));
    dm[p] = VMUL(hv, VSUB(lp, lm));
  }
  for (int a = 1; a < 4; a++)
    for (int i = 0; i < 3; i++)
      x[a][i] = FMA(V[6 + i], W[3 * (a - 1) + 2], FMA(V[3 + i], W[3 * (a - 1) + 1], VMUL(V[i], W[3 * (a - 1)])));
#define HO(a, r, b, c) O[12 * (3 * (a) + (r)) + 3 * (b) + (c)]
  for (int a = 1; a < 4; a++)
    for (int b = a; b < 4; b++) {
      v4 xy[9], M[9];
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) xy[3 * i + j] = VMUL(x[a][i], x[b][j]);
      const v4 N[9] = {FMA(sp[1], xy[8], FMA(sp[0], xy[4], VMUL(h[0], xy[0]))), FMA(dm[0], xy[3], VMUL(h[1], xy[1])),
                       FMA(dm[1], xy[6], VMUL(h[2], xy[2])),
                       FMA(dm[0], xy[1], VMUL(h[1], xy[3])),
                       FMA(sp[2], xy[8], FMA(sp[0], xy[0], VMUL(h[4], xy[4]))),
                       FMA(dm[2], xy[7], VMUL(h[5], xy[5])),
                       FMA(dm[1], xy[2], VMUL(h[2], xy[6])),
                       FMA(dm[2], xy[5], VMUL(h[5], xy[7])),
                       FMA(sp[2], xy[4], FMA(sp[1], xy[0], VMUL(h[8], xy[8])))};
      for (int r = 0; r < 3; r++)
        for (int j = 0; j < 3; j++)
          M[3 * r + j] = FMA(U[3 * r + 2], N[6 + j], FMA(U[3 * r + 1], N[3 + j], VMUL(U[3 * r], N[j])));
      for (int r = 0; r < 3; r++)
        for (int c = (a == b ? r : 0); c < 3; c++)
          HO(a, r, b, c) = FMA(M[3 * r + 2], U[3 * c + 2], FMA(M[3 * r + 1], U[3 * c + 1], VMUL(M[3 * r], U[3 * c])));
      if (a == b)
        for (int r = 0; r < 3; r++)
          for (int c = r + 1; c < 3; c++) HO(a, c, a, r) = HO(a, r, a, c);
    }
  const v4 neg = _mm256_set1_pd(-0.0);
  for (int a = 2; a < 4; a++)
    for (int b = 1; b < a; b++)
      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) HO(a, r, b, c) = HO(b, c, a, r);
  for (int b = 1; b < 4; b++)
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++)
        HO(0, r, b, c) = _mm256_xor_pd(VADD(VADD(HO(1, r, b, c), HO(2, r, b, c)), HO(3, r, b, c)), neg);
  for (int r = 0; r < 3; r++)
    for (int c = r; c < 3; c++)
      HO(0, r, 0, c) = HO(0, c, 0, r) =
          _mm256_xor_pd(VADD(VADD(HO(0, r, 1, c), HO(0, r, 2, c)), HO(0, r, 3, c)), neg);
  for (int b = 1; b < 4; b++)
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) HO(b, r, 0, c) = HO(0, c, b, r);
#undef HO
  for (int k = 0; k < 144; k += 4) { /* 4x4 transposes: entries k..k+3 of each tet */
    const v4 t0 = _mm256_unpacklo_pd(O[k], O[k + 1]), t1 = _mm256_unpackhi_pd(O[k], O[k + 1]);
    const v4 t2 = _mm256_unpacklo_pd(O[k + 2], O[k + 3]), t3 = _mm256_unpackhi_pd(O[k + 2], O[k + 3]);
    _mm256_storeu_pd(H + k, _mm256_permute2f128_pd(t0, t2, 0x20));
    _mm256_storeu_pd(H + 144 + k, _mm256_permute2f128_pd(t1, t3, 0x20));
    _mm256_storeu_pd(H + 288 + k, _mm256_permute2f128_pd(t0, t2, 0x31));
    _mm256_storeu_pd(H + 432 + k, _mm256_permute2f128_pd(t1, t3, 0x31));
  }
}
#undef FMA
#undef VADD
#undef VSUB
#undef VMUL
#endif

/* Energy (and gradient when g != NULL) of n <= BS_MATERIAL_BATCH tets: the
 * corotated models 4 at a time by corotated_x4 where the CPU has AVX2, every
 * other tet (declined lanes, the rest of the batch, other models) by
 * bs_material_psi(_P)_batch. */
static void energy_grad_block(const bs_material *m, int n, const double *x, const double *Dm_inv, const double *vol,
                              double *e, double *g) {
  enum { B = BS_MATERIAL_BATCH };
  double F[9 * B], Fr[9 * B], P[9 * B], psi[B];
  int idx[B], nr = 0, i = 0;
#ifdef BS_POLAR_AVX2
  if ((m->model == BS_MODEL_FIXED_COROTATED || m->model == BS_MODEL_COROTATED) && __builtin_cpu_supports("avx2"))
    for (; i + 4 <= n; i += 4) {
      const int done = corotated_x4(m, x + 12 * i, Dm_inv + 9 * i, vol + i, e + i, g ? g + 12 * i : NULL, F + 9 * i);
      for (int l = 0; l < 4; l++)
        if (!((done >> l) & 1)) idx[nr++] = i + l;
    }
#endif
  for (; i < n; i++) {
    bs_tet_F(x + 12 * i, Dm_inv + 9 * i, F + 9 * i);
    idx[nr++] = i;
  }
  if (nr == 0) return;
  for (int k = 0; k < nr; k++) memcpy(Fr + 9 * k, F + 9 * idx[k], 9 * sizeof(double));
  if (g)
    bs_material_psi_P_batch(m, nr, Fr, psi, P);
  else
    bs_material_psi_batch(m, nr, Fr, psi);
  for (int k = 0; k < nr; k++) {
    const int t = idx[k];
    if (g) grad_from_P(P + 9 * k, Dm_inv + 9 * t, vol[t], g + 12 * t);
    e[t] = vol[t] * psi[k];
  }
}

void bs_tet_energy_batch(const bs_material *m, int n, const double *x, const double *Dm_inv, const double *vol,
                         double *e) {
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    energy_grad_block(m, nb, x + 12 * i0, Dm_inv + 9 * i0, vol + i0, e + i0, NULL);
  }
}

void bs_tet_energy_grad_batch(const bs_material *m, int n, const double *x, const double *Dm_inv,
                              const double *vol, double *e, double *g) {
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    energy_grad_block(m, nb, x + 12 * i0, Dm_inv + 9 * i0, vol + i0, e + i0, g + 12 * i0);
  }
}

void bs_tet_hessian_batch(const bs_material *m, int n, const double *x, const double *Dm_inv, const double *vol,
                          bs_psd_mode project_psd, double *H) {
  if (m->model == BS_MODEL_LINEAR) {
    for (int i = 0; i < n; i++) bs_tet_hessian(m, x + 12 * i, Dm_inv + 9 * i, vol[i], project_psd, H + 144 * i);
    return;
  }
  for (int i0 = 0; i0 < n; i0 += BS_MATERIAL_BATCH) {
    const int nb = n - i0 < BS_MATERIAL_BATCH ? n - i0 : BS_MATERIAL_BATCH;
    double F[9 * BS_MATERIAL_BATCH];
    bs_dPdF_modes md[BS_MATERIAL_BATCH];
    for (int i = 0; i < nb; i++) bs_tet_F(x + 12 * (i0 + i), Dm_inv + 9 * (i0 + i), F + 9 * i);
    bs_material_dPdF_modes_batch(m, nb, F, project_psd, md);
    int i = 0;
#ifdef BS_POLAR_AVX2
    if (have_fma())
      for (; i + 4 <= nb; i += 4)
        hessian_from_modes_x4(md + i, Dm_inv + 9 * (i0 + i), vol + i0 + i, H + 144 * (i0 + i));
#endif
    for (; i < nb; i++) hessian_from_modes(md + i, Dm_inv + 9 * (i0 + i), vol[i0 + i], H + 144 * (i0 + i));
  }
}
