/* fields.c — the output fields of a simulation's state (bs_fields.h): the
 * buffers, allocated once; the fields that do not change (scripted flags,
 * body ids, material indices) filled at creation; the per-tet stress and
 * strain measures of physics/bs_stress.h at each call; the list of arrays
 * handed to the VTU writer. */
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_fields.h"
#include "bs_forces.h"
#include "bs_stress.h"
#include "bs_tet10.h"

#define HAS(f, F) (((f)->set & BS_FIELD_BIT(F)) != 0)

/* The fields bs_stress_eval gives (an SVD per tet): computed together. */
#define STRESS_SET                                                                                               \
  (BS_FIELD_BIT(BS_FIELD_FIRST_PIOLA) | BS_FIELD_BIT(BS_FIELD_CAUCHY) | BS_FIELD_BIT(BS_FIELD_VON_MISES) |      \
   BS_FIELD_BIT(BS_FIELD_GREEN_STRAIN) | BS_FIELD_BIT(BS_FIELD_STRETCHES) | BS_FIELD_BIT(BS_FIELD_ENERGY_DENSITY))

void bs_fields_destroy(bs_fields **pf) {
  if (!pf || !*pf) return;
  bs_fields *f = *pf;
  free(f->scripted);
  free(f->point_body);
  free(f->cell_body);
  free(f->material);
  free(f->J);
  free(f->inverted);
  free(f->P);
  free(f->cauchy);
  free(f->green);
  free(f->von_mises);
  free(f->psi);
  free(f->stretch);
  free(f->f_elastic);
  free(f->f_contact);
  free(f->friction);
  free(f);
  *pf = NULL;
}

/* n zeroed elements of `size` bytes when needed, else NULL. */
static void *alloc_if(int need, size_t n, size_t size, int *oom) {
  if (!need) return NULL;
  void *p = calloc(n ? n : 1, size);
  if (!p) *oom = 1;
  return p;
}

static int alloc_buffers(bs_fields *f, bs_error *err) {
  const size_t nv = (size_t)f->n_vertices, nt = (size_t)f->n_tets;
  const int body = HAS(f, BS_FIELD_BODY);
  int oom = 0;
  f->scripted = alloc_if(HAS(f, BS_FIELD_SCRIPTED), nv, 1, &oom);
  f->point_body = alloc_if(body, nv, sizeof(int32_t), &oom);
  f->cell_body = alloc_if(body || HAS(f, BS_FIELD_MATERIAL), nt, sizeof(int32_t), &oom);
  f->material = alloc_if(HAS(f, BS_FIELD_MATERIAL), nt, sizeof(int32_t), &oom);
  f->J = alloc_if(HAS(f, BS_FIELD_DETF) || HAS(f, BS_FIELD_INVERTED), nt, sizeof(double), &oom);
  f->inverted = alloc_if(HAS(f, BS_FIELD_INVERTED), nt, 1, &oom);
  f->P = alloc_if(HAS(f, BS_FIELD_FIRST_PIOLA), 9 * nt, sizeof(double), &oom);
  f->cauchy = alloc_if(HAS(f, BS_FIELD_CAUCHY), 9 * nt, sizeof(double), &oom);
  f->green = alloc_if(HAS(f, BS_FIELD_GREEN_STRAIN), 9 * nt, sizeof(double), &oom);
  f->von_mises = alloc_if(HAS(f, BS_FIELD_VON_MISES), nt, sizeof(double), &oom);
  f->psi = alloc_if(HAS(f, BS_FIELD_ENERGY_DENSITY), nt, sizeof(double), &oom);
  f->stretch = alloc_if(HAS(f, BS_FIELD_STRETCHES), 3 * nt, sizeof(double), &oom);
  f->f_elastic = alloc_if(HAS(f, BS_FIELD_ELASTIC_FORCE), 3 * nv, sizeof(double), &oom);
  f->f_contact = alloc_if(HAS(f, BS_FIELD_CONTACT_FORCE), 3 * nv, sizeof(double), &oom);
  f->friction = alloc_if(HAS(f, BS_FIELD_FRICTION_IMPULSE), 3 * nv, sizeof(double), &oom);
  return oom ? bs_error_set(err, BS_ENOMEM, "out of memory for the output fields (%d tets)", f->n_tets) : 0;
}

/* The body of vertex v: the b with vertex_offset[b] <= v < vertex_offset[b + 1]. */
static int32_t body_of(const bs_sim *s, int32_t v) {
  int lo = 0, hi = s->n_bodies - 1;
  while (lo < hi) {
    int mid = (lo + hi + 1) / 2;
    if (s->vertex_offset[mid] <= v) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

/* Body b's first material in s->materials (bodies' materials in body order). */
static int first_material(const bs_sim *s, int b) {
  int m = 0;
  for (int i = 0; i < b; i++) m += s->scene->bodies[i].n_materials;
  return m;
}

/* scripted, body and material: fixed for the run. */
static void fill_static(bs_fields *f, const bs_sim *s) {
  for (int32_t v = 0; v < f->n_vertices; v++) {
    if (f->scripted) f->scripted[v] = !s->mask[v];
    if (f->point_body) f->point_body[v] = body_of(s, v);
  }
  if (!f->cell_body) return;
  for (int32_t t = 0; t < f->n_tets; t++) {
    f->cell_body[t] = body_of(s, s->mesh->tets[4 * (size_t)t]);
    if (f->material) f->material[t] = s->tet_material[t] - first_material(s, f->cell_body[t]);
  }
}

static void add_array(bs_vtu_data *list, int *n, const char *name, bs_vtu_type type, int ncomp, const void *data) {
  if (data) list[(*n)++] = (bs_vtu_data){name, type, ncomp, data};
}

/* The VTU's arrays beyond displacement and velocity, in bs_field order. */
static void list_arrays(bs_fields *f) {
  int np = 0, nc = 0;
  add_array(f->point_data, &np, "scripted", BS_VTU_UINT8, 1, f->scripted);
  add_array(f->point_data, &np, "body", BS_VTU_INT32, 1, f->point_body);
  add_array(f->point_data, &np, "elastic_force", BS_VTU_FLOAT64, 3, f->f_elastic);
  add_array(f->point_data, &np, "contact_force", BS_VTU_FLOAT64, 3, f->f_contact);
  add_array(f->point_data, &np, "friction_impulse", BS_VTU_FLOAT64, 3, f->friction);
  add_array(f->cell_data, &nc, "body", BS_VTU_INT32, 1, HAS(f, BS_FIELD_BODY) ? f->cell_body : NULL);
  add_array(f->cell_data, &nc, "material", BS_VTU_INT32, 1, f->material);
  add_array(f->cell_data, &nc, "detF", BS_VTU_FLOAT64, 1, HAS(f, BS_FIELD_DETF) ? f->J : NULL);
  add_array(f->cell_data, &nc, "inverted", BS_VTU_UINT8, 1, f->inverted);
  add_array(f->cell_data, &nc, "first_piola", BS_VTU_FLOAT64, 9, f->P);
  add_array(f->cell_data, &nc, "cauchy", BS_VTU_FLOAT64, 9, f->cauchy);
  add_array(f->cell_data, &nc, "von_mises", BS_VTU_FLOAT64, 1, f->von_mises);
  add_array(f->cell_data, &nc, "green_strain", BS_VTU_FLOAT64, 9, f->green);
  add_array(f->cell_data, &nc, "stretches", BS_VTU_FLOAT64, 3, f->stretch);
  add_array(f->cell_data, &nc, "energy_density", BS_VTU_FLOAT64, 1, f->psi);
  f->n_point_data = np;
  f->n_cell_data = nc;
}

int bs_fields_create(const bs_sim *s, uint32_t set, bs_fields **out, bs_error *err) {
  *out = NULL;
  if (set & ~BS_FIELDS_ALL)
    return bs_error_set(err, BS_EINPUT, "output.fields: unknown field bits 0x%x", (unsigned)(set & ~BS_FIELDS_ALL));
  bs_fields *f = calloc(1, sizeof *f);
  if (!f) return bs_error_set(err, BS_ENOMEM, "out of memory");
  f->set = set | BS_FIELD_BIT(BS_FIELD_DISPLACEMENT);
  f->n_vertices = s->mesh->n_vertices;
  f->n_tets = s->mesh->n_tets;
  int st = alloc_buffers(f, err);
  if (st) {
    bs_fields_destroy(&f);
    return st;
  }
  fill_static(f, s);
  list_arrays(f);
  *out = f;
  return 0;
}

/* The stress fields of a quadratic tet t: det F and every measure averaged
 * over its quadrature points, weighted by w_q det J_q (the plain mean on a
 * straight tet's 4-point rule); inverted when det F <= 0 at some point. */
static void tet10_fields(bs_fields *f, const bs_sim *s, int32_t t, int stress) {
  const bs_fem *fem = s->fem;
  bs_tet10_rest r;
  double xt[30], J = 0, W = 0, F[9];
  int inv = 0;
  bs_fem_tet10_rest(fem, t, &r);
  bs_fem_tet10_gather(fem, s->x, t, xt);
  bs_stress_fields q[BS_TET10_MAX_POINTS], a;
  memset(&a, 0, sizeof a);
  if (stress) bs_tet10_stress(&s->materials[s->tet_material[t]], &r, xt, q);
  for (int p = 0; p < r.n_points; p++) {
    const double w = r.wdetJ[p];
    bs_tet10_F(&r, p, xt, F);
    const double Jp = bs_det3(F);
    inv |= !(Jp > 0.0);
    J += w * Jp, W += w;
    if (!stress) continue;
    for (int i = 0; i < 9; i++) a.P[i] += w * q[p].P[i], a.cauchy[i] += w * q[p].cauchy[i], a.green[i] += w * q[p].green[i];
    for (int i = 0; i < 3; i++) a.stretch[i] += w * q[p].stretch[i];
    a.von_mises += w * q[p].von_mises, a.psi += w * q[p].psi;
  }
  if (f->J) f->J[t] = J / W;
  if (f->inverted) f->inverted[t] = (uint8_t)inv;
  if (!stress) return;
  for (int i = 0; i < 9; i++) a.P[i] /= W, a.cauchy[i] /= W, a.green[i] /= W;
  for (int i = 0; i < 3; i++) a.stretch[i] /= W;
  if (f->P) memcpy(f->P + 9 * (size_t)t, a.P, sizeof a.P);
  if (f->cauchy) memcpy(f->cauchy + 9 * (size_t)t, a.cauchy, sizeof a.cauchy);
  if (f->green) memcpy(f->green + 9 * (size_t)t, a.green, sizeof a.green);
  if (f->stretch) memcpy(f->stretch + 3 * (size_t)t, a.stretch, sizeof a.stretch);
  if (f->von_mises) f->von_mises[t] = a.von_mises / W;
  if (f->psi) f->psi[t] = a.psi / W;
}

/* Tet t's measures into the buffers the set has. */
static void tet_fields(bs_fields *f, const bs_sim *s, int32_t t, int stress) {
  const bs_fem *fem = s->fem;
  if (fem->order == 2) {
    tet10_fields(f, s, t, stress);
    return;
  }
  double xt[12], F[9];
  bs_fem_gather(fem, s->x, t, xt);
  bs_tet_F(xt, fem->Dm_inv + 9 * (size_t)fem->tet_pos[t], F);
  const double J = bs_det3(F);
  if (f->J) f->J[t] = J;
  if (f->inverted) f->inverted[t] = !(J > 0.0);
  if (!stress) return;
  bs_stress_fields sf;
  bs_stress_eval(&s->materials[s->tet_material[t]], F, &sf);
  if (f->P) memcpy(f->P + 9 * (size_t)t, sf.P, sizeof sf.P);
  if (f->cauchy) memcpy(f->cauchy + 9 * (size_t)t, sf.cauchy, sizeof sf.cauchy);
  if (f->green) memcpy(f->green + 9 * (size_t)t, sf.green, sizeof sf.green);
  if (f->stretch) memcpy(f->stretch + 3 * (size_t)t, sf.stretch, sizeof sf.stretch);
  if (f->von_mises) f->von_mises[t] = sf.von_mises;
  if (f->psi) f->psi[t] = sf.psi;
}

void bs_fields_compute(bs_fields *f, const bs_sim *s) {
  const int stress = (f->set & STRESS_SET) != 0;
  if (!stress && !f->J) return;
#pragma omp parallel for schedule(static)
  for (int32_t t = 0; t < f->n_tets; t++) tet_fields(f, s, t, stress);
}

int bs_fields_write_vtu(bs_fields *f, const bs_sim *s, const char *path, bs_error *err) {
  bs_fields_compute(f, s);
  int st = f->f_elastic ? bs_sim_force_elastic(s, f->f_elastic, err) : 0;
  if (!st && f->f_contact) st = bs_sim_force_contact(s, -1, f->f_contact, err);
  if (st) return st;
  if (f->friction && s->friction_impulse)
    memcpy(f->friction, s->friction_impulse, sizeof(double) * 3 * (size_t)f->n_vertices);
  bs_vtu_fields v = {.x = s->x,
                     .velocity = HAS(f, BS_FIELD_VELOCITY) ? s->v : NULL,
                     .custom_cells = 1,
                     .n_point_data = f->n_point_data,
                     .point_data = f->point_data,
                     .n_cell_data = f->n_cell_data,
                     .cell_data = f->cell_data,
                     .compress = s->scene->out_compress};
  return bs_mesh_write_vtu(s->mesh, &v, path, err);
}
