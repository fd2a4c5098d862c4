/* test_child.c — bs_run_in_child: results come back whole, the child's own
 * error comes back as it was set, and a child that crashes or leaves early
 * is an error naming the signal or the exit status, never the caller's end.
 * Mesh_3 runs this way (bs_shim_mesh_surface); test_mesh_surface and
 * test_mesh_lift check its meshes. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_child.h"

#define N 100000 /* larger than a pipe's buffer: the parent reads while the child writes */

typedef struct {
  int mode; /* 0: compute, 1: fail, 2: SIGSEGV, 3: exit early, 4: SIGSEGV mid-send */
  double *v;
  double sum;
} job;

static int run(void *c, bs_error *err) {
  job *j = c;
  if (j->mode == 1) return bs_error_set(err, BS_ENUMERIC, "the job's own error, value %d", 42);
  if (j->mode == 2) {
    signal(SIGSEGV, SIG_DFL); /* the sanitizers' handler would turn the signal into exit(1) */
    raise(SIGSEGV);
  }
  if (j->mode == 3) _exit(7);
  j->v = malloc(N * sizeof(double));
  if (!j->v) return bs_error_set(err, BS_ENOMEM, "no memory");
  for (int i = 0; i < N; i++) j->v[i] = 0.5 * i;
  j->sum = 0.25 * (double)N * (N - 1);
  return BS_OK;
}

static int send(void *c, int fd) {
  job *j = c;
  if (bs_write_all(fd, &j->sum, sizeof j->sum)) return BS_EIO;
  if (j->mode == 4) {
    (void)bs_write_all(fd, j->v, N / 2 * sizeof(double));
    signal(SIGSEGV, SIG_DFL);
    raise(SIGSEGV);
  }
  return bs_write_all(fd, j->v, N * sizeof(double));
}

static int receive(void *c, int fd, bs_error *err) {
  job *j = c;
  int rc = bs_read_all(fd, &j->sum, sizeof j->sum, "the sum", err);
  if (rc) return rc;
  j->v = malloc(N * sizeof(double));
  if (!j->v) return bs_error_set(err, BS_ENOMEM, "no memory");
  rc = bs_read_all(fd, j->v, N * sizeof(double), "the values", err);
  if (rc) {
    free(j->v);
    j->v = NULL;
  }
  return rc;
}

/* The job in mode `mode` run in a child ("the sum"); its status, *err its
 * message, *j what the parent kept. */
static int run_mode(int mode, job *j, bs_error *err) {
  *j = (job){.mode = mode};
  bs_error_clear(err);
  return bs_run_in_child("the sum", run, send, receive, j, err);
}

Test(child, results_come_back_whole) {
  job j;
  bs_error err;
  cr_assert_eq(run_mode(0, &j, &err), BS_OK, "%s", err.msg);
  cr_assert_not_null(j.v);
  double s = 0;
  for (int i = 0; i < N; i++) s += j.v[i];
  cr_expect_eq(s, j.sum, "the values sum to %.17g, the child said %.17g", s, j.sum);
  cr_expect_eq(j.v[N - 1], 0.5 * (N - 1));
  free(j.v);
}

Test(child, the_childs_error_comes_back_as_set) {
  job j;
  bs_error err;
  cr_assert_eq(run_mode(1, &j, &err), BS_ENUMERIC);
  cr_expect_str_eq(err.msg, "the job's own error, value 42");
  cr_expect_null(j.v);
}

Test(child, a_crash_is_an_error_naming_the_signal) {
  job j;
  bs_error err;
  cr_assert_eq(run_mode(2, &j, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "the sum crashed (signal 11") != NULL, "%s", err.msg);
  cr_expect_null(j.v);
}

Test(child, an_early_exit_is_an_error_naming_its_status) {
  job j;
  bs_error err;
  cr_assert_eq(run_mode(3, &j, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "exit status 7") != NULL, "%s", err.msg);
}

Test(child, a_crash_while_sending_keeps_nothing) {
  job j;
  bs_error err;
  cr_assert_eq(run_mode(4, &j, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "signal 11") != NULL, "%s", err.msg);
  cr_expect_null(j.v, "a half-sent result was kept");
}
