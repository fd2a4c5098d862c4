/* fuzz_util.h — what every fuzz harness of tests/fuzz/ shares.
 *
 * A harness is one LLVMFuzzerTestOneInput(data, size) that hands the bytes
 * to one library reader and asserts only that the reader returns 0 or a
 * proper status (a negative BS_E* code other than BS_EINTERNAL) with a
 * non-empty message; a crash, a sanitizer report, a hang or an allocation
 * sized by an unchecked count is what the fuzzer looks for. Readers that need
 * a path get the bytes in a temporary file (removed afterwards).
 */
#ifndef BS_FUZZ_UTIL_H
#define BS_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "bs_base.h"

/* Writes the bytes to a new file /tmp/bs_fuzz_XXXXXX<suffix>; its name into
 * path (n bytes). Aborts when the file cannot be written (not the reader's
 * fault: the fuzz run cannot go on). */
void fuzz_write_temp(const uint8_t *data, size_t size, const char *suffix, char *path, size_t n);

/* Aborts (so that the fuzzer records the input) unless rc is 0, or a
 * negative status other than BS_EINTERNAL whose message is not empty. */
void fuzz_check(const char *reader, int rc, const bs_error *err);

/* Reads the file at path with a library reader, frees what it returned and
 * returns its status (err filled). */
typedef int (*fuzz_reader)(const char *path, bs_error *err);

/* The whole of a harness whose reader takes a path: the bytes into a
 * temporary file with the suffix, read(), the file removed, the status
 * checked (fuzz_check, naming the reader `name`). */
void fuzz_file(const uint8_t *data, size_t size, const char *suffix, const char *name, fuzz_reader read);

/* fuzz_reader of bs_shim_read_surface (the format from the path's suffix). */
int fuzz_read_surface(const char *path, bs_error *err);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif
