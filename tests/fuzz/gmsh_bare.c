/* gmsh_bare.c — a diagnostic, not a test: each input (seeds and mutations,
 * through driver.c) goes STRAIGHT to gmshOpen, without bigstep's .msh check,
 * in a child process (4 GB address space, 20 s alarm), and the way the child
 * ended is printed together with whether bs__msh_check refuses the input.
 * This is how mesh/msh_check.c's list of Gmsh's own crashes was made:
 *
 *   build/tests/fuzz/fuzz_gmsh_bare --mutations 3000 tests/data/fuzz/msh
 *
 * Inputs that killed Gmsh are kept as /tmp/bs_gmsh_bare_<refused|ACCEPTED>_sig<N>_<i>.msh;
 * an ACCEPTED one is a hole in the check. */
#define _DEFAULT_SOURCE
#include <gmshc.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fuzz_util.h"
#include "mesh_internal.h"

static long n_in, n_refused, n_killed_refused, n_killed_accepted;

static void bare_gmsh(const char *path) {
  struct rlimit rl = {4UL << 30, 4UL << 30};
  setrlimit(RLIMIT_AS, &rl);
  alarm(20);
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOpen(path, &ierr);
  size_t *tags = NULL, n = 0, nc = 0, np = 0;
  double *c = NULL, *p = NULL;
  gmshModelMeshGetNodes(&tags, &n, &c, &nc, &p, &np, -1, -1, 0, 0, &ierr);
  _exit(0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".msh", path, sizeof path);
  bs_error err = {0};
  int accepted = bs__msh_check(path, &err) == 0;
  pid_t pid = fork();
  if (pid == 0) bare_gmsh(path);
  int st = 0;
  waitpid(pid, &st, 0);
  n_in++;
  n_refused += !accepted;
  if (pid > 0 && WIFSIGNALED(st)) {
    char keep[128];
    snprintf(keep, sizeof keep, "/tmp/bs_gmsh_bare_%s_sig%d_%ld.msh", accepted ? "ACCEPTED" : "refused",
             WTERMSIG(st), n_in);
    rename(path, keep);
    n_killed_accepted += accepted;
    n_killed_refused += !accepted;
    printf("signal %d in Gmsh, %s: %s%s%s\n", WTERMSIG(st), keep, accepted ? "ACCEPTED by the check" : "",
           accepted ? "" : "refused: ", accepted ? "" : err.msg);
  } else {
    remove(path);
  }
  return 0;
}

__attribute__((destructor)) static void report(void) {
  printf("gmsh_bare: %ld inputs, %ld refused by bigstep's check; Gmsh killed by a signal on %ld refused and %ld "
         "accepted inputs\n",
         n_in, n_refused, n_killed_refused, n_killed_accepted);
}
