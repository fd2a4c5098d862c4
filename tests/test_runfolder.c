/* The run folder (runfolder/bs_runfolder.h) written and read back by the library:
 * state.bin holds the simulation's x and v bit for bit, frames.csv a row per
 * frame at its time, summary.txt the solves/step and failed count that
 * bs_summary_format wrote; a state.bin that is not one (wrong magic, unknown
 * version, truncated) is refused naming the file. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "bs_vtu_read.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "scene_fixture.h"

#define FRAMES 3
#define FPS 24.0

static char dir[] = "/tmp/bs_runfolder_XXXXXX";

static void setup(void) { cr_assert_not_null(mkdtemp(dir)); }
static void teardown(void) {
  char cmd[256];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}

/* A 2^3-cell box clamped at x = 0, thrown up and sagging for FRAMES frames, with stats and states. */
static bs_scene *small_box(void) {
  bs_scene *sc = bs_test_box_scene(FRAMES, FPS, 1);
  bs_scene_body *b = &sc->bodies[0];
  bs_error err;
  b->velocity[1] = 0.5;
  bs_scene_script *clamp = NULL; /* clamped: the steps take Newton iterations */
  cr_assert_eq(bs_scene_body_add_script(b, "xmin", BS_SCRIPT_FIXED, &clamp, &err), 0, "%s", err.msg);
  sc->states = 1;
  sc->stats_csv = 1;
  sc->vtu_every = 0;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  return sc;
}

/* state.bin: FRAMES + 1 frames, frame 0 the rest state, the last one s->x, s->v */
static void check_state(const char *out, const bs_sim *s) {
  const int32_t n = s->mesh->n_vertices;
  const size_t bytes = 3 * sizeof(double) * (size_t)n;
  bs_state_reader r;
  bs_error err;
  cr_assert_eq(bs_state_open(out, &r, &err), 0, "%s", err.msg);
  cr_expect_eq(r.version, BS_STATE_VERSION);
  cr_expect_eq(r.n, n);
  cr_assert_eq(r.frames, FRAMES + 1);
  long k = 0;
  int last_ok = 0;
  while (bs_state_next(&r) == 0) {
    cr_expect_eq(r.time, k / FPS, "frame %ld at %.17g", k, r.time);
    if (k == 0) cr_expect_eq(memcmp(r.x, s->x0, bytes), 0, "frame 0 is not the rest state");
    last_ok = memcmp(r.x, s->x, bytes) == 0 && memcmp(r.v, s->v, bytes) == 0;
    k++;
  }
  bs_state_close(&r);
  cr_expect_eq(k, FRAMES + 1, "%ld frames read", k);
  cr_expect(last_ok, "the last frame's x, v are not s->x, s->v bit for bit");
  cr_expect_neq(memcmp(s->x, s->x0, bytes), 0, "nothing moved");
}

/* frames.csv: a row per frame at its time, the run's sums */
static void check_frames(const char *out, const bs_run_totals *T) {
  bs_frames_table t;
  bs_error err;
  cr_assert_eq(bs_frames_csv_read(out, &t, &err), 0, "%s", err.msg);
  cr_expect_eq(t.n, FRAMES + 1);
  for (int f = 0; f < t.n && f <= FRAMES; f++)
    cr_expect(fabs(t.time[f] - f / FPS) <= 1e-9 * (f / FPS), "row %d: time %.17g", f, t.time[f]);
  cr_expect_eq(t.newton, T->iterations);
  cr_expect_eq(t.failed, T->failed);
  cr_expect_eq(t.inverted_max, 0);
  cr_expect(t.has_depth);
  bs_frames_table_free(&t);
  cr_expect_eq(bs_frames_csv_lines(out), FRAMES + 2);
}

/* u formatted into out/summary.txt and read back into *back. */
static void write_and_read(const char *out, const bs_summary *u, bs_summary *back) {
  char text[2048], p[600];
  bs_error err;
  bs_summary_format(u, text, sizeof text);
  snprintf(p, sizeof p, "%s/summary.txt", out);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(text, f);
  fclose(f);
  cr_assert_eq(bs_summary_read(out, back, &err), 0, "%s", err.msg);
}

/* summary.txt: what bs_summary_format wrote (u, made with 1.5 s of wall time),
 * and a failed count and solves/step of another summary round-trip too */
static void check_summary(const char *out, const bs_sim *s, const bs_run_totals *T, bs_summary *u) {
  bs_summary back;
  bs_error err;
  cr_assert_eq(bs_summary_read(out, &back, &err), 0, "%s", err.msg);
  cr_expect_str_eq(back.method, "optimization");
  cr_expect_eq(back.steps_per_frame, 1);
  cr_expect_eq(back.dofs, bs_sim_dofs(s));
  cr_expect_eq(back.failed, 0);
  cr_expect(fabs(back.solves_per_step - (double)T->iterations / T->steps) <= 0.005, "solves/step %g, not %g",
            back.solves_per_step, (double)T->iterations / T->steps);
  cr_expect(fabs(back.s_per_frame - 1.5 / FRAMES) <= 5e-5, "s/frame %g", back.s_per_frame);
  cr_expect(isfinite(back.peak_mib) && back.peak_mib > 0, "peak %g MiB", back.peak_mib);
  u->failed = 17;
  u->solves_per_step = 4.25;
  write_and_read(out, u, &back);
  cr_expect_eq(back.failed, 17);
  cr_expect_eq(back.solves_per_step, 4.25);
}

Test(runfolder, round_trip, .init = setup, .fini = teardown) {
  bs_scene *sc = small_box();
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_run_totals T;
  bs_error err;
  char out[512];
  snprintf(out, sizeof out, "%s/run", dir);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_open(out, s, &(bs_runfolder_opts){.replace = 1}, &rf, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_run(s, bs_runfolder_frame, rf, &T, &err), 0, "%s", err.msg);
  bs_summary u;
  char text[2048];
  bs_summary_make(s, &T, 1.5, &u);
  cr_assert_gt(bs_summary_format(&u, text, sizeof text), 0);
  cr_assert_eq(bs_runfolder_finish(rf, text, &err), 0, "%s", err.msg);
  bs_runfolder_destroy(&rf);
  cr_assert_null(rf);
  cr_assert_eq(T.steps, FRAMES);
  cr_assert_gt(T.iterations, 0);
  check_state(out, s);
  check_frames(out, &T);
  check_summary(out, s, &T, &u);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A run stopped before its first frame: its s/frame and solves/step are not
 * measured (NaN, "nan" in summary.txt and NaN read back), not the partial
 * frame's seconds over no frame or 0 solves. */
Test(runfolder, no_frame_done_has_no_seconds_per_frame, .init = setup, .fini = teardown) {
  bs_scene *sc = small_box();
  bs_sim *s = NULL;
  bs_error err;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  bs_run_totals T;
  memset(&T, 0, sizeof T);
  bs_summary u, back;
  bs_summary_make(s, &T, 71.4, &u);
  cr_expect_eq(u.frames, 0);
  cr_expect_eq(u.partial, BS_SUMMARY_RUNNING);
  cr_expect(isnan(u.s_per_frame), "s/frame %g over no frame", u.s_per_frame);
  cr_expect(isnan(u.solves_per_step), "solves/step %g over no step", u.solves_per_step);
  write_and_read(dir, &u, &back);
  cr_expect(isnan(back.s_per_frame), "s/frame %g read back", back.s_per_frame);
  cr_expect(isnan(back.solves_per_step), "solves/step %g read back", back.solves_per_step);
  cr_expect_eq(back.frames, 0);
  cr_expect_eq(back.frames_total, FRAMES);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* Writes bytes to dir/bad/state.bin. */
static void write_state(const void *bytes, size_t n) {
  char p[600];
  snprintf(p, sizeof p, "%s/bad", dir);
  cr_assert(mkdir(p, 0755) == 0 || errno == EEXIST, "cannot make %s", p);
  snprintf(p, sizeof p, "%s/bad/state.bin", dir);
  FILE *f = fopen(p, "wb");
  cr_assert_not_null(f);
  cr_assert_eq(fwrite(bytes, 1, n, f), n);
  fclose(f);
}

static void expect_refused(const char *what) {
  char d[600], p[600];
  snprintf(d, sizeof d, "%s/bad", dir);
  snprintf(p, sizeof p, "%s/bad/state.bin", dir);
  bs_state_reader r;
  bs_error err;
  bs_error_clear(&err);
  cr_expect_eq(bs_state_open(d, &r, &err), BS_EINPUT, "%s: %s", what, err.msg);
  cr_expect_not_null(strstr(err.msg, p), "%s: the message does not name %s: %s", what, p, err.msg);
  cr_expect_null(r.f, "%s: the reader stays open", what);
}

/* A version-2 header for n vertices, then `frames` frames of zeros and
 * `extra` more bytes. */
static void write_v2(const char magic[4], uint32_t version, int32_t n, int frames, size_t extra) {
  size_t rec = sizeof(double) * (1 + 6 * (size_t)n), len = 16 + frames * rec + extra;
  unsigned char *b = calloc(1, len);
  memcpy(b, magic, 4);
  memcpy(b + 4, &version, 4);
  memcpy(b + 8, &n, 4);
  write_state(b, len);
  free(b);
}

Test(runfolder, bad_state_files_refused, .init = setup, .fini = teardown) {
  /* the writer's layout is what the reader takes: one whole frame of 2 vertices */
  write_v2("BSST", BS_STATE_VERSION, 2, 1, 0);
  char d[600];
  snprintf(d, sizeof d, "%s/bad", dir);
  bs_state_reader r;
  bs_error err;
  cr_assert_eq(bs_state_open(d, &r, &err), 0, "%s", err.msg);
  cr_expect_eq(r.frames, 1);
  cr_expect_eq(bs_state_next(&r), 0);
  cr_expect_eq(bs_state_next(&r), 1, "a second frame read");
  bs_state_close(&r);

  write_v2("BSSX", BS_STATE_VERSION, 2, 1, 0);
  expect_refused("wrong magic");
  write_v2("BSST", 99, 2, 1, 0);
  expect_refused("version 99");
  write_v2("BSST", BS_STATE_VERSION, 2, 0, 8 * 7); /* 7 of the 13 doubles of a frame */
  expect_refused("truncated");
  write_state("BSST", 4); /* shorter than the header */
  expect_refused("no header");
  write_v2("BSST", BS_STATE_VERSION, 0, 1, 0);
  expect_refused("0 vertices");
}

/* The messages say what is wrong. */
Test(runfolder, bad_state_messages, .init = setup, .fini = teardown) {
  char d[600];
  snprintf(d, sizeof d, "%s/bad", dir);
  bs_state_reader r;
  bs_error err;
  write_v2("XSST", BS_STATE_VERSION, 2, 1, 0);
  cr_expect_eq(bs_state_open(d, &r, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "not a bigstep state file"), "%s", err.msg);
  write_v2("BSST", 99, 2, 1, 0);
  cr_expect_eq(bs_state_open(d, &r, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "version 99"), "%s", err.msg);
  write_v2("BSST", BS_STATE_VERSION, 2, 0, 8);
  cr_expect_eq(bs_state_open(d, &r, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "shorter than one frame"), "%s", err.msg);
  /* a folder without state.bin: BS_EIO naming it */
  cr_expect_eq(bs_state_open(dir, &r, &err), BS_EIO);
  cr_expect_not_null(strstr(err.msg, "state.bin"), "%s", err.msg);
}

/* After each frame: frames.pvd lists every VTU frame written so far. */
static int pvd_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  int st = bs_runfolder_frame(s, fs, ctx, err);
  if (st) return st;
  char p[600];
  snprintf(p, sizeof p, "%s/run/frames.pvd", dir);
  bs_pvd *pvd = NULL;
  cr_assert_eq(bs_pvd_read(p, &pvd, err), 0, "frame %d: %s", fs->frame, err->msg);
  cr_expect_eq(pvd->n, fs->frame + 1, "frame %d: %d entries", fs->frame, pvd->n);
  cr_expect_eq(pvd->times[pvd->n - 1], s->time);
  bs_pvd_destroy(&pvd);
  return 0;
}

/* Runs small_box into dir/run with VTU frames, the options o. */
static int run_into(const bs_runfolder_opts *o, bs_error *err) {
  bs_scene *sc = small_box();
  sc->vtu_every = 1;
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_run_totals T;
  char out[512];
  snprintf(out, sizeof out, "%s/run", dir);
  cr_assert_eq(bs_sim_create(sc, &s, err), 0, "%s", err->msg);
  int st = bs_runfolder_open(out, s, o, &rf, err);
  if (!st) st = bs_sim_run(s, pvd_frame, rf, &T, err);
  if (!st) st = bs_runfolder_finish(rf, NULL, err);
  bs_runfolder_destroy(&rf);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return st;
}

static int exists(const char *name) {
  char p[600];
  snprintf(p, sizeof p, "%s/run/%s", dir, name);
  return access(p, F_OK) == 0;
}

Test(runfolder, pvd_valid_each_frame_and_earlier_run_refused, .init = setup, .fini = teardown) {
  bs_error err;
  bs_runfolder_opts o = {.replace = 0, .command_line = "bigstep run test"};
  cr_assert_eq(run_into(&o, &err), 0, "%s", err.msg);
  cr_expect(exists("run.txt") && exists("scene.json") && exists("frame_00003.vtu") && exists("frames.pvd"));
  char sp[600];
  snprintf(sp, sizeof sp, "%s/run/scene.json", dir);
  bs_scene *back = NULL;
  cr_expect_eq(bs_scene_load(sp, 0, NULL, &back, &err), 0, "the resolved scene does not load: %s", err.msg);
  if (back) cr_expect_eq(back->frames, FRAMES);
  bs_scene_destroy(&back);
  cr_expect(!exists("frames.pvd.tmp"), "the temporary PVD is left");
  char p[600];
  snprintf(p, sizeof p, "%s/run/notes.txt", dir); /* the user's file: never removed */
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fclose(f);
  snprintf(p, sizeof p, "%s/run/frame_00009.vtu", dir); /* a stale frame of a longer run */
  cr_assert_not_null(f = fopen(p, "w"));
  fclose(f);
  bs_error_clear(&err);
  cr_expect_eq(run_into(&o, &err), BS_EINPUT, "an earlier run's folder was not refused");
  cr_expect_not_null(strstr(err.msg, "earlier run"), "%s", err.msg);
  cr_expect_not_null(strstr(err.msg, dir), "the message does not name the folder: %s", err.msg);
  o.replace = 1;
  cr_assert_eq(run_into(&o, &err), 0, "%s", err.msg);
  cr_expect(!exists("frame_00009.vtu"), "a stale frame file is left beside the new ones");
  cr_expect(exists("notes.txt"), "the user's own file was removed");
  cr_expect(exists("frame_00003.vtu"));
  snprintf(p, sizeof p, "%s/run/run.txt", dir);
  cr_assert_not_null(f = fopen(p, "r"));
  char line[256];
  cr_assert_not_null(fgets(line, sizeof line, f));
  fclose(f);
  char want[64];
  snprintf(want, sizeof want, "version: bigstep %s\n", bs_version());
  cr_expect_str_eq(line, want);
}
