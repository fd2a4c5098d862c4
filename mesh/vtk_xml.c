/* vtk_xml.c — the pieces of VTK XML output that the .vtu, .pvd and .vti
 * writers share (see vtk_xml.h): byte order, escaping, appended arrays raw
 * or zlib-compressed in VTK's block layout. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "vtk_xml.h"

const char *bs__vtk_byte_order(void) {
  const uint16_t one = 1;
  unsigned char c;
  memcpy(&c, &one, 1);
  return c ? "LittleEndian" : "BigEndian";
}

int bs__vtk_put_escaped(FILE *fp, const char *s) {
  for (; *s; s++) {
    int r;
    switch (*s) {
      case '&': r = fputs("&amp;", fp); break;
      case '<': r = fputs("&lt;", fp); break;
      case '>': r = fputs("&gt;", fp); break;
      case '"': r = fputs("&quot;", fp); break;
      case '\'': r = fputs("&apos;", fp); break;
      default: r = fputc(*s, fp); break;
    }
    if (r < 0) return -1;
  }
  return 0;
}

/* The zlib encoding of data (vtk_xml.h): header words, then the blocks, each
 * compressed in place after the previous one. */
static int zlib_encode(bs_vtk_blob *b, const char *name, bs_error *err) {
  const uint64_t B = BS_VTK_BLOCK, nb = (b->bytes + B - 1) / B;
  const uint64_t head = 8 * (3 + nb);
  const uint64_t cap = head + nb * (uint64_t)compressBound((uLong)B);
  uint64_t *h = malloc((size_t)cap);
  if (!h) return bs_error_set(err, BS_ENOMEM, "out of memory compressing array '%s' (%llu bytes)", name,
                              (unsigned long long)b->bytes);
  h[0] = nb;
  h[1] = B;
  h[2] = b->bytes % B;
  unsigned char *out = (unsigned char *)h + head;
  uint64_t used = head;
  for (uint64_t i = 0; i < nb; i++) {
    const uint64_t len = i + 1 < nb || !h[2] ? B : h[2];
    uLongf clen = (uLongf)(cap - used);
    int zs = compress2(out, &clen, (const Bytef *)b->data + i * B, (uLong)len, BS_VTK_ZLIB_LEVEL);
    if (zs != Z_OK) {
      free(h);
      return bs_error_set(err, zs == Z_MEM_ERROR ? BS_ENOMEM : BS_EINTERNAL,
                          "zlib failed (%d) compressing array '%s'", zs, name);
    }
    h[3 + i] = clen;
    out += clen;
    used += clen;
  }
  b->z = (unsigned char *)h;
  b->encoded = used;
  return 0;
}

int bs__vtk_blob_encode(bs_vtk_blob *b, const void *data, uint64_t bytes, int compress, const char *name,
                        bs_error *err) {
  memset(b, 0, sizeof *b);
  b->data = data;
  b->bytes = bytes;
  b->encoded = 8 + bytes;
  return compress ? zlib_encode(b, name, err) : 0;
}

int bs__vtk_blob_write(FILE *fp, const bs_vtk_blob *b) {
  if (b->z) return fwrite(b->z, 1, (size_t)b->encoded, fp) == (size_t)b->encoded ? 0 : -1;
  if (fwrite(&b->bytes, sizeof b->bytes, 1, fp) != 1) return -1;
  if (b->bytes && fwrite(b->data, 1, (size_t)b->bytes, fp) != (size_t)b->bytes) return -1;
  return 0;
}

void bs__vtk_blob_free(bs_vtk_blob *b) {
  free(b->z);
  memset(b, 0, sizeof *b);
}

/* VTK 9.2 as Debian 12 builds it, with an expat that carries expat 2.6's
 * "reparse deferral", fails on raw appended data, VTK's own files included
 * ("not well-formed (invalid token)", VTK issue 19258): expat has not yet
 * reported the <AppendedData> tag when VTK hands it the block that holds the
 * binary bytes. Measured with python3-vtk and pvpython: files whose '_' lies
 * in the block after the tag's read (headers of 2 to 80 kB); with less
 * padding they fail. */
int bs__vtk_start_appended(FILE *fp) {
  enum { BLOCK = 8192 };
  long at = ftell(fp);
  if (at < 0) return -1;
  long target = (at + BLOCK - 1) / BLOCK * BLOCK + BLOCK;
  char buf[256];
  memset(buf, ' ', sizeof buf);
  for (long n = target - at - 1; n > 0;) {
    size_t k = n > (long)sizeof buf ? sizeof buf : (size_t)n;
    if (fwrite(buf, 1, k, fp) != k) return -1;
    n -= (long)k;
  }
  return fputc('_', fp) == EOF ? -1 : 0;
}

int bs__vtk_close(FILE *fp, int bad, const char *what, const char *path, bs_error *err) {
  int e = errno;
  if (ferror(fp)) bad = 1;
  if (fclose(fp) != 0) {
    e = errno;
    bad = 1;
  }
  if (!bad) return BS_OK;
  remove(path);
  return bs_error_set(err, BS_EIO, "write %s: writing '%s' failed: %s", what, path, strerror(e));
}
