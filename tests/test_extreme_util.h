/* test_extreme_util.h — shared helpers of the stability-at-the-extremes tests
 * (tests/test_extreme_*.c, issue 6): run `bigstep run` with overrides into an
 * output folder, then check the run's contract from what it wrote:
 *  - the final state (state.bin, last frame: x and v) and every frames.csv
 *    value are finite;
 *  - the run either converged in every step (exit 0, summary "failed" 0, every
 *    stats.csv reason "converged") or reported its failure (exit 1, summary
 *    "failed" > 0, "N of M steps did not converge" on stderr, and each failed
 *    step's stats.csv reason names why: max_iter, stalled, line_search,
 *    nonfinite). */
#ifndef BS_TEST_EXTREME_UTIL_H
#define BS_TEST_EXTREME_UTIL_H

#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_runfolder.h"
#include "cli_util.h"

typedef struct ext_run {
  int rc;                  /* exit status of bigstep                                  */
  long steps, failed;      /* stats.csv rows and rows with a non-converged reason     */
  long summary_failed;     /* "failed" column of the summary row                      */
  long newton;             /* Newton iterations summed over the steps (stats.csv)     */
  int frames;              /* frames.csv rows after frame 0                           */
  int last_inverted;       /* frames.csv "inverted" of the last frame                 */
  int max_penetrating;     /* max over frames >= 1 of "penetrating"                   */
  int first_clean;         /* first frame >= 1 with no inverted tet (-1: none)        */
  double last_min_detF;    /* frames.csv "min_detF" of the last frame                 */
  double max_grad;         /* largest final |grad E| of a step (stats.csv)            */
  char reason[160];        /* first failure reason, else the last step's reason       */
  char *out;               /* bigstep's stdout + stderr (freed by ext_run_free)       */
} ext_run;

static inline void ext_run_free(ext_run *r) {
  free(r->out);
  r->out = NULL;
}

/* A shell prefix for every bigstep command of these tests. In a sanitizer build
 * (BS_SANITIZE) Gmsh 4.8 itself leaks a few hundred bytes while meshing a surface
 * (meshGFace), which LeakSanitizer turns into a failed exit of bigstep; this
 * suppresses leaks whose stack is in libgmsh only (bigstep's own leaks are still
 * reported). Without a sanitizer the variable is ignored. */
static inline const char *ext_env(void) {
  static const char *const supp = "/tmp/bs_extreme_lsan.supp";
  FILE *f = fopen(supp, "w");
  cr_assert_not_null(f, "cannot write %s", supp);
  fputs("leak:libgmsh.so\n", f);
  fclose(f);
  return "LSAN_OPTIONS=suppressions=/tmp/bs_extreme_lsan.supp:print_suppressions=0 ";
}

/* The reason names of bs_min_reason (solver/bs_minimize.h). */
static inline int ext_reason_known(const char *s) {
  static const char *const names[] = {"converged:", "max_iter:", "stalled:", "line_search:", "nonfinite:",
                                      "steps_done:"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
    if (!strncmp(s, names[i], strlen(names[i]))) return 1;
  return 0;
}

/* stats.csv: frame,step,time,guess,iterations,...,grad_norm,E,reason,inverted,... The
 * reason is the 17th field; it has no comma of its own in the texts of bs_minimize. */
static inline void ext_read_stats(const char *dir, ext_run *r) {
  char path[512], line[2048];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *f = fopen(path, "r");
  cr_assert_not_null(f, "%s missing; bigstep said:\n%s", path, r->out);
  cr_assert_not_null(fgets(line, sizeof line, f));
  cr_assert(strstr(line, ",grad_norm,E,reason,") != NULL, "unexpected stats.csv header %s", line);
  while (fgets(line, sizeof line, f)) {
    char *field[24];
    int n = 0;
    for (char *p = line; n < 24;) {
      field[n++] = p;
      char *c = strchr(p, ',');
      if (!c) break;
      *c = '\0';
      p = c + 1;
    }
    cr_assert(n >= 18, "short stats.csv row in %s", path);
    const char *reason = field[16];
    cr_assert(ext_reason_known(reason), "%s step %ld: no known reason: '%s'", path, r->steps, reason);
    double g = strtod(field[14], NULL);
    if (g > r->max_grad || !isfinite(g)) r->max_grad = g;
    r->newton += strtol(field[4], NULL, 10);
    int conv = !strncmp(reason, "converged:", 10);
    if (!conv) r->failed++;
    if (!conv && r->failed == 1) snprintf(r->reason, sizeof r->reason, "%s", reason);
    if (r->failed == 0) snprintf(r->reason, sizeof r->reason, "%s", reason);
    r->steps++;
  }
  fclose(f);
}

/* frames.csv: every value finite; the last frame's inverted and min_detF; the max
 * of penetrating; the first clean frame. */
static inline void ext_read_frames(const char *dir, ext_run *r) {
  char path[512], line[2048];
  snprintf(path, sizeof path, "%s/frames.csv", dir);
  FILE *f = fopen(path, "r");
  cr_assert_not_null(f, "%s missing", path);
  cr_assert_not_null(fgets(line, sizeof line, f));
  static const char head[] =
      "frame,time,kinetic,elastic,gravity,total,inverted,min_detF,newton,cg,failed,seconds,penetrating,max_depth";
  cr_assert(!strncmp(line, head, sizeof head - 1), "unexpected frames.csv header %s", line);
  r->first_clean = -1;
  while (fgets(line, sizeof line, f)) {
    double v[14];
    int n = 0;
    char *p = line, *end;
    while (n < 14) {
      v[n] = strtod(p, &end);
      cr_assert(end != p, "%s: unreadable value in column %d: %s", path, n, line);
      cr_assert(isfinite(v[n]), "%s: column %d not finite: %s", path, n, line);
      n++;
      if (*end != ',') break;
      p = end + 1;
    }
    cr_assert_eq(n, 14, "%s: %d columns in %s", path, n, line);
    int frame = (int)v[0];
    if (frame == 0) continue;
    r->frames = frame;
    r->last_inverted = (int)v[6];
    r->last_min_detF = v[7];
    if ((int)v[12] > r->max_penetrating) r->max_penetrating = (int)v[12];
    if (r->first_clean < 0 && (int)v[6] == 0) r->first_clean = frame;
  }
  fclose(f);
}

/* state.bin (bs_runfolder.h): whole frames only, and the last frame's x and v
 * are all finite. */
static inline void ext_check_state(const char *dir) {
  bs_state_reader st;
  bs_error err;
  cr_assert_eq(bs_state_open(dir, &st, &err), 0, "%s", err.msg);
  cr_assert(st.frames > 0, "%s/state.bin: no frame", dir);
  long n = 0;
  while (bs_state_next(&st) == 0) n++;
  cr_assert_eq(n, st.frames, "%s/state.bin: %ld frames read of %ld", dir, n, st.frames);
  const size_t m = 6 * (size_t)st.n;
  size_t bad = m;
  for (size_t i = 0; i < m && bad == m; i++)
    if (!isfinite(st.buf[1 + i])) bad = i;
  double val = bad < m ? st.buf[1 + bad] : 0;
  bs_state_close(&st);
  cr_assert_eq(bad, m, "%s/state.bin: last frame value %zu is %g", dir, bad, val);
}

/* The "failed" column of the summary row (method steps s/frame dofs solves failed ...). */
static inline long ext_summary_failed(const char *out) {
  double solves;
  long failed;
  cr_assert_eq(bs_test_summary_row(out, &solves, &failed), 0, "no summary row in:\n%s", out);
  return failed;
}

/* Runs `bigstep run SCENE --quiet ARGS` into a fresh output folder /tmp/bs_extreme_TAG
 * (stats, frames and the states written, no VTU) and checks the contract above. */
static inline ext_run ext_run_scene(const char *scene, const char *args, const char *tag) {
  ext_run r;
  memset(&r, 0, sizeof r);
  char dir[256], cmd[2048];
  snprintf(dir, sizeof dir, "/tmp/bs_extreme_%s", tag);
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  cr_assert_eq(system(cmd), 0);
  snprintf(cmd, sizeof cmd,
           "%s%s run %s --quiet %s --set output.dir=%s --set output.vtu_every=0 --set output.stats=true "
           "--set output.states=true",
           ext_env(), BS_BIGSTEP_EXE, scene, args, dir);
  r.rc = bs_test_run(cmd, &r.out);
  cr_assert(r.rc == 0 || r.rc == 1, "%s: exit %d (crash?):\n%s", tag, r.rc, r.out);
  r.summary_failed = ext_summary_failed(r.out);
  ext_read_stats(dir, &r);
  ext_read_frames(dir, &r);
  ext_check_state(dir);
  cr_assert(r.steps > 0, "%s: no step ran", tag);
  cr_assert_eq(r.summary_failed, r.failed, "%s: summary says %ld failed steps, stats.csv %ld", tag, r.summary_failed,
               r.failed);
  if (r.failed == 0) {
    cr_assert_eq(r.rc, 0, "%s: every step converged but exit %d:\n%s", tag, r.rc, r.out);
  } else {
    char msg[128];
    snprintf(msg, sizeof msg, "%ld of %ld steps did not converge", r.failed, r.steps);
    cr_assert_eq(r.rc, 1, "%s: %ld failed steps but exit %d", tag, r.failed, r.rc);
    cr_assert(strstr(r.out, msg) != NULL, "%s: no '%s' in:\n%s", tag, msg, r.out);
  }
  cr_log_info("%-44s exit %d  steps %3ld  failed %3ld  Newton/step %6.1f  max|gradE| %9.2e  last inverted %4d  "
              "first clean %3d  penetrating %d  [%s]\n",
              tag, r.rc, r.steps, r.failed, (double)r.newton / (double)r.steps, r.max_grad, r.last_inverted,
              r.first_clean, r.max_penetrating, r.reason);
  return r;
}

/* The paper's figures 8 and 9 at test size: SCENE (random_cube or point_cube) on
 * 4x4x4 cells with MODEL at Young's modulus E, for as many frames as the paper's
 * recovery times allow at that stiffness (1e4 Pa: 60 frames; 1e5: 15; stiffer:
 * 3). The run must keep the contract and end with no inverted tet. */
static inline void ext_recover(const char *scene, const char *model, const char *E) {
  double e = strtod(E, NULL);
  int frames = e < 3e4 ? 60 : e < 1e6 ? 15 : 3;
  char path[512], args[512], tag[96];
  snprintf(path, sizeof path, "%s/data/scenes/%s.json", BS_SOURCE_DIR, scene);
  snprintf(args, sizeof args,
           "--frames %d --set bodies.0.box.cells=[4,4,4] --set bodies.0.material.model=%s "
           "--set bodies.0.material.youngs=%s",
           frames, model, E);
  snprintf(tag, sizeof tag, "%s_%s_E%s", scene, model, E);
  ext_run r = ext_run_scene(path, args, tag);
  cr_expect_eq(r.last_inverted, 0, "%s %s E=%s: %d tets still inverted after %d frames (min det F %g) [%s]", scene,
               model, E, r.last_inverted, r.frames, r.last_min_detF, r.reason);
  ext_run_free(&r);
}

#endif
