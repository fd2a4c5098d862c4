/* `bigstep run` stopped and continued (--resume), one run per folder, a full
 * disk: two boxes, one falling onto the other, on a floor with friction
 * (constraint), self-collision with friction, every output on; 48 frames of
 * 2 steps (about a second). A run killed (kill -9) at a random frame, or
 * stopped by SIGINT (exit 130, a consistent folder), and then resumed ends
 * with the same state.bin, frames.csv (but its seconds column), stats.csv
 * (but its timing columns) and VTU frames, byte for byte, as the run never
 * stopped. A bad checkpoint or another scene is refused. */
#define _GNU_SOURCE
#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "bs_vtu_read.h"
#include "cli_util.h"

#define FRAMES 48
/* This test's folder (each test runs in a process of its own). */
static char root[128];
#define AT(buf, name) snprintf(buf, sizeof buf, "%s/%s", root, name)

static const char *const scene_text =
    "{\"time\": {\"fps\": 24, \"frames\": 48, \"steps_per_frame\": 2},\n"
    " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-3},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [3, 3, 3], \"size\": [0.5, 0.5, 0.5]},\n"
    "   \"translate\": [0, 0.3, 0],\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000,\n"
    "                \"rayleigh\": 0.01}},\n"
    "  {\"mesh\": \"box\", \"box\": {\"cells\": [3, 3, 3], \"size\": [0.5, 0.5, 0.5]},\n"
    "   \"translate\": [0.2, 1.0, 0], \"velocity\": [0, -2, 0],\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"constraint\",\n"
    "                \"friction\": 0.3}],\n"
    " \"self_collision\": {\"stiffness\": 1e5, \"friction\": 0.2},\n"
    " \"qoi\": [{\"name\": \"ke\", \"quantity\": \"energy\", \"term\": \"kinetic\"}],\n"
    " \"output\": {\"vtu_every\": 1, \"states\": true, \"checkpoint_every\": 3}}\n";

static void sh(const char *fmt, const char *arg) {
  char cmd[1024];
  snprintf(cmd, sizeof cmd, fmt, arg);
  cr_assert_eq(system(cmd), 0, "%s", cmd);
}

static void setup(void) {
  snprintf(root, sizeof root, "/tmp/bs_cli_resume_%ld", (long)getpid());
  sh("rm -rf %1$s && mkdir -p %1$s", root);
  char p[256];
  AT(p, "scene.json");
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(scene_text, f);
  fclose(f);
}
static void teardown(void) { sh("rm -rf %s", root); }

/* `bigstep run SCENE --quiet --out DIR ARGS` in the foreground: its status, output in *out. */
static int run(const char *dir, const char *args, char **out) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "%s run %s/scene.json --quiet --out %s %s", BS_BIGSTEP_EXE, root, dir, args);
  return bs_test_run(cmd, out);
}

/* The same in the background (output to DIR.log): its pid. */
static pid_t start(const char *dir) {
  char log[512], scene[256];
  snprintf(log, sizeof log, "%s.log", dir);
  AT(scene, "scene.json");
  pid_t pid = fork();
  cr_assert(pid >= 0);
  if (pid == 0) {
    int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execl(BS_BIGSTEP_EXE, BS_BIGSTEP_EXE, "run", scene, "--quiet", "--out", dir, (char *)NULL);
    _exit(127);
  }
  return pid;
}

/* Waits until dir/frames.csv holds the rows of frames 0..frame (or the run
 * ended: returns 0 then); 1 while it runs. */
static int wait_for_frame(pid_t pid, const char *dir, int frame) {
  for (;;) {
    int status;
    if (waitpid(pid, &status, WNOHANG) == pid) return 0;
    if (bs_frames_csv_lines(dir) >= frame + 2) return 1;
    usleep(1000);
  }
}

static int finish_child(pid_t pid) {
  int status;
  cr_assert_eq(waitpid(pid, &status, 0), pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* The file dir/name with, per line, the comma-separated columns in `skip` left out. */
static char *read_columns(const char *dir, const char *name, const int *skip, int n_skip) {
  char p[512], *line = NULL;
  size_t cap = 0, len = 0, size = 1 << 16;
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "r");
  cr_assert_not_null(f, "%s", p);
  char *text = calloc(size, 1);
  while (getline(&line, &cap, f) > 0) {
    int col = 0;
    for (char *tok = strtok(line, ",\n"); tok; tok = strtok(NULL, ",\n"), col++) {
      int drop = 0;
      for (int i = 0; i < n_skip; i++) drop |= skip[i] == col;
      if (drop) continue;
      while (len + strlen(tok) + 2 >= size) text = realloc(text, size *= 2);
      len += (size_t)sprintf(text + len, "%s,", tok);
    }
    text[len++] = '\n';
    text[len] = 0;
  }
  free(line);
  fclose(f);
  return text;
}

static void expect_same_file(const char *a, const char *b, const char *name) {
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "cmp -s %s/%s %s/%s", a, name, b, name);
  cr_expect_eq(system(cmd), 0, "%s differs from the run never stopped", name);
}

/* The resumed run `dir` against the reference `ref`, byte for byte. */
static void expect_same_run(const char *ref, const char *dir) {
  expect_same_file(ref, dir, "state.bin");
  expect_same_file(ref, dir, "qoi.csv");
  expect_same_file(ref, dir, "frames.pvd");
  expect_same_file(ref, dir, "obstacles_0.pvd");
  static const int frames_timing[] = {11}, stats_timing[] = {18, 19, 20, 21, 22};
  char *a = read_columns(ref, "frames.csv", frames_timing, 1), *b = read_columns(dir, "frames.csv", frames_timing, 1);
  cr_expect_str_eq(b, a, "frames.csv (but its seconds) differs");
  free(a);
  free(b);
  a = read_columns(ref, "stats.csv", stats_timing, 5), b = read_columns(dir, "stats.csv", stats_timing, 5);
  cr_expect_str_eq(b, a, "stats.csv (but its timing) differs");
  free(a);
  free(b);
  for (int f = 0; f <= FRAMES; f++) {
    char name[64];
    snprintf(name, sizeof name, "frame_%05d.vtu", f);
    expect_same_file(ref, dir, name);
  }
  bs_summary u;
  bs_error err;
  cr_assert_eq(bs_summary_read(dir, &u, &err), 0, "%s", err.msg);
  cr_expect_eq(u.partial, BS_SUMMARY_COMPLETE);
}

/* A random frame in [2, FRAMES - 8], logged so that a failure can be repeated. */
static int random_frame(void) {
  srand((unsigned)time(NULL) ^ (unsigned)getpid());
  int f = 2 + rand() % (FRAMES - 9);
  cr_log_info("stopping at frame %d", f);
  return f;
}

static void reference(char *ref, size_t n, char **out) {
  snprintf(ref, n, "%s/ref", root);
  cr_assert_eq(run(ref, "", out), 0, "%s", *out);
  free(*out);
}

Test(cli_resume, killed_at_a_random_frame_then_resumed_repeats_the_run, .init = setup, .fini = teardown) {
  char *out = NULL, ref[160], dir[160];
  reference(ref, sizeof ref, &out);
  AT(dir, "k9");
  const int f = random_frame();
  pid_t pid = start(dir);
  int running = wait_for_frame(pid, dir, f);
  if (running) kill(pid, SIGKILL);
  int rc = finish_child(pid);
  if (!running) cr_log_warn("the run ended (status %d) before it could be killed", rc);
  else cr_expect_eq(rc, 128 + SIGKILL);
  cr_assert_eq(run(dir, "--resume", &out), 0, "%s", out);
  free(out);
  expect_same_run(ref, dir);
}

/* After SIGINT: exit 130, the folder consistent (rows of frames 0..K, as
 * many complete VTU frames in frames.pvd, the summary interrupted at K, the
 * checkpoint at K), then resumed as the run never stopped. */
Test(cli_resume, sigint_leaves_a_consistent_folder_and_resumes, .init = setup, .fini = teardown) {
  char *out = NULL, ref[160], dir[160], p[256];
  reference(ref, sizeof ref, &out);
  AT(dir, "int");
  const int f = random_frame();
  pid_t pid = start(dir);
  int running = wait_for_frame(pid, dir, f);
  cr_assert(running, "the run ended before SIGINT");
  kill(pid, SIGINT);
  cr_assert_eq(finish_child(pid), 130);
  bs_summary u;
  bs_error err;
  cr_assert_eq(bs_summary_read(dir, &u, &err), 0, "%s", err.msg);
  cr_expect_eq(u.partial, BS_SUMMARY_INTERRUPTED);
  const int K = u.frames;
  cr_expect_geq(K, f);
  cr_expect_eq(bs_frames_csv_lines(dir), K + 2, "frames.csv: %d lines for frame %d", bs_frames_csv_lines(dir), K);
  bs_pvd *pvd = NULL;
  snprintf(p, sizeof p, "%s/frames.pvd", dir);
  cr_assert_eq(bs_pvd_read(p, &pvd, &err), 0, "%s", err.msg);
  cr_expect_eq(pvd->n, K + 1);
  for (int i = 0; i < pvd->n; i++) {
    bs_vtu *v = NULL;
    cr_expect_eq(bs_vtu_read(pvd->files[i], &v, &err), 0, "%s", err.msg);
    bs_vtu_destroy(&v);
  }
  bs_pvd_destroy(&pvd);
  snprintf(p, sizeof p, "%s/frame_%05d.vtu", dir, K + 1);
  cr_expect_neq(access(p, F_OK), 0, "a frame after the interruption: %s", p);
  cr_assert_eq(run(dir, "--resume", &out), 0, "%s", out);
  free(out);
  expect_same_run(ref, dir);
}

/* A second run into a folder in use (the first one paused, SIGSTOP) is
 * refused at once, naming the folder and the first run's pid. */
Test(cli_resume, a_second_run_into_a_folder_in_use_is_refused, .init = setup, .fini = teardown) {
  char dir[160];
  AT(dir, "busy");
  pid_t pid = start(dir);
  cr_assert(wait_for_frame(pid, dir, 1), "the run ended before the second one could start");
  kill(pid, SIGSTOP);
  char *out = NULL, want[256];
  int rc = run(dir, "--replace", &out);
  kill(pid, SIGCONT);
  kill(pid, SIGINT);
  cr_expect_eq(finish_child(pid), 130);
  cr_expect_eq(rc, 1, "%s", out);
  snprintf(want, sizeof want, "output folder '%s' is in use by another run (pid %ld", dir, (long)pid);
  cr_expect_not_null(strstr(out, want), "%s", out);
  free(out);
}

static void patch(const char *path, long offset, const void *bytes, size_t n) {
  FILE *f = fopen(path, "r+b");
  cr_assert_not_null(f);
  fseek(f, offset, SEEK_SET);
  fwrite(bytes, 1, n, f);
  fclose(f);
}

static void expect_refused(const char *dir, const char *args, const char *what) {
  char *out = NULL;
  cr_expect_eq(run(dir, args, &out), 1, "%s", out);
  cr_expect_not_null(strstr(out, what), "no '%s' in: %s", what, out);
  free(out);
}

Test(cli_resume, bad_checkpoints_and_other_scenes_are_refused, .init = setup, .fini = teardown) {
  char *out = NULL, dir[160], ck[200], good[200], other[160];
  AT(dir, "bad");
  AT(good, "good.bin");
  AT(other, "other");
  snprintf(ck, sizeof ck, "%s/checkpoint.bin", dir);
  cr_assert_eq(run(dir, "--frames 4", &out), 0, "%s", out);
  free(out);
  expect_refused(dir, "--frames 5 --resume", "the scene is not the one it was run with");
  expect_refused(dir, "--frames 4 --set bodies.0.material.youngs=2e5 --resume", "\"youngs\": 200000");
  char cmd[600];
  snprintf(cmd, sizeof cmd, "cp %s %s", ck, good);
  cr_assert_eq(system(cmd), 0);
  snprintf(cmd, sizeof cmd, "cp %s %s", good, ck);
  const uint32_t v7 = 7;
  patch(ck, 4, &v7, 4);
  expect_refused(dir, "--frames 4 --resume", "checkpoint version 7; this bigstep reads versions 3 and 4");
  cr_assert_eq(system(cmd), 0);
  patch(ck, 500, "\x01\x02\x03", 3);
  expect_refused(dir, "--frames 4 --resume", "the checksum does not match");
  cr_assert_eq(system(cmd), 0);
  cr_assert_eq(truncate(ck, 3000), 0);
  expect_refused(dir, "--frames 4 --resume", "truncated or damaged");
  patch(ck, 0, "XXXX", 4);
  expect_refused(dir, "--frames 4 --resume", "is not a bigstep checkpoint");
  cr_assert_eq(unlink(ck), 0);
  expect_refused(dir, "--frames 4 --resume", "no checkpoint to continue from");
  /* a checkpoint of another scene beside the right scene.json */
  cr_assert_eq(run(other, "--frames 4 --set bodies.0.material.youngs=2e5", &out), 0, "%s", out);
  free(out);
  char ocmd[600];
  snprintf(ocmd, sizeof ocmd, "cp %s/checkpoint.bin %s", other, ck);
  cr_assert_eq(system(ocmd), 0);
  expect_refused(dir, "--frames 4 --resume", "is a checkpoint of another scene");
  /* the good one resumes (nothing left to run) and the run is whole */
  cr_assert_eq(system(cmd), 0);
  cr_expect_eq(run(dir, "--frames 4 --resume", &out), 0, "%s", out);
  free(out);
  cr_expect_eq(bs_frames_csv_lines(dir), 6);
  cr_expect_eq(run(dir, "--frames 4 --resume --replace", &out), 2, "%s", out);
  free(out);
}

/* A full disk (a 96 KiB tmpfs): the run ends with status 1 naming the file
 * and the reason. Skipped when tmpfs cannot be mounted here. */
Test(cli_resume, a_full_disk_ends_the_run_with_status_1, .init = setup, .fini = teardown) {
  char mnt[160], dir[200];
  AT(mnt, "small");
  snprintf(dir, sizeof dir, "%s/run", mnt);
  sh("mkdir -p %s", mnt);
  if (mount("tmpfs", mnt, "tmpfs", 0, "size=96k") != 0) {
    cr_log_warn("skipped: cannot mount a tmpfs on %s (%s)", mnt, strerror(errno));
    return;
  }
  char *out = NULL;
  int rc = run(dir, "", &out);
  umount(mnt);
  cr_expect_eq(rc, 1, "%s", out);
  cr_expect_not_null(strstr(out, "bigstep run: "), "%s", out);
  cr_expect_not_null(strstr(out, dir), "the message names no file: %s", out);
  cr_expect_not_null(strstr(out, "No space left on device"), "%s", out);
  free(out);
}

/* SIGTERM stops the run as SIGINT does, with status 143; --resume=DIR finishes it. */
Test(cli_resume, sigterm_exits_143_and_resume_equals_finishes, .init = setup, .fini = teardown) {
  char dir[160], arg[200], *out = NULL;
  AT(dir, "term");
  pid_t pid = start(dir);
  cr_assert(wait_for_frame(pid, dir, 1), "the run ended before SIGTERM");
  kill(pid, SIGTERM);
  cr_expect_eq(finish_child(pid), 143);
  snprintf(arg, sizeof arg, "--resume=%s", dir);
  cr_expect_eq(run("/nowhere", arg, &out), 0, "%s", out);
  free(out);
  cr_expect_eq(bs_frames_csv_lines(dir), FRAMES + 2);
  cr_expect_eq(run(dir, "--resume=", &out), 2, "%s", out);
  cr_expect_not_null(strstr(out, "--resume= needs a folder"), "%s", out);
  free(out);
}
