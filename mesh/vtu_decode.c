/* vtu_decode.c — the bytes of one DataArray: base64 text, VTK's block header,
 * zlib-compressed blocks, inline (format="binary") and appended (raw or
 * base64) data; see vtu_internal.h.
 *
 * VTK's layout: an uncompressed block is one header word (UInt32 or UInt64,
 * the file's header_type) holding the number of data bytes, then the data.
 * With compressor="vtkZLibDataCompressor" the data is cut into blocks of
 * `block size` bytes (the last one `last block size` bytes, or a full block
 * when that is 0), each compressed with zlib, and the header is
 * [number of blocks, block size, last block size, compressed size of each
 * block], then the compressed blocks back to back. Inline, the header and the
 * data are base64-encoded (VTK encodes them separately, so padding may end
 * the header's text). Appended raw, the array's offset is the position of
 * its header after the '_'; appended base64, the position in the text, and
 * the array's text ends where the next array's begins. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "vtu_internal.h"

/* ---- base64 ---------------------------------------------------------------- */

static int b64_value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

int bs__vtu_base64(const char *s, size_t n, unsigned char **out, size_t *outlen, bs_error *err) {
  *out = NULL;
  *outlen = 0;
  unsigned char *o = malloc(n / 4 * 3 + 3);
  if (!o) return bs_error_set(err, BS_ENOMEM, "out of memory for %zu characters of base64", n);
  size_t w = 0;
  uint32_t acc = 0;
  int q = 0, pad = 0; /* characters in the current group, '=' among them */
  for (size_t i = 0; i < n; i++) {
    unsigned char c = (unsigned char)s[i];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') continue;
    int v = c == '=' ? 0 : b64_value(c);
    const char *why = v < 0                 ? "a character outside the base64 alphabet"
                      : c == '=' && q < 2   ? "'=' in the first half of a group"
                      : c != '=' && pad > 0 ? "a character after '=' in the same group"
                                            : NULL;
    if (why) {
      free(o);
      return bs_error_set(err, BS_EINPUT, "bad base64: %s (0x%02x at character %zu)", why, c, i);
    }
    pad += c == '=';
    acc = acc << 6 | (uint32_t)v;
    if (++q == 4) {
      unsigned char b[3] = {(unsigned char)(acc >> 16), (unsigned char)(acc >> 8), (unsigned char)acc};
      memcpy(o + w, b, (size_t)(3 - pad));
      w += (size_t)(3 - pad);
      acc = 0;
      q = pad = 0;
    }
  }
  if (q) {
    free(o);
    return bs_error_set(err, BS_EINPUT, "bad base64: the text ends inside a group of 4 characters (%d left over)",
                        q);
  }
  *out = o;
  *outlen = w;
  return BS_OK;
}

/* ---- blocks -------------------------------------------------------------- */

static uint64_t word(const bs__vtu_doc *d, const unsigned char *p) {
  unsigned char b[8];
  const int hs = d->header8 ? 8 : 4;
  memcpy(b, p, (size_t)hs);
  if (d->swap) bs__vtu_swap(b, 1, hs);
  if (hs == 8) {
    uint64_t v;
    memcpy(&v, b, 8);
    return v;
  }
  uint32_t v;
  memcpy(&v, b, 4);
  return v;
}

/* zlib's deflate expands at most 1032-fold: a block that claims more is
 * corrupt, and is refused before anything is allocated for it. */
enum { MAX_INFLATE_RATIO = 1032 };

typedef struct zheader {
  uint64_t nb, bs, last; /* blocks, block size, size of the last block */
  size_t hdr;            /* header bytes                               */
  uint64_t csum;         /* sum of the compressed sizes                */
} zheader;

/* Reads and checks the compression header at p. */
static int zlib_header(const bs__vtu_doc *d, const unsigned char *p, size_t avail, uint64_t expect, zheader *z,
                       bs_error *err) {
  const size_t hs = d->header8 ? 8 : 4;
  if (avail < 3 * hs)
    return bs_error_set(err, BS_EINPUT, "the compression header is cut off (%zu of %zu bytes): truncated data", avail,
                        3 * hs);
  z->nb = word(d, p);
  z->bs = word(d, p + hs);
  uint64_t last = word(d, p + 2 * hs);
  if (z->nb > (avail - 3 * hs) / hs)
    return bs_error_set(err, BS_EINPUT, "the compression header lists %llu blocks but only %zu bytes follow: "
                        "truncated data", (unsigned long long)z->nb, avail - 3 * hs);
  if (last > z->bs || (z->nb > 0 && z->bs == 0))
    return bs_error_set(err, BS_EINPUT, "the compression header gives blocks of %llu bytes and a last block of %llu",
                        (unsigned long long)z->bs, (unsigned long long)last);
  z->last = last ? last : z->bs;
  z->hdr = (size_t)(3 + z->nb) * hs;
  uint64_t total = 0;
  if (z->nb > 0) {
    if (z->nb - 1 > (UINT64_MAX - z->last) / z->bs)
      return bs_error_set(err, BS_EINPUT, "the compression header's sizes overflow");
    total = (z->nb - 1) * z->bs + z->last;
  }
  if (total != expect)
    return bs_error_set(err, BS_EINPUT, "holds %llu bytes (uncompressed), expected %llu", (unsigned long long)total,
                        (unsigned long long)expect);
  z->csum = 0;
  for (uint64_t i = 0; i < z->nb; i++) {
    uint64_t c = word(d, p + (3 + i) * hs), raw = i + 1 < z->nb ? z->bs : z->last;
    if (c > avail - z->hdr - z->csum)
      return bs_error_set(err, BS_EINPUT, "compressed block %llu of %llu (%llu bytes) runs past the end of the data: "
                          "truncated data", (unsigned long long)i, (unsigned long long)z->nb, (unsigned long long)c);
    if (raw / MAX_INFLATE_RATIO > c)
      return bs_error_set(err, BS_EINPUT, "compressed block %llu of %llu claims %llu bytes from %llu: more than zlib "
                          "can expand", (unsigned long long)i, (unsigned long long)z->nb, (unsigned long long)raw,
                          (unsigned long long)c);
    z->csum += c;
  }
  return BS_OK;
}

/* Inflates the blocks after the header at p into out (expect bytes). */
static int zlib_inflate(const bs__vtu_doc *d, const unsigned char *p, const zheader *z, unsigned char *out,
                        bs_error *err) {
  const size_t hs = d->header8 ? 8 : 4;
  const unsigned char *src = p + z->hdr;
  size_t at = 0;
  for (uint64_t i = 0; i < z->nb; i++) {
    const uint64_t c = word(d, p + (3 + i) * hs), raw = i + 1 < z->nb ? z->bs : z->last;
    uLongf dl = (uLongf)raw;
    uLong sl = (uLong)c;
    int zr = uncompress2(out + at, &dl, src, &sl);
    if (zr != Z_OK || dl != raw || sl != c)
      return bs_error_set(err, BS_EINPUT, "zlib block %llu of %llu (%llu bytes): %s", (unsigned long long)i,
                          (unsigned long long)z->nb, (unsigned long long)c,
                          zr == Z_BUF_ERROR ? "it inflates to more than the header's size, or is cut off"
                          : zr != Z_OK     ? zError(zr)
                          : dl != raw      ? "it inflates to fewer bytes than the header's size"
                                           : "its compressed stream ends before the header's size");
    at += (size_t)raw;
    src += c;
  }
  return BS_OK;
}

int bs__vtu_block(const bs__vtu_doc *d, const unsigned char *p, size_t avail, uint64_t expect, size_t *used,
                  const unsigned char **data, unsigned char **owned, bs_error *err) {
  const size_t hs = d->header8 ? 8 : 4;
  *owned = NULL;
  *data = NULL;
  if (!d->zlib) {
    if (avail < hs)
      return bs_error_set(err, BS_EINPUT, "the block's byte count is cut off (%zu of %zu bytes): truncated data",
                          avail, hs);
    uint64_t n = word(d, p);
    if (n > avail - hs)
      return bs_error_set(err, BS_EINPUT, "the block holds %llu bytes but only %zu follow: truncated data",
                          (unsigned long long)n, avail - hs);
    if (n != expect)
      return bs_error_set(err, BS_EINPUT, "holds %llu bytes, expected %llu", (unsigned long long)n,
                          (unsigned long long)expect);
    *data = p + hs;
    *used = hs + (size_t)n;
    return BS_OK;
  }
  zheader z = {0};
  int rc = zlib_header(d, p, avail, expect, &z, err);
  if (rc) return rc;
  unsigned char *out = malloc((size_t)expect + 1);
  if (!out) return bs_error_set(err, BS_ENOMEM, "out of memory for %llu bytes", (unsigned long long)expect);
  if ((rc = zlib_inflate(d, p, &z, out, err))) {
    free(out);
    return rc;
  }
  *owned = out;
  *data = out;
  *used = z.hdr + (size_t)z.csum;
  return BS_OK;
}

/* ---- arrays ------------------------------------------------------------------- */

/* Decodes base64 text s[0..n) holding exactly one block. */
static int base64_block(const bs__vtu_doc *d, const char *s, size_t n, uint64_t expect, const unsigned char **data,
                        unsigned char **owned, bs_error *err) {
  unsigned char *bytes;
  size_t nb, used;
  int rc = bs__vtu_base64(s, n, &bytes, &nb, err);
  if (rc) return rc;
  unsigned char *inflated;
  rc = bs__vtu_block(d, bytes, nb, expect, &used, data, &inflated, err);
  if (!rc && used != nb)
    rc = bs_error_set(err, BS_EINPUT, "its base64 text decodes to %zu bytes, %zu more than its block", nb, nb - used);
  if (rc) {
    free(inflated);
    free(bytes);
    *data = NULL;
    return rc;
  }
  if (inflated) {
    free(bytes);
    *owned = inflated;
  } else {
    *owned = bytes;
  }
  return BS_OK;
}

/* The end of appended array a's base64 text: the next offset after its own. */
static size_t base64_end(const bs__vtu_doc *d, const bs__vtu_decl *a) {
  size_t end = d->app_len;
  for (int i = 0; i < d->n_arr; i++) {
    const bs__vtu_decl *b = &d->arr[i];
    if (b->format == BS__VTU_APPENDED && b->offset > a->offset && b->offset < end) end = (size_t)b->offset;
  }
  return end;
}

static int appended(const bs__vtu_doc *d, const bs__vtu_decl *a, uint64_t expect, const unsigned char **data,
                    unsigned char **owned, bs_error *err) {
  if (!d->app)
    return bs_error_set(err, BS_EINPUT, "format=\"appended\" but the file has no <AppendedData>");
  if (a->offset > d->app_len)
    return bs_error_set(err, BS_EINPUT, "offset %llu is past the end of the appended data (%zu bytes): truncated "
                        "file", (unsigned long long)a->offset, d->app_len);
  const size_t off = (size_t)a->offset;
  if (d->app_base64)
    return base64_block(d, (const char *)d->app + off, base64_end(d, a) - off, expect, data, owned, err);
  size_t used;
  return bs__vtu_block(d, d->app + off, d->app_len - off, expect, &used, data, owned, err);
}

int bs__vtu_array_bytes(const bs__vtu_doc *d, const bs__vtu_decl *a, uint64_t expect, const unsigned char **data,
                        unsigned char **owned, bs_error *err) {
  *data = NULL;
  *owned = NULL;
  const int sz = bs__vtu_type_size(a->type);
  int rc;
  if (a->format == BS__VTU_ASCII) {
    rc = bs__vtu_ascii_values(a->text ? a->text : "", a->text_len, a->type, expect / (uint64_t)sz, owned, err);
    *data = *owned;
    return rc; /* already in the machine's byte order */
  }
  if (a->format == BS__VTU_BINARY)
    rc = base64_block(d, a->text ? a->text : "", a->text_len, expect, data, owned, err);
  else
    rc = appended(d, a, expect, data, owned, err);
  if (rc || !d->swap || sz == 1) return rc;
  if (!*owned) { /* swap a copy, not the file's buffer */
    if (!(*owned = malloc((size_t)expect + 1))) {
      *data = NULL;
      return bs_error_set(err, BS_ENOMEM, "out of memory for %llu bytes", (unsigned long long)expect);
    }
    memcpy(*owned, *data, (size_t)expect);
  }
  bs__vtu_swap(*owned, (size_t)expect / (size_t)sz, sz);
  *data = *owned;
  return BS_OK;
}
