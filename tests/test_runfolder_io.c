/* Write failures of a run folder (runfolder/bs_runfolder.h): every output file
 * pointed at /dev/full ends the run with BS_EIO and a message naming the file
 * and the OS reason. Appended files (frames.csv, stats.csv, state.bin,
 * qoi.csv) are opened by bs_runfolder_open: their descriptor is then swapped
 * for /dev/full (dup2). Replaced files (VTU frames, obstacle frames, the PVD
 * collections, summary.txt, checkpoint.bin) are written as NAME.tmp and renamed: NAME.tmp is
 * made a symbolic link to /dev/full; the final NAME must then not appear. */
#define _GNU_SOURCE
#include <criterion/criterion.h>
#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_vtu_read.h"
#include "scene_fixture.h"

static char dir[] = "/tmp/bs_runfolder_io_XXXXXX";

static void setup(void) { cr_assert_not_null(mkdtemp(dir)); }
static void teardown(void) {
  char cmd[256];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}

/* The box falling for 2 frames onto a plane with friction, every output on:
 * stats, states, a VTU frame per frame, a quantity of interest. */
static bs_scene *all_outputs(void) {
  bs_scene *sc = bs_test_box_scene(2, 24.0, 1);
  bs_error err;
  bs_scene_obstacle *o = NULL;
  bs_scene_qoi *q = NULL;
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_PLANE, &o, &err), 0, "%s", err.msg);
  o->offset = -0.01;
  o->friction = 0.3;
  cr_assert_eq(bs_scene_add_qoi(sc, "ke", BS_QOI_ENERGY, &q, &err), 0, "%s", err.msg);
  q->energy = BS_QOI_KINETIC;
  sc->gravity[1] = -9.8;
  sc->states = 1;
  sc->stats_csv = 1;
  sc->vtu_every = 1;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  return sc;
}

/* Points the descriptor this process holds on path at /dev/full. */
static void swap_for_dev_full(const char *path) {
  DIR *d = opendir("/proc/self/fd");
  cr_assert_not_null(d);
  int found = 0;
  for (struct dirent *e; (e = readdir(d));) {
    char link[300], target[1024];
    snprintf(link, sizeof link, "/proc/self/fd/%s", e->d_name);
    ssize_t n = readlink(link, target, sizeof target - 1);
    if (n <= 0) continue;
    target[n] = 0;
    if (strcmp(target, path)) continue;
    int full = open("/dev/full", O_WRONLY);
    cr_assert(full >= 0);
    cr_assert(dup2(full, atoi(e->d_name)) >= 0);
    close(full);
    found = 1;
  }
  closedir(d);
  cr_assert(found, "no descriptor on %s", path);
}

/* Runs the scene into dir/NAME-run with `name` failing; returns the status and the message. */
static int run_failing(const char *name, int appended, char *msg, size_t n) {
  bs_scene *sc = all_outputs();
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_error err;
  bs_error_clear(&err);
  char out[512], p[700];
  snprintf(out, sizeof out, "%s/%s-run", dir, name);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_open(out, s, NULL, &rf, &err), 0, "%s", err.msg);
  snprintf(p, sizeof p, "%s/%s%s", out, name, appended ? "" : ".tmp");
  if (appended) swap_for_dev_full(p);
  else cr_assert_eq(symlink("/dev/full", p), 0, "%s", p);
  int st = bs_sim_run(s, bs_runfolder_frame, rf, NULL, &err);
  if (!st) st = bs_runfolder_finish(rf, "summary\n", &err);
  snprintf(msg, n, "%s", err.msg);
  bs_runfolder_destroy(&rf);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return st;
}

static void expect_failure(const char *name, int appended) {
  char msg[BS_ERROR_MSG];
  int st = run_failing(name, appended, msg, sizeof msg);
  cr_expect_eq(st, BS_EIO, "%s: status %d (%s)", name, st, msg);
  cr_expect_not_null(strstr(msg, name), "%s: the message does not name it: %s", name, msg);
  cr_expect_not_null(strstr(msg, "No space left on device"), "%s: no OS reason: %s", name, msg);
}

Test(runfolder_io, appended_files_on_a_full_disk, .init = setup, .fini = teardown) {
  static const char *const names[] = {"frames.csv", "stats.csv", "state.bin", "qoi.csv"};
  for (int i = 0; i < 4; i++) expect_failure(names[i], 1);
}

/* The replaced files: the error names the file, and a failed VTU frame is
 * not left under its final name. */
Test(runfolder_io, replaced_files_on_a_full_disk, .init = setup, .fini = teardown) {
  static const char *const names[] = {"frame_00000.vtu", "obstacle_0.vtu",  "frames.pvd",
                                      "obstacles_0.pvd", "summary.txt", "checkpoint.bin"};
  for (int i = 0; i < 6; i++) expect_failure(names[i], 0);
  char p[600];
  snprintf(p, sizeof p, "%s/frame_00000.vtu-run/frame_00000.vtu", dir);
  cr_expect_neq(access(p, F_OK), 0, "%s was left after its write failed", p);
  snprintf(p, sizeof p, "%s/frame_00000.vtu-run/frame_00000.vtu.tmp", dir);
  cr_expect_neq(access(p, F_OK), 0, "%s was left after its write failed", p);
}

/* The folder after frame fs->frame: no temporary file; frames.pvd names
 * exactly the VTU frames there, each one readable; summary.txt is partial,
 * of the frames so far. */
static void check_consistent(const char *out, const bs_frame_stats *fs) {
  DIR *d = opendir(out);
  cr_assert_not_null(d);
  int n_vtu = 0;
  for (struct dirent *e; (e = readdir(d));) {
    const size_t n = strlen(e->d_name);
    cr_expect(n < 4 || strcmp(e->d_name + n - 4, ".tmp"), "frame %d: %s is left", fs->frame, e->d_name);
    n_vtu += !strncmp(e->d_name, "frame_", 6);
  }
  closedir(d);
  char p[600];
  bs_error err;
  snprintf(p, sizeof p, "%s/frames.pvd", out);
  bs_pvd *pvd = NULL;
  cr_assert_eq(bs_pvd_read(p, &pvd, &err), 0, "frame %d: %s", fs->frame, err.msg);
  cr_expect_eq(pvd->n, n_vtu, "frame %d: %d entries, %d VTU files", fs->frame, pvd->n, n_vtu);
  for (int i = 0; i < pvd->n; i++) {
    bs_vtu *v = NULL;
    cr_expect_eq(bs_vtu_read(pvd->files[i], &v, &err), 0, "frame %d: %s", fs->frame, err.msg);
    bs_vtu_destroy(&v);
  }
  bs_pvd_destroy(&pvd);
  bs_summary u;
  cr_assert_eq(bs_summary_read(out, &u, &err), 0, "frame %d: %s", fs->frame, err.msg);
  cr_expect_eq(u.partial, BS_SUMMARY_RUNNING, "frame %d", fs->frame);
  cr_expect_eq(u.frames, fs->frame);
  cr_expect_eq(u.frames_total, 2);
}

static int consistent_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  int st = bs_runfolder_frame(s, fs, ctx, err);
  char out[512];
  snprintf(out, sizeof out, "%s/run", dir);
  if (!st) check_consistent(out, fs);
  return st;
}

Test(runfolder_io, consistent_after_every_frame, .init = setup, .fini = teardown) {
  bs_scene *sc = all_outputs();
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_error err;
  char out[512];
  snprintf(out, sizeof out, "%s/run", dir);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_open(out, s, NULL, &rf, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_run(s, consistent_frame, rf, NULL, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_finish(rf, NULL, &err), 0, "%s", err.msg);
  bs_runfolder_destroy(&rf);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* One run per folder: while the folder's lock is held (here by the test,
 * through a descriptor of its own), bs_runfolder_open refuses it naming the
 * folder and the holder's pid; once released the folder opens. */
Test(runfolder_io, a_folder_in_use_is_refused, .init = setup, .fini = teardown) {
  bs_scene *sc = all_outputs();
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL, *second = NULL;
  bs_error err;
  char out[512], pid[32];
  snprintf(out, sizeof out, "%s/run", dir);
  snprintf(pid, sizeof pid, "pid %ld", (long)getpid());
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_open(out, s, NULL, &rf, &err), 0, "%s", err.msg);
  cr_expect_eq(bs_runfolder_open(out, s, &(bs_runfolder_opts){.replace = 1}, &second, &err), BS_EINPUT);
  cr_expect_null(second);
  cr_expect_not_null(strstr(err.msg, "is in use by another run"), "%s", err.msg);
  cr_expect_not_null(strstr(err.msg, out), "the message does not name the folder: %s", err.msg);
  cr_expect_not_null(strstr(err.msg, pid), "the message does not name the holder (%s): %s", pid, err.msg);
  char p[600];
  snprintf(p, sizeof p, "%s/frames.csv", out);
  cr_expect_eq(access(p, F_OK), 0, "the refused open removed the first run's files");
  bs_runfolder_destroy(&rf);
  cr_expect_eq(bs_runfolder_open(out, s, &(bs_runfolder_opts){.replace = 1}, &second, &err), 0, "%s", err.msg);
  bs_runfolder_destroy(&second);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}
