/* `bigstep levelset SURFACE OUT.vti` writes VTK image data (point data
 * "phi") holding the same grid as OUT.bsls: the same nodes, origin, spacing
 * and values bit for bit; OUT.bsls stays the grid file scenes load. */
#define _GNU_SOURCE /* mkdtemp */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_levelset.h"
#include "cli_util.h"

static char *slurp(const char *path) {
  FILE *fp = fopen(path, "rb");
  cr_assert_not_null(fp, "cannot read %s", path);
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  cr_assert_eq(fread(s, 1, (size_t)n, fp), (size_t)n);
  s[n] = 0;
  fclose(fp);
  return s;
}

static void numbers(const char *s, const char *attr, double *out, int n) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", attr);
  const char *p = strstr(s, key);
  cr_assert_not_null(p, "no %s", attr);
  p += strlen(key);
  for (int i = 0; i < n; i++) out[i] = strtod(p, (char **)&p);
}

Test(levelset_vti, vti_holds_the_grid_of_the_bsls) {
  char dir[] = "/tmp/bs_test_lsvti_XXXXXX", cmd[1024], vti[256], bsls[256];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(vti, sizeof vti, "%s/cube.vti", dir);
  snprintf(bsls, sizeof bsls, "%s/cube.bsls", dir);
  char *out = NULL;
  snprintf(cmd, sizeof cmd, "%s levelset box:2 %s --h 0.1", BS_BIGSTEP_EXE, vti);
  cr_assert_eq(bs_test_run(cmd, &out), 0, "%s", out);
  free(out);
  snprintf(cmd, sizeof cmd, "%s levelset box:2 %s --h 0.1", BS_BIGSTEP_EXE, bsls);
  cr_assert_eq(bs_test_run(cmd, &out), 0, "%s", out);
  free(out);
  bs_levelset *ls = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_load(bsls, &ls, &err), 0, "%s", err.msg);
  int32_t n[3];
  double origin[3], h;
  const double *values = bs_levelset_grid_values(ls, n, origin, &h);
  char *s = slurp(vti);
  cr_assert_not_null(strstr(s, "<VTKFile type=\"ImageData\""));
  cr_assert_not_null(strstr(s, "Name=\"phi\""));
  double ext[6], o[3], sp[3];
  numbers(s, "WholeExtent", ext, 6);
  numbers(s, "Origin", o, 3);
  numbers(s, "Spacing", sp, 3);
  for (int k = 0; k < 3; k++) {
    cr_assert_eq(ext[2 * k + 1], n[k] - 1);
    cr_assert_eq(o[k], origin[k]);
    cr_assert_eq(sp[k], h);
  }
  const char *u = strchr(strstr(s, "<AppendedData"), '_');
  uint64_t bytes;
  memcpy(&bytes, u + 1, 8);
  const size_t N = (size_t)n[0] * n[1] * n[2];
  cr_assert_eq(bytes, 8 * N);
  cr_assert_eq(memcmp(u + 9, values, 8 * N), 0, "the same values, bit for bit");
  free(s);
  bs_levelset_destroy(&ls);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_assert_eq(system(cmd), 0);
}
