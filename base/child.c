/* child.c — a computation run in a child process (see bs_child.h). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <signal.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bs_child.h"

int bs_write_all(int fd, const void *buf, size_t n) {
  const char *p = (const char *)buf;
  while (n > 0) {
    const ssize_t k = write(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return BS_EIO;
    p += k, n -= (size_t)k;
  }
  return BS_OK;
}

int bs_read_all(int fd, void *buf, size_t n, const char *what, bs_error *err) {
  char *p = (char *)buf;
  while (n > 0) {
    const ssize_t k = read(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return bs_error_set(err, BS_EINPUT, "%s: the child process ended before sending it", what);
    p += k, n -= (size_t)k;
  }
  return BS_OK;
}

/* The child's side: run, its status and message, then the results. */
static void child_side(int fd, bs_child_run run, bs_child_send send, void *ctx) {
  bs_error e;
  bs_error_clear(&e);
  const int rc = run(ctx, &e);
  if (bs_write_all(fd, &rc, sizeof rc) || bs_write_all(fd, &e, sizeof e)) _exit(2);
  if (rc == BS_OK && send(ctx, fd)) _exit(3);
  _exit(0);
}

/* waitpid, retried on EINTR; *status the child's. */
static void reap(pid_t pid, int *status) {
  while (waitpid(pid, status, 0) < 0 && errno == EINTR) {
  }
}

/* The child ended before its results were whole: what its status says. */
static int ended_early(const char *what, int status, bs_error *err) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return bs_error_set(err, BS_EINPUT, "%s crashed (signal %d, %s) and sent no result", what, sig, strsignal(sig));
  }
  return bs_error_set(err, BS_EINPUT, "%s ended (exit status %d) before sending its result", what,
                      WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

int bs_run_in_child(const char *what, bs_child_run run, bs_child_send send, bs_child_receive receive, void *ctx,
                    bs_error *err) {
  int fds[2];
  if (pipe(fds) != 0) return bs_error_set(err, BS_ENOMEM, "%s: cannot open a pipe: %s", what, strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) {
    const int e = errno;
    close(fds[0]), close(fds[1]);
    return bs_error_set(err, BS_ENOMEM, "%s: cannot start a child process: %s", what, strerror(e));
  }
  if (pid == 0) {
    close(fds[0]);
    child_side(fds[1], run, send, ctx);
  }
  close(fds[1]);
  int rc = 0, status = 0;
  bs_error e;
  bs_error_clear(&e);
  int got = bs_read_all(fds[0], &rc, sizeof rc, what, err) == BS_OK && bs_read_all(fds[0], &e, sizeof e, what, err) == BS_OK;
  int rrc = BS_OK;
  if (got && rc == BS_OK) got = (rrc = receive(ctx, fds[0], err)) == BS_OK;
  close(fds[0]);
  reap(pid, &status);
  if (!got && rrc != BS_OK && rrc != BS_EINPUT) return rrc; /* the parent's own failure (memory) */
  if (!got) return ended_early(what, status, err);
  if (rc == BS_OK) return BS_OK;
  e.msg[sizeof e.msg - 1] = '\0';
  if (err) *err = e;
  return rc;
}
