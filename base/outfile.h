/* outfile.h — checked output files (internal to bigstep: not installed): the one place where a
 * run folder's writes are checked.
 *
 * Every write's failure is kept with the errno of the first failure and
 * reported by bs_outfile_flush / bs_outfile_close as BS_EIO with the message
 * "cannot write 'PATH': REASON" (strerror). A file whose content is replaced
 * is written to PATH.tmp in the same folder (bs_outfile_open_replace) and
 * renamed over PATH when closed, so that a reader, or a kill at any moment,
 * finds the old file or the new one, never a part of it; a failed replace
 * removes PATH.tmp and leaves PATH as it was. Nothing here calls fsync: the
 * guarantee is against the process dying, not the machine.
 *
 * Ownership: a bs_outfile is the caller's struct; open fills it, close and
 * abandon end it (and are no-ops on a closed one).
 */
#ifndef BS_OUTFILE_H
#define BS_OUTFILE_H

#include <stddef.h>
#include <stdio.h>

#include "bs_base.h"

#define BS_TMP_SUFFIX ".tmp"

typedef struct bs_outfile {
  FILE *f;
  char path[BS_MAX_PATH + 64]; /* the file's name in messages (the final one)  */
  char tmp[BS_MAX_PATH + 72];  /* replacing: the temporary file; else ""      */
  int eno;                     /* errno of the first failed write (0: none)   */
  int bad;                     /* a write failed                              */
} bs_outfile;

/* Opens dir/name (dir NULL: name is the path) with an fopen mode ("w", "ab",
 * "r+b", ...). */
int bs_outfile_open(bs_outfile *o, const char *dir, const char *name, const char *mode, bs_error *err);

/* Opens dir/name.tmp for writing; bs_outfile_close renames it to dir/name. */
int bs_outfile_open_replace(bs_outfile *o, const char *dir, const char *name, bs_error *err);

/* Writes; a failure is recorded (returns -1) and reported at the next flush. */
int bs_outfile_printf(bs_outfile *o, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
int bs_outfile_write(bs_outfile *o, const void *p, size_t size, size_t n);

/* fflush, then the verdict on every write so far: 0 or BS_EIO. */
int bs_outfile_flush(bs_outfile *o, bs_error *err);

/* Flushes and closes (replacing: renames over the final name); 0 or BS_EIO.
 * The file is closed either way. */
int bs_outfile_close(bs_outfile *o, bs_error *err);

/* Closes without a verdict (after an error elsewhere); removes a temporary. */
void bs_outfile_abandon(bs_outfile *o);

/* tmp := path + BS_TMP_SUFFIX; renames it over path (0 or BS_EIO naming both
 * and the reason). For writers outside sim/ that take a path (mesh/). */
void bs_tmp_path(char *tmp, size_t n, const char *path);
int bs_tmp_commit(const char *tmp, const char *path, bs_error *err);

/* Writes the string text to dir/name through a temporary (see the top). */
int bs_outfile_replace_text(const char *dir, const char *name, const char *text, bs_error *err);

#endif
