/* fem_internal.h — what fem.c and fem10.c share (not installed): the
 * quadratic-tet path of bs_fem (bs_fem.h, "Quadratic tets"). */
#ifndef BS_FEM_INTERNAL_H
#define BS_FEM_INTERNAL_H

#include "bs_fem.h"

/* Fills the tet10 part of f (f->mesh, f->n_materials, f->materials set; the
 * rest calloc'ed): order 2, volumes, HRZ masses, load weights, materials,
 * quadrature cache, pattern and slots. On an error f is to be destroyed. */
/* Chunks of nearby tets (chunk_ptr, chunk_tets: position -> tet) and a
 * greedy colouring of them (n_colors, color_ptr, color_chunks) in which no
 * two chunks of a colour share a corner (fem.c; for both orders). */
int bs__fem_color_chunks(bs_fem *f, bs_error *err);
int bs__fem10_create(bs_fem *f, const int32_t *tet_material, bs_error *err);
double bs__fem10_energy(const bs_fem *f, const double *x);
double bs__fem10_gradient(const bs_fem *f, const double *x, double *g);
/* As fem.c's hessian_all: project_psd, or per tet by vmax; scale s, or
 * material_scale[m] (tets of scale 0 skipped). */
void bs__fem10_hessian(const bs_fem *f, const double *x, int project_psd, const double *vmax, double s,
                       const double *material_scale, bs_bsr *H);
int32_t bs__fem10_count_inverted(const bs_fem *f, const double *x, double *min_detF);

#endif
