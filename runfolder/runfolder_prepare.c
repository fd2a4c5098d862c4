/* runfolder_prepare.c — before a run writes into a folder: its lock, the
 * refusal of a folder that holds an earlier run or the removal of that run's
 * files (bs_runfolder.h), and the run's record run.txt. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <sys/file.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "outfile.h"

static int has_suffix(const char *s, const char *suf) {
  size_t n = strlen(s), m = strlen(suf);
  return n >= m && !strcmp(s + n - m, suf);
}

int bs_runfolder_is_run_file(const char *name) {
  static const char *const fixed[] = {"frames.csv", "stats.csv", "state.bin",  "summary.txt",    "frames.pvd",
                                      "qoi.csv",    "run.txt",   "scene.json", "checkpoint.bin", NULL};
  const size_t n = strlen(name), nt = strlen(BS_TMP_SUFFIX);
  if (n > nt && has_suffix(name, BS_TMP_SUFFIX)) { /* a temporary: NAME.tmp of a run file NAME */
    char stem[300];
    if (n - nt >= sizeof stem) return 0;
    memcpy(stem, name, n - nt);
    stem[n - nt] = 0;
    return bs_runfolder_is_run_file(stem);
  }
  for (int i = 0; fixed[i]; i++)
    if (!strcmp(name, fixed[i])) return 1;
  if (!strncmp(name, "frame_", 6) && (has_suffix(name, ".vtu") || has_suffix(name, ".pvtu"))) return 1;
  if (!strncmp(name, "obstacle", 8))
    return has_suffix(name, ".vtu") || has_suffix(name, ".pvd") || has_suffix(name, ".vti") ||
           has_suffix(name, ".vtm");
  return 0;
}

/* Counts (and with remove, unlinks) the run files of dir; *first gets the
 * first one's name. */
static int scan(const char *dir, int remove, int *count, char *first, size_t nfirst, bs_error *err) {
  *count = 0;
  DIR *d = opendir(dir);
  if (!d) return errno == ENOENT ? 0 : bs_error_set(err, BS_EIO, "cannot read folder '%s': %s", dir, strerror(errno));
  int st = 0;
  for (struct dirent *e; !st && (e = readdir(d));) {
    if (!bs_runfolder_is_run_file(e->d_name)) continue;
    if (*count == 0) snprintf(first, nfirst, "%s", e->d_name);
    (*count)++;
    char p[BS_MAX_PATH + 300];
    snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
    if (remove && unlink(p) && errno != ENOENT)
      st = bs_error_set(err, BS_EIO, "cannot remove '%s' of the earlier run: %s", p, strerror(errno));
  }
  closedir(d);
  return st;
}

int bs_runfolder_prepare(const char *dir, int replace, int *n_removed, bs_error *err) {
  int count = 0;
  char first[300] = "";
  if (n_removed) *n_removed = 0;
  int st = scan(dir, 0, &count, first, sizeof first, err);
  if (st || count == 0) return st;
  if (!replace)
    return bs_error_set(err, BS_EINPUT,
                        "output folder '%s' holds an earlier run (%s and %d other file%s): replace it (bigstep run "
                        "--replace) or choose another output.dir",
                        dir, first, count - 1, count == 2 ? "" : "s");
  st = scan(dir, 1, &count, first, sizeof first, err);
  if (!st && n_removed) *n_removed = count;
  return st;
}

/* The pid recorded in a lock file held by another process ("?" if none). */
static void holder(int fd, char *buf, size_t n) {
  char text[32] = "";
  ssize_t got = pread(fd, text, sizeof text - 1, 0);
  long pid = 0;
  if (got > 0 && sscanf(text, "%ld", &pid) == 1 && pid > 0) snprintf(buf, n, "pid %ld", pid);
  else snprintf(buf, n, "pid unknown");
}

int bs_runfolder_lock(const char *dir, int *out, bs_error *err) {
  *out = -1;
  char p[BS_MAX_PATH + 32];
  snprintf(p, sizeof p, "%s/%s", dir, BS_RUNFOLDER_LOCK);
  int fd = open(p, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return bs_error_set(err, BS_EIO, "cannot open the lock file '%s': %s", p, strerror(errno));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    int e = errno;
    char who[48];
    holder(fd, who, sizeof who);
    close(fd);
    if (e == EWOULDBLOCK)
      return bs_error_set(err, BS_EINPUT,
                          "output folder '%s' is in use by another run (%s holds '%s'): wait for it to end or choose "
                          "another output.dir",
                          dir, who, p);
    return bs_error_set(err, BS_EIO, "cannot lock '%s': %s", p, strerror(e));
  }
  char pid[32];
  int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
  if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != len) {
    int e = errno;
    close(fd);
    return bs_error_set(err, BS_EIO, "cannot write '%s': %s", p, strerror(e));
  }
  *out = fd;
  return 0;
}

void bs_runfolder_unlock(int *fd) {
  if (!fd || *fd < 0) return;
  int rc = ftruncate(*fd, 0); /* the pid is a hint for messages: a failure here does not matter */
  (void)rc;
  close(*fd); /* releases the flock */
  *fd = -1;
}

int bs_runfolder_write_record(const char *dir, const char *command_line, bs_error *err) {
  char stamp[64] = "?";
  time_t now = time(NULL);
  struct tm tm;
  if (gmtime_r(&now, &tm)) strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &tm);
  char cwd[BS_MAX_PATH];
  if (!getcwd(cwd, sizeof cwd)) snprintf(cwd, sizeof cwd, "?");
  bs_outfile o;
  int st = bs_outfile_open_replace(&o, dir, "run.txt", err);
  if (st) return st;
  bs_outfile_printf(&o, "version: bigstep %s\ncommand: %s\ncwd: %s\nstarted: %s\n", bs_version(),
                    command_line ? command_line : "(library call)", cwd, stamp);
  return bs_outfile_close(&o, err);
}
