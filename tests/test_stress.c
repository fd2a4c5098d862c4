/* Stress and strain measures (physics/bs_stress.h) against closed forms:
 * for each of the five models, a homogeneously stretched cube F = diag(l)
 * and the same stretch rotated on the left (F = Q diag(l): sigma rotates
 * with Q, frame objectivity) and on the right (F = diag(l) Q: sigma does not
 * change) gives the model's analytic Cauchy stress to 1e-10 relative; the
 * Green strain, stretches, J and von Mises are checked beside it. Then the
 * cell fields of sim/bs_fields.h on a real box mesh deformed homogeneously
 * equal the element values in every cell, and the VTU written from them
 * carries them. */
#define _GNU_SOURCE /* mkstemps */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_fields.h"
#include "bs_material.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_stress.h"
#include "bs_vtu_read.h"

static const bs_model models[5] = {BS_MODEL_FIXED_COROTATED, BS_MODEL_COROTATED, BS_MODEL_NEO_HOOKEAN,
                                   BS_MODEL_STABLE_NEO_HOOKEAN, BS_MODEL_LINEAR};

static bs_material make(bs_model model) {
  bs_material m;
  bs_error err = {0};
  cr_assert_eq(bs_material_init(model, 2.5e6, 0.35, 1100, &m, &err), 0, "%s", err.msg);
  return m;
}

/* The principal Cauchy stresses of the model at principal stretches l,
 * derived by hand from the energies of bs_material.h (J = l0 l1 l2, b = F F^T
 * with eigenvalues l_i^2, V = sqrt(b) the left stretch):
 *  fixed corotated  P = 2 mu (F - R) + lambda (J - 1) J F^-T
 *                   sigma = 2 mu / J (b - V) + lambda (J - 1) I
 *  corotated        P = 2 mu (F - R) + lambda tr(S - I) R
 *                   sigma = (2 mu (b - V) + lambda (tr V - 3) V) / J
 *  neo-Hookean      P = mu F + (lambda ln J - mu) F^-T  (J >= J0)
 *                   sigma = mu / J (b - I) + lambda ln J / J I
 *  stable n.-H.     P = mu' (1 - 1 / (I_C + 1)) F + lambda' (J - alpha) J F^-T
 *                   sigma = mu' (1 - 1 / (I_C + 1)) b / J + lambda' (J - alpha) I
 *  linear (F = diag(l) only: not objective)
 *                   P = 2 mu (F - I) + lambda tr(F - I) I,  sigma = P F / J. */
static void analytic(const bs_material *m, const double l[3], double s[3]) {
  const double mu = m->mu, la = m->lambda, J = l[0] * l[1] * l[2];
  const double tr = l[0] + l[1] + l[2], Ic = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
  const double mu2 = 4.0 * mu / 3.0, la2 = la + 5.0 * mu / 6.0, alpha = 1.0 + 0.75 * mu2 / la2;
  for (int i = 0; i < 3; i++) {
    const double li = l[i];
    switch (m->model) {
      case BS_MODEL_FIXED_COROTATED: s[i] = 2.0 * mu / J * (li * li - li) + la * (J - 1.0); break;
      case BS_MODEL_COROTATED: s[i] = (2.0 * mu * (li * li - li) + la * (tr - 3.0) * li) / J; break;
      case BS_MODEL_NEO_HOOKEAN: s[i] = mu / J * (li * li - 1.0) + la * log(J) / J; break;
      case BS_MODEL_STABLE_NEO_HOOKEAN: s[i] = mu2 * (1.0 - 1.0 / (Ic + 1.0)) * li * li / J + la2 * (J - alpha); break;
      case BS_MODEL_LINEAR: s[i] = (2.0 * mu * (li - 1.0) + la * (tr - 3.0)) * li / J; break;
    }
  }
}

/* A rotation: axis-angle (axis normalized here), Rodrigues. */
static void rotation(const double axis[3], double th, double Q[9]) {
  double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  double k[3] = {axis[0] / n, axis[1] / n, axis[2] / n}, c = cos(th), s = sin(th), C = 1 - c;
  double R[9] = {c + k[0] * k[0] * C,        k[0] * k[1] * C - k[2] * s, k[0] * k[2] * C + k[1] * s,
                 k[1] * k[0] * C + k[2] * s, c + k[1] * k[1] * C,        k[1] * k[2] * C - k[0] * s,
                 k[2] * k[0] * C - k[1] * s, k[2] * k[1] * C + k[0] * s, c + k[2] * k[2] * C};
  memcpy(Q, R, sizeof R);
}

static void matmul(const double A[9], const double B[9], double C[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

/* Q diag(d) Q^T. */
static void rotate_diag(const double Q[9], const double d[3], double out[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) out[3 * i + j] = Q[3 * i] * d[0] * Q[3 * j] + Q[3 * i + 1] * d[1] * Q[3 * j + 1] +
                                                 Q[3 * i + 2] * d[2] * Q[3 * j + 2];
}

static double rel_err9(const double *a, const double *b) {
  double e = 0, n = 0;
  for (int i = 0; i < 9; i++) {
    e = fmax(e, fabs(a[i] - b[i]));
    n = fmax(n, fabs(b[i]));
  }
  return e / n;
}

/* Stretches: tension, compression, mixed, near-incompressible. */
static const double stretches[4][3] = {{1.2, 0.95, 1.05}, {0.8, 0.9, 0.85}, {1.5, 0.7, 1.0}, {1.1, 0.953, 0.953}};

static void check_case(const bs_material *m, const double l[3], const double Q[9], int left) {
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, D[9] = {l[0], 0, 0, 0, l[1], 0, 0, 0, l[2]};
  double F[9], s[3], want[9], E[9], Ed[3];
  if (left) matmul(Q, D, F);
  else matmul(D, Q, F);
  analytic(m, l, s);
  rotate_diag(left ? Q : I, s, want); /* F = Q D: b = Q D^2 Q^T; F = D Q: b = D^2 */
  bs_stress_fields f;
  bs_stress_eval(m, F, &f);
  const char *name = bs_model_name(m->model);
  cr_assert_lt(rel_err9(f.cauchy, want), 1e-10, "%s, l = (%g, %g, %g), %s rotation: Cauchy off by %.3g relative", name,
               l[0], l[1], l[2], left ? "left" : "right", rel_err9(f.cauchy, want));
  for (int i = 0; i < 3; i++) Ed[i] = 0.5 * (l[i] * l[i] - 1.0);
  double Qt[9]; /* C = F^T F: D^2 for F = Q D, Q^T D^2 Q for F = D Q */
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) Qt[3 * i + j] = Q[3 * j + i];
  rotate_diag(left ? I : Qt, Ed, E);
  cr_assert_lt(rel_err9(f.green, E), 1e-13, "%s: Green strain", name);
  cr_assert_float_eq(f.J, l[0] * l[1] * l[2], 1e-14, "%s: J", name);
  double vm = sqrt(0.5 * ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) + (s[2] - s[0]) * (s[2] - s[0])));
  cr_assert_float_eq(f.von_mises, vm, 1e-10 * fmax(1.0, fabs(s[0]) + fabs(s[1]) + fabs(s[2])), "%s: von Mises", name);
  double sorted[3] = {l[0], l[1], l[2]};
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      if (sorted[j] > sorted[i]) {
        double t = sorted[i];
        sorted[i] = sorted[j];
        sorted[j] = t;
      }
  for (int i = 0; i < 3; i++) cr_assert_float_eq(f.stretch[i], sorted[i], 1e-13, "%s: stretch %d", name, i);
  cr_assert_float_eq(f.psi, bs_material_psi(m, F), 1e-12 * fmax(1.0, fabs(f.psi)), "%s: psi", name);
}

Test(stress, analytic_cauchy_of_the_five_models) {
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, axis[3] = {1, -2, 0.5};
  double Q[9];
  rotation(axis, 0.7, Q);
  for (int k = 0; k < 5; k++) {
    bs_material m = make(models[k]);
    for (int c = 0; c < 4; c++) {
      check_case(&m, stretches[c], I, 1);
      if (m.model == BS_MODEL_LINEAR) continue; /* small strain: not frame objective */
      check_case(&m, stretches[c], Q, 1);
      check_case(&m, stretches[c], Q, 0);
    }
  }
}

Test(stress, rest_is_stress_free_and_degenerate_is_nan) {
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, Z[9] = {1, 0, 0, 0, 1, 0, 0, 0, 0};
  for (int k = 0; k < 5; k++) {
    bs_material m = make(models[k]);
    bs_stress_fields f;
    bs_stress_eval(&m, I, &f);
    for (int i = 0; i < 9; i++) {
      cr_assert_float_eq(f.cauchy[i], 0.0, 1e-9, "%s: sigma at rest", bs_model_name(m.model));
      cr_assert_eq(f.green[i], 0.0);
    }
    cr_assert_eq(f.J, 1.0);
    bs_stress_eval(&m, Z, &f); /* flat: J = 0 */
    cr_assert(isnan(f.cauchy[0]) && isnan(f.von_mises), "%s: sigma of a flat element", bs_model_name(m.model));
    cr_assert(isfinite(f.P[0]) && isfinite(f.psi));
  }
}

Test(stress, uniaxial_von_mises_is_the_axial_stress) {
  const double s[9] = {-3.5e5, 0, 0, 0, 0, 0, 0, 0, 0}, shear[9] = {0, 2e3, 0, 2e3, 0, 0, 0, 0, 0};
  cr_assert_float_eq(bs_von_mises(s), 3.5e5, 1e-9);
  cr_assert_float_eq(bs_von_mises(shear), sqrt(3.0) * 2e3, 1e-9);
}

/* ---- the mesh path ------------------------------------------------------- */

/* A 3x2x2-cell box of the model, in a scene of two frames; simulation made. */
static bs_sim *box_sim(bs_scene **sc, bs_model model) {
  bs_scene_body *b = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_create(sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_add_body(*sc, "box", &b, &err), 0, "%s", err.msg);
  b->box_cells[0] = 3;
  b->box_cells[1] = b->box_cells[2] = 2;
  b->box_size[0] = 1.5;
  b->materials[0] = (bs_scene_material){.model = model, .youngs = 2.5e6, .poisson = 0.35, .density = 1100};
  bs_scene_script *clamp = NULL;
  cr_assert_eq(bs_scene_body_add_script(b, "xmin", BS_SCRIPT_FIXED, &clamp, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_validate(*sc, &err), 0, "%s", err.msg);
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(*sc, &s, &err), 0, "%s", err.msg);
  return s;
}

/* x = F X + c on every vertex: F is the same in every tet. */
static void deform(bs_sim *s, const double F[9]) {
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    const double *X = s->x0 + 3 * v;
    for (int i = 0; i < 3; i++) s->x[3 * v + i] = F[3 * i] * X[0] + F[3 * i + 1] * X[1] + F[3 * i + 2] * X[2] + 0.1 * i;
  }
}

static void check_cells(const bs_fields *fl, const bs_stress_fields *want, int32_t nt) {
  for (int32_t t = 0; t < nt; t++) {
    cr_assert_lt(rel_err9(fl->cauchy + 9 * t, want->cauchy), 1e-10, "tet %d: Cauchy", t);
    cr_assert_lt(rel_err9(fl->P + 9 * t, want->P), 1e-10, "tet %d: P", t);
    cr_assert_lt(rel_err9(fl->green + 9 * t, want->green), 1e-10, "tet %d: Green", t);
    cr_assert_float_eq(fl->von_mises[t], want->von_mises, 1e-10 * want->von_mises, "tet %d: von Mises", t);
    cr_assert_float_eq(fl->psi[t], want->psi, 1e-10 * want->psi, "tet %d: psi", t);
    cr_assert_float_eq(fl->J[t], want->J, 1e-12, "tet %d: J", t);
    for (int k = 0; k < 3; k++) cr_assert_float_eq(fl->stretch[3 * t + k], want->stretch[k], 1e-12, "tet %d", t);
  }
}

/* The VTU written from the fields carries the element values. */
static void check_vtu(bs_fields *fl, const bs_sim *s, const bs_stress_fields *want) {
  char path[] = "/tmp/bs_test_stress_XXXXXX.vtu";
  int fd = mkstemps(path, 4);
  cr_assert(fd >= 0);
  close(fd);
  bs_error err;
  cr_assert_eq(bs_fields_write_vtu(fl, s, path, &err), 0, "%s", err.msg);
  bs_vtu *v = NULL;
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  const bs_vtu_array *c = bs_vtu_cell_array(v, "cauchy"), *vm = bs_vtu_cell_array(v, "von_mises");
  const bs_vtu_array *body = bs_vtu_cell_array(v, "body"), *scr = bs_vtu_point_array(v, "scripted");
  cr_assert(c && vm && body && scr, "cauchy, von_mises, body and scripted are written");
  cr_assert_eq(c->ncomp, 9);
  for (int32_t t = 0; t < v->n_cells; t++) {
    cr_assert_lt(rel_err9(c->data + 9 * t, want->cauchy), 1e-10, "vtu tet %d", t);
    cr_assert_eq(body->data[t], 0.0);
  }
  int32_t n_scripted = 0;
  for (int32_t p = 0; p < v->n_points; p++) n_scripted += scr->data[p] != 0;
  cr_assert_eq(n_scripted, s->mesh->n_vertices - s->n_free, "the clamped face's vertices are flagged");
  bs_vtu_destroy(&v);
  unlink(path);
}

Test(stress, mesh_fields_equal_the_element_values) {
  const double axis[3] = {0.3, 1, -0.4}, l[3] = {1.15, 0.92, 0.97};
  for (int k = 0; k < 5; k++) {
    bs_scene *sc = NULL;
    bs_sim *s = box_sim(&sc, models[k]);
    double Q[9], F[9], D[9] = {l[0], 0, 0, 0, l[1], 0, 0, 0, l[2]};
    rotation(axis, models[k] == BS_MODEL_LINEAR ? 0.0 : 0.4, Q);
    matmul(Q, D, F);
    deform(s, F);
    bs_fields *fl = NULL;
    bs_error err;
    cr_assert_eq(bs_fields_create(s, BS_FIELDS_ALL, &fl, &err), 0, "%s", err.msg);
    bs_fields_compute(fl, s);
    bs_stress_fields want;
    bs_stress_eval(&s->materials[0], F, &want);
    check_cells(fl, &want, s->mesh->n_tets);
    check_vtu(fl, s, &want);
    bs_fields_destroy(&fl);
    bs_sim_destroy(&s);
    bs_scene_destroy(&sc);
  }
}
