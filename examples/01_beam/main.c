/* Example 1: a clamped beam sagging under gravity, built in C without a scene
 * file, solved with the optimization integrator, and its tip deflection set
 * beside beam theory.
 *
 * Read it top to bottom; README.md beside it shows what it prints.
 *
 * The beam: 1 m long, 0.1 m x 0.1 m in section, steel-soft (E = 1e8 Pa,
 * nu = 0.3, rho = 1000 kg/m^3), clamped at x = 0, loaded by its own weight.
 * We solve the static problem (the minimum of the elastic energy plus the
 * gravity potential, with the clamped vertices fixed) on three meshes, each
 * the uniform refinement of the last, and compare the tip deflection with
 * Timoshenko beam theory, which adds shear to Euler-Bernoulli's q L^4/(8 E I).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <bigstep/bigstep.h>

/* Every bigstep call that can fail returns a status and fills a bs_error with
 * a message that names what is wrong (a key, a group, a vertex). */
#define CHECK(call)                                   \
  do {                                                \
    if ((call) != 0) {                                \
      fprintf(stderr, "beam: %s\n", err.msg);         \
      exit(1);                                        \
    }                                                 \
  } while (0)

/* Step 1: the scene, in C. bs_scene_create gives every default of the JSON
 * schema (docs/scene-keys.md); we add one body and say what differs. */
static bs_scene *beam_scene(int refine) {
  bs_error err;
  bs_scene *sc = NULL;
  bs_scene_body *b = NULL;
  bs_scene_script *clamp = NULL;
  CHECK(bs_scene_create(&sc, &err));
  CHECK(bs_scene_add_body(sc, "box", &b, &err));
  /* A structured box [0, 1] x [0, 0.1] x [0, 0.1] m of 20 x 2 x 2 cells, each
     cell six tets; its faces are the groups xmin, xmax, ymin, ... */
  b->box_cells[0] = 20;
  b->box_cells[1] = b->box_cells[2] = 2;
  b->box_size[0] = 1.0;
  b->box_size[1] = b->box_size[2] = 0.1;
  b->refine = refine;
  b->materials[0] = (bs_scene_material){.model = BS_MODEL_FIXED_COROTATED, .youngs = 1e8, .poisson = 0.3,
                                        .density = 1000};
  /* The clamp: the vertices of the group xmin never move. */
  CHECK(bs_scene_body_add_script(b, "xmin", BS_SCRIPT_FIXED, &clamp, &err));
  /* Statics with the optimization integrator's minimizer; a sparse Cholesky
     factorization solves each Newton system exactly. */
  sc->mode = BS_MODE_STATIC;
  sc->solver.method = BS_METHOD_OPTIMIZATION;
  sc->solver.min.linear = BS_LIN_CHOLMOD;
  sc->solver.min.tol = 1e-6; /* N, on the norm of the energy's gradient */
  sc->gravity[1] = -9.8;     /* the default already; said here for the reader */
  /* bs_scene_validate derives dt and checks every value as the JSON loader
     would, naming the key at fault. */
  CHECK(bs_scene_validate(sc, &err));
  return sc;
}

/* Step 2: the tip deflection, the mean y displacement of the vertices at
 * x = 1 m. The simulation owns the state: s->x0 (rest, 3 per vertex) and s->x. */
static double tip_deflection(const bs_sim *s) {
  double sum = 0;
  int n = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    if (fabs(s->x0[3 * v] - 1.0) < 1e-9) {
      sum += s->x[3 * v + 1] - s->x0[3 * v + 1];
      n++;
    }
  return sum / n;
}

int main(void) {
  bs_error err;
  double u[3];
  printf("level   dofs     tip deflection (mm)   Newton iterations\n");
  for (int r = 0; r < 3; r++) {
    /* Step 3: scene -> simulation -> static solve. bs_sim_create reads or
       builds the mesh, makes the terms the scene asks for (here gravity and
       elasticity), the clamped set and the integrator. bs_sim_statics runs
       the minimizer; a solve that did not converge is not an error but is
       counted in fs.failed, with the reason in the step's statistics. */
    bs_scene *sc = beam_scene(r);
    bs_sim *s = NULL;
    bs_frame_stats fs;
    CHECK(bs_sim_create(sc, &s, &err));
    CHECK(bs_sim_statics(s, &fs, &err));
    if (fs.failed) {
      fprintf(stderr, "beam: level %d did not converge: %s\n", r, fs.steps[0].st.min.reason_text);
      return 1;
    }
    u[r] = tip_deflection(s);
    printf("%5d %7ld %18.4f %14ld\n", r, bs_sim_dofs(s), 1e3 * u[r], fs.iterations);
    /* Step 4: who owns what. The simulation borrows the scene, so it goes
       first; destroy functions take the pointer's address and null it. */
    bs_sim_destroy(&s);
    bs_scene_destroy(&sc);
  }

  /* Step 5: the limit h -> 0 by Richardson extrapolation with the observed
     order p = log2(d01 / d12) of the successive differences. */
  double d01 = u[0] - u[1], d12 = u[1] - u[2];
  double p = log2(d01 / d12), u_inf = u[2] - d12 / (pow(2.0, p) - 1);

  /* Step 6: Timoshenko beam theory for a cantilever under a uniform load q
     (N/m): q L^4 / (8 E I) + q L^2 / (2 kappa G A), with the rectangle's
     shear coefficient kappa = 10 (1 + nu) / (12 + 11 nu). */
  const double E = 1e8, nu = 0.3, rho = 1000, g = 9.8, L = 1, a = 0.1;
  const double A = a * a, I = a * a * a * a / 12, q = rho * g * A, G = E / (2 * (1 + nu));
  const double kappa = 10 * (1 + nu) / (12 + 11 * nu);
  const double theory = -(q * pow(L, 4) / (8 * E * I) + q * L * L / (2 * kappa * G * A));
  /* The coarse beam is pre-asymptotic (P1 tets lock in bending), so the
     observed order is below P1's asymptotic 2: we give the limit with both. */
  const double u_inf2 = u[2] - d12 / 3;
  printf("Timoshenko beam theory: %.4f mm\n", 1e3 * theory);
  printf("Richardson limit with the observed order %.2f: %.4f mm (%.1f%% from theory)\n", p, 1e3 * u_inf,
         100 * fabs(u_inf / theory - 1));
  printf("Richardson limit with the asymptotic order 2: %.4f mm (%.1f%% from theory)\n", 1e3 * u_inf2,
         100 * fabs(u_inf2 / theory - 1));
  return 0;
}
