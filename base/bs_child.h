/* bs_child.h — a computation run in a child process, so that a crash inside
 * a library it calls ends the child, not the caller.
 *
 * bs_run_in_child forks. The child calls run(ctx, err); when that returns
 * BS_OK it calls send(ctx, fd), which writes the results to a pipe, and
 * then leaves with _exit (no atexit handler, no stdio flush). The parent
 * gets the child's status and message and, on BS_OK, calls receive(ctx, fd,
 * err), which reads the results into memory the parent owns. The child's
 * writes to ctx are its own (copy on write): only what send writes reaches
 * the parent.
 *
 * When the child ends before its results are whole (a signal: SIGSEGV
 * inside the library; or an exit), the call returns BS_EINPUT with a
 * message naming `what` and the signal or the exit status. The results are
 * then whatever receive was given before the end, which receive must free
 * or leave for the caller to free (receive returns an error when the pipe
 * ends early: bs_read_all says so).
 *
 * Made for code that needs no threads of the parent: the child has only the
 * calling thread (it may start its own). It must not enter OpenMP parallel
 * regions when the parent already has: libgomp's thread pool does not
 * survive fork.
 *
 * Errors: BS_EINPUT (the child ended early, named as above; or run's own
 * status and message), BS_ENOMEM (fork or pipe failed: the message names
 * the system's reason), and receive's own codes.
 *
 * Example:
 *   static int run(void *c, bs_error *e) { return compute((job *)c, e); }
 *   static int send(void *c, int fd) { return bs_write_all(fd, ((job *)c)->r, sizeof(double)); }
 *   static int receive(void *c, int fd, bs_error *e) {
 *     return bs_read_all(fd, ((job *)c)->r, sizeof(double), "the result", e);
 *   }
 *   int rc = bs_run_in_child("compute", run, send, receive, &j, &err); */
#ifndef BS_CHILD_H
#define BS_CHILD_H

#include <stddef.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef int (*bs_child_run)(void *ctx, bs_error *err);
typedef int (*bs_child_send)(void *ctx, int fd);
typedef int (*bs_child_receive)(void *ctx, int fd, bs_error *err);

int bs_run_in_child(const char *what, bs_child_run run, bs_child_send send, bs_child_receive receive, void *ctx,
                    bs_error *err);

/* Writes n bytes of buf to fd, retrying short writes and EINTR: BS_OK, or
 * BS_EIO (no message: the reader learns of it from a short read). */
int bs_write_all(int fd, const void *buf, size_t n);

/* Reads exactly n bytes from fd into buf: BS_OK, or BS_EINPUT naming
 * `what` when the pipe ends before them (the writer ended). */
int bs_read_all(int fd, void *buf, size_t n, const char *what, bs_error *err);

#ifdef __cplusplus
}
#endif

#endif
