/* scene_full.h — a scene that holds every section of the schema table (and
 * every key of it that can stand beside the others: not time.dt, which
 * excludes steps_per_frame, nor solver.cg_sigma_scale, which a number
 * cg_sigma excludes; not the scripts' fixed and velocity, which exclude
 * keyframes), for the tests that
 * walk the table against the loader; and the instance path of a table
 * section in it ("bodies[].scripted[]" -> "bodies.0.scripted.0"). */
#ifndef BS_TEST_SCENE_FULL_H
#define BS_TEST_SCENE_FULL_H

#include <stdio.h>
#include <string.h>

static const char *const bs_test_full_scene =
    "{\"$schema\": \"../scene.schema.json\", \"description\": \"every section\",\n"
    " \"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"linear\": \"cg\", \"tolerance\": 1e-3, \"rtol\": 0, \"load_rtol\": 0, \"max_iterations\": 500,\n"
    "   \"newton_max_iterations\": 40,\n"
    "   \"cg_max_iterations\": 0, \"newton_k\": 1, \"mode\": \"dynamic\", \"backend\": \"serial\", \"load_steps\": 1,\n"
    "   \"project_hessian\": \"none\", \"cg_sigma\": \"auto\", \"cg_forcing\": \"paper\",\n"
    "   \"cg_downhill\": true, \"contact_hessian\": \"adaptive\", \"cg_precision\": \"double\", \"amg_matrix\": \"rest\", \"amg_rebuild_factor\": 3,\n"
    "   \"amg_rebuild_every\": 0},\n"
    " \"gravity\": [0, -9.8, 0], \"drag\": 0,\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]}, \"mesh_size\": 0,\n"
    "   \"min_dihedral\": 10,\n"
    "   \"refine\": 0, \"close_holes\": false, \"reorder\": \"none\", \"element\": \"tet4\", \"scale\": [1, 1, 1], \"rotate\": [0, 0, 0],\n"
    "   \"translate\": [0, 0, 0],\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000,\n"
    "                \"rayleigh\": 0},\n"
    "   \"materials\": {\"body\": {\"youngs\": 2e5, \"poisson\": 0.3, \"density\": 1000}},\n"
    "   \"velocity\": [0, 0, 0], \"angular_velocity\": [0, 0, 0],\n"
    "   \"initial_state\": {\"type\": \"random\", \"lo\": [0, 0, 0], \"hi\": [1, 1, 1], \"point\": [0, 0, 0],\n"
    "                     \"seed\": 3},\n"
    "   \"scripted\": [{\"group\": \"ymin\", \"keyframes\": [{\"t\": 0, \"offset\": [0, 0, 0]},\n"
    "                                                 {\"t\": 1, \"offset\": [0, 0.1, 0]}]}]}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": -1, \"center\": [0, 0, 0],\n"
    "   \"radius\": 0.5, \"half_extents\": [0.5, 0.5, 0.5], \"axis\": [0, 1, 0], \"half_height\": 0.5,\n"
    "   \"major\": 1, \"minor\": 0.25, \"inside_out\": false, \"file\": \"\", \"grid_h\": 0,\n"
    "   \"collision\": \"constraint\", \"stiffness\": 1e6, \"friction\": 0, \"velocity\": [0, 0, 0],\n"
    "   \"angular_velocity\": [0, 0, 0], \"keyframes\": [{\"t\": 0, \"translate\": [0, 0, 0], \"rotate\": [0, 0, 0]}]}],\n"
    " \"self_collision\": {\"stiffness\": 1e5, \"friction\": 0, \"model\": \"penalty\"},\n"
    " \"contact\": {\"dhat\": 0.001, \"kappa\": 1e6},\n"
    " \"qoi\": [{\"name\": \"q\", \"quantity\": \"energy\", \"component\": \"magnitude\", \"reduce\": \"max\", \"body\": 0,\n"
    "   \"group\": \"ymin\", \"obstacle\": 0, \"term\": \"elastic\"}],\n"
    " \"output\": {\"dir\": \"\", \"vtu_every\": 1, \"stats\": true, \"states\": false}}\n";

/* The path in the full scene of an object of the table's section: "[]"
 * becomes ".0" ("" for the top level). */
static inline void bs_test_section_path(const char *section, char *out, size_t n) {
  size_t k = 0;
  for (const char *p = section; *p && k + 3 < n; p++) {
    if (p[0] == '[' && p[1] == ']') {
      out[k++] = '.';
      out[k++] = '0';
      p++;
    } else {
      out[k++] = *p;
    }
  }
  out[k] = '\0';
}

/* section path + "." + key (just the key at the top level). */
static inline void bs_test_key_path(const char *section, const char *key, char *out, size_t n) {
  bs_test_section_path(section, out, n);
  if (out[0]) strncat(out, ".", n - strlen(out) - 1);
  strncat(out, key, n - strlen(out) - 1);
}

#endif
