/* bs_field_names.h — the fields a run can write into its VTU frames, by
 * name: the choices of a scene's output.fields, parsed into a set of bits.
 * What each field holds and how it is computed: bs_fields.h (sim/).
 *
 * Fields (the name is the key in output.fields and the array's name in the
 * VTU; units SI):
 *   point data  displacement    3   m    x - rest (always written: `bigstep
 *                                        check` recovers the rest shape from it)
 *               velocity        3   m/s
 *               scripted        1   -    UInt8: 1 where a scripted group sets
 *                                        the position (fixed or moving), else 0
 *               body            1   -    Int32: the body's index in `bodies`
 *                                        (also written as cell data)
 *               elastic_force   3   N    -dPhi_e/dx (bs_forces.h)
 *               contact_force   3   N    obstacles' and self-collision's force
 *               friction_impulse 3  N s  m dv of Coulomb friction (applied
 *                                        after the solve) in the last step;
 *                                        zero when the scene has no friction
 *   cell data   material        1   -    Int32: the material's index within
 *                                        its body: 0 the body's "material",
 *                                        i >= 1 its "materials" entry i - 1
 *                                        (with "body", names the scene material)
 *               detF            1   -    J = det F (current over rest volume)
 *               inverted        1   -    UInt8: 1 where J <= 0 (or NaN)
 *               first_piola     9   Pa   P = dPsi/dF (row-major, P[3 r + c])
 *               cauchy          9   Pa   sigma = sym(P F^T) / J
 *               von_mises       1   Pa   of sigma
 *               green_strain    9   -    E = (F^T F - I) / 2
 *               stretches       3   -    principal stretches (singular values
 *                                        of F, descending; the last negative in
 *                                        an inverted tet)
 *               energy_density  1   Pa   Psi(F), J/m^3 of rest volume
 * Per-tet quantities are those of physics/bs_stress.h (constant over a P1
 * tet). The default set (BS_FIELDS_DEFAULT) is every field but first_piola.
 *
 *
 * Status: 0, or BS_EINPUT for an unknown name (the message lists the allowed
 * names).
 *
 * Example:
 *     uint32_t set;
 *     const char *names[] = {"von_mises", "detF"};
 *     if (bs_fields_parse_names(2, names, &set, &err)) ...
 *     if (set & BS_FIELD_BIT(BS_FIELD_DETF)) ...
 */
#ifndef BS_FIELD_NAMES_H
#define BS_FIELD_NAMES_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum bs_field {
  BS_FIELD_DISPLACEMENT = 0,
  BS_FIELD_VELOCITY,
  BS_FIELD_SCRIPTED,
  BS_FIELD_BODY,
  BS_FIELD_MATERIAL,
  BS_FIELD_DETF,
  BS_FIELD_INVERTED,
  BS_FIELD_FIRST_PIOLA,
  BS_FIELD_CAUCHY,
  BS_FIELD_VON_MISES,
  BS_FIELD_GREEN_STRAIN,
  BS_FIELD_STRETCHES,
  BS_FIELD_ENERGY_DENSITY,
  BS_FIELD_ELASTIC_FORCE,      /* point: -dPhi_e/dx (N), bs_forces.h          */
  BS_FIELD_CONTACT_FORCE,      /* point: obstacles and self-collision (N)     */
  BS_FIELD_FRICTION_IMPULSE,   /* point: friction of the last step (N s)      */
  BS_FIELD_COUNT
} bs_field;

/* A set of fields: bit f for field f. */
#define BS_FIELD_BIT(f) (1u << (f))
#define BS_FIELDS_ALL ((1u << BS_FIELD_COUNT) - 1u)
#define BS_FIELDS_DEFAULT (BS_FIELDS_ALL & ~BS_FIELD_BIT(BS_FIELD_FIRST_PIOLA))

/* The name of a field ("displacement", ...); "unknown" outside the enum. */
const char *bs_field_name(bs_field f);

/* The field named `name`: 0, or BS_EINPUT "unknown field "x" (allowed: ...)". */
int bs_field_parse(const char *name, bs_field *out, bs_error *err);

/* A set from n names (each parsed as above; repeats are fine). On an unknown
 * name the message names its index: "output.fields.2: unknown field ...". */
int bs_fields_parse_names(int n, const char *const *names, uint32_t *set, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
