// shim_surface_check.cpp — STL and PLY files checked before CGAL reads them
// (see shim_soup.hpp).
//
// STL: a file of exactly 84 + 50 N bytes, N the little-endian count at byte
// 80, is binary; its 9 N vertex coordinates must be finite (CGAL's reader
// keys a std::map by the points, which a NaN breaks) and N at most
// BS_MAX_SURFACE_FACES. Any other file must start with the word "solid"
// (ASCII STL, whose numbers CGAL reads with operator>>, refusing NaN and
// overflow). PLY: the header must end with end_header; each element's count
// must fit in the bytes after the header (an item takes at least one byte
// per property in binary, two in ASCII: CGAL loops over the count, so a
// huge count in a short file would spin) and under bs_limits.h; a list's
// length type must be 8- or 16-bit (CGAL resizes a vector to the length it
// reads, so a 32-bit length of 4e9 would be a 32 GB allocation).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "bs_limits.h"
#include "shim_soup.hpp"

namespace bs_shim {

int check_stl(const char *path, const std::string &b, bs_error *err) {
  if (b.size() >= 84) {
    uint32_t n = 0;
    for (int i = 0; i < 4; i++) n |= (uint32_t)(unsigned char)b[80 + (std::size_t)i] << (8 * i);
    if (b.size() == 84 + 50 * (uint64_t)n) {
      if (n > BS_MAX_SURFACE_FACES)
        return bs_error_set(err, BS_EINPUT, "%s: %u triangles exceed bigstep's limit of %ld", path, n,
                            (long)BS_MAX_SURFACE_FACES);
      for (uint64_t t = 0; t < n; t++)
        for (int k = 3; k < 12; k++) {
          float f;
          std::memcpy(&f, b.data() + 84 + 50 * t + 4 * (uint64_t)k, 4);
          if (!std::isfinite(f))
            return bs_error_set(err, BS_EINPUT, "%s: triangle %llu has a non-finite vertex coordinate", path,
                                (unsigned long long)t);
        }
      return BS_OK;
    }
  }
  std::size_t i = 0;
  while (i < b.size() && std::isspace((unsigned char)b[i])) i++;
  if (b.compare(i, 5, "solid") == 0) return BS_OK;
  return bs_error_set(err, BS_EINPUT,
                      "%s: neither an ASCII STL (starting with 'solid') nor a binary STL (84 bytes and 50 per "
                      "triangle that its header counts): %zu bytes",
                      path, b.size());
}

namespace {

int ply_type_size(const std::string &t) {
  static const char *const names[] = {"char", "int8", "uchar", "uint8", "short", "int16", "ushort", "uint16",
                                      "int", "int32", "uint", "uint32", "float", "float32", "double", "float64"};
  static const int sizes[] = {1, 1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 4, 4, 4, 8, 8};
  for (int i = 0; i < 16; i++)
    if (t == names[i]) return sizes[i];
  return 0;
}

struct ply_element {
  std::string name;
  unsigned long long n;
  unsigned long long min_bytes; // per item
};

// One header line; appends to elems. The format is 1 (ASCII) or 0.
int ply_line(const char *path, std::size_t line, const std::string &text, int ascii, std::vector<ply_element> &elems,
             bs_error *err) {
  std::istringstream is(text);
  std::string w, a, b2, c;
  is >> w;
  if (w == "element") {
    if (!(is >> a >> b2) || b2.find_first_not_of("0123456789") != std::string::npos || b2.size() > 12)
      return bs_error_set(err, BS_EINPUT, "%s: line %zu: bad element line '%.60s'", path, line, text.c_str());
    unsigned long long n = std::stoull(b2);
    long limit = a == "vertex" ? BS_MAX_SURFACE_POINTS : BS_MAX_SURFACE_FACES;
    if (n > (unsigned long long)limit)
      return bs_error_set(err, BS_EINPUT, "%s: line %zu: %llu %s elements exceed bigstep's limit of %ld", path, line, n,
                          a.c_str(), limit);
    elems.push_back({a, n, 0});
  } else if (w == "property") {
    if (elems.empty()) return bs_error_set(err, BS_EINPUT, "%s: line %zu: a property before any element", path, line);
    if (!(is >> a)) return bs_error_set(err, BS_EINPUT, "%s: line %zu: bad property line", path, line);
    int size = 0;
    std::string name;
    if (a == "list") {
      if (!(is >> b2 >> c >> name) || (size = ply_type_size(b2)) == 0 || size > 2 || ply_type_size(c) == 0)
        return bs_error_set(err, BS_EINPUT,
                            "%s: line %zu: list property '%.60s': the length type must be an 8- or 16-bit integer", path,
                            line, text.c_str());
    } else if ((size = ply_type_size(a)) == 0 || !(is >> name)) {
      return bs_error_set(err, BS_EINPUT, "%s: line %zu: bad property '%.60s'", path, line, text.c_str());
    }
    /* CGAL reads a vertex's x, y, z as float or double without checking the
     * type: another type is a null dereference in PLY_reader.h (fuzzing). */
    const std::string &el = elems.back().name;
    bool coord = (el == "vertex" || el == "vertices") && (name == "x" || name == "y" || name == "z");
    if (coord && a != "float" && a != "float32" && a != "double" && a != "float64")
      return bs_error_set(err, BS_EINPUT, "%s: line %zu: vertex coordinate '%s' must be float or double, not '%.20s'",
                          path, line, name.c_str(), a.c_str());
    elems.back().min_bytes += ascii ? 2 : (unsigned long long)size;
  }
  return BS_OK;
}

} // namespace

int check_ply(const char *path, const std::string &b, bs_error *err) {
  std::size_t pos = 0, line = 0;
  int ascii = -1;
  std::vector<ply_element> elems;
  for (;;) {
    std::size_t e = b.find('\n', pos);
    if (e == std::string::npos) return bs_error_set(err, BS_EINPUT, "%s: the PLY header has no end_header", path);
    std::string text = b.substr(pos, e - pos);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    pos = e + 1;
    line++;
    if (line == 1 && text != "ply") return bs_error_set(err, BS_EINPUT, "%s: not a PLY file (no 'ply' line)", path);
    if (text.compare(0, 7, "format ") == 0) ascii = text.compare(7, 5, "ascii") == 0;
    if (text == "end_header") break;
    int rc = ply_line(path, line, text, ascii == 1, elems, err);
    if (rc) return rc;
  }
  if (ascii < 0) return bs_error_set(err, BS_EINPUT, "%s: the PLY header has no format line", path);
  long double need = 0;
  for (const ply_element &el : elems) need += (long double)el.n * (long double)el.min_bytes;
  if (need > (long double)(b.size() - pos))
    return bs_error_set(err, BS_EINPUT, "%s: the PLY header's element counts need at least %.0Lf bytes, %zu follow it",
                        path, need, b.size() - pos);
  return BS_OK;
}

} // namespace bs_shim
