// shim_off.cpp — OFF text read into a polygon soup by bigstep itself
// (bs_shim::read_off_soup, see shim_soup.hpp).
//
// Why not CGAL's OFF reader (CGAL 5.5, Debian 12): its File_scanner_OFF reads
// facet sizes and vertex indices as doubles and converts them to size_t
// (UBSan: "1e+30 is outside the range of representable values of type
// 'unsigned long'" at File_scanner_OFF.h:718 for a facet size, :751 for an
// index such as 1e20 or -2), and a file "OFF 4 1 0 ... 1e30 0 1 2" is even
// read as a success; the reports add signed overflow in its header
// scanner and arrays reserved from a face count of 1e30.
//
// Accepted: an optional header keyword [ST][C][N]OFF (3-D; "4OFF", "nOFF" and
// "OFF BINARY" are errors), the counts "nv nf [ne]" (on the header line or the
// next), nv vertex lines whose first three numbers are the coordinates
// (finite; the rest of the line, normals or colours, is ignored) and nf face
// lines "k i1 .. ik [colour]" with 3 <= k <= BS_MAX_POLYGON_VERTICES and
// 0 <= i < nv. '#' starts a comment; blank lines are skipped; text after the
// last face is ignored. The counts are checked against bs_limits.h and
// against the bytes left (a vertex line takes at least 6 bytes, a face line
// 2) before anything is reserved.
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "bs_limits.h"
#include "shim_soup.hpp"

namespace bs_shim {
namespace {

struct off_in {
  const std::string &b;
  std::size_t pos, line;
  const char *path;
  bs_error *err;
  std::vector<std::string> tok; // the tokens of the current line
};

int bad(off_in &in, const char *what, const std::string &value) {
  return bs_error_set(in.err, BS_EINPUT, "%s: line %zu: %s%s%.40s%s", in.path, in.line, what,
                      value.empty() ? "" : " '", value.c_str(), value.empty() ? "" : "'");
}

// The next line with tokens (comments stripped) into in.tok: false at the end.
bool next_line(off_in &in) {
  while (in.pos < in.b.size()) {
    std::size_t e = in.b.find('\n', in.pos);
    if (e == std::string::npos) e = in.b.size();
    std::size_t hash = in.b.find('#', in.pos);
    std::size_t stop = (hash != std::string::npos && hash < e) ? hash : e;
    in.tok.clear();
    for (std::size_t i = in.pos; i < stop;) {
      while (i < stop && std::isspace((unsigned char)in.b[i])) i++;
      std::size_t s = i;
      while (i < stop && !std::isspace((unsigned char)in.b[i])) i++;
      if (i > s) in.tok.push_back(in.b.substr(s, i - s));
    }
    in.line++;
    in.pos = e + 1;
    if (!in.tok.empty()) return true;
  }
  in.tok.clear();
  return false;
}

bool parse_int(const std::string &s, long long lo, long long hi, long long &out) {
  char *end = nullptr;
  errno = 0;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (errno || *end || end == s.c_str() || v < lo || v > hi) return false;
  out = v;
  return true;
}

bool parse_double(const std::string &s, double &out) {
  char *end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (*end || end == s.c_str() || !std::isfinite(v)) return false;
  out = v;
  return true;
}

// The header keyword (if any) and the counts nv, nf.
int header(off_in &in, long long &nv, long long &nf) {
  if (!next_line(in)) return bs_error_set(in.err, BS_EINPUT, "%s: empty OFF file", in.path);
  std::size_t first = 0;
  const std::string &h = in.tok[0];
  if (h.size() >= 3 && h.compare(h.size() - 3, 3, "OFF") == 0) {
    std::string pre = h.substr(0, h.size() - 3);
    if (pre.find('4') != std::string::npos || pre.find('n') != std::string::npos)
      return bad(in, "only 3-D OFF files are read, not", h);
    if (pre != "" && pre != "C" && pre != "N" && pre != "NC" && pre != "CN" && pre != "ST" && pre != "STC" &&
        pre != "STN" && pre != "STNC" && pre != "STCN")
      return bad(in, "unknown OFF header", h);
    if (in.tok.size() > 1 && in.tok[1] == "BINARY") return bad(in, "binary OFF is not read (save it as text)", "");
    first = 1;
    if (in.tok.size() == 1) { // the counts on the next line
      if (!next_line(in)) return bad(in, "the file ends before the counts", "");
      first = 0;
    }
  }
  if (in.tok.size() < first + 2) return bad(in, "expected the counts 'vertices faces [edges]'", "");
  if (!parse_int(in.tok[first], 0, BS_MAX_SURFACE_POINTS, nv))
    return bad(in, "the vertex count must be an integer in [0, 1e8] (bigstep's limit), not", in.tok[first]);
  if (!parse_int(in.tok[first + 1], 0, BS_MAX_SURFACE_FACES, nf))
    return bad(in, "the face count must be an integer in [0, 2e8] (bigstep's limit), not", in.tok[first + 1]);
  std::size_t rest = in.b.size() > in.pos ? in.b.size() - in.pos : 0;
  if ((unsigned long long)(6 * nv + 2 * nf) > rest)
    return bs_error_set(in.err, BS_EINPUT,
                        "%s: line %zu: %lld vertices and %lld faces cannot fit in the %zu bytes left in the file",
                        in.path, in.line, nv, nf, rest);
  return BS_OK;
}

int vertices(off_in &in, long long nv, std::vector<Point> &points) {
  points.reserve((std::size_t)nv);
  for (long long i = 0; i < nv; i++) {
    if (!next_line(in)) return bad(in, "the file ends before all the vertices", "");
    double x[3];
    if (in.tok.size() < 3) return bad(in, "a vertex needs 3 coordinates", "");
    for (int k = 0; k < 3; k++)
      if (!parse_double(in.tok[(std::size_t)k], x[k])) return bad(in, "a vertex coordinate must be a finite number, not", in.tok[(std::size_t)k]);
    points.push_back(Point(x[0], x[1], x[2]));
  }
  return BS_OK;
}

int faces(off_in &in, long long nv, long long nf, std::vector<Polygon> &polygons) {
  polygons.reserve((std::size_t)nf);
  for (long long f = 0; f < nf; f++) {
    if (!next_line(in)) return bad(in, "the file ends before all the faces", "");
    long long k, v;
    std::string face = "polygon " + std::to_string(f) + ": ";
    if (!parse_int(in.tok[0], 3, BS_MAX_POLYGON_VERTICES, k))
      return bad(in, (face + "its vertex count must be an integer in [3, 65536], not").c_str(), in.tok[0]);
    if ((long long)in.tok.size() < 1 + k)
      return bad(in, (face + "it lists fewer vertices than its count").c_str(), in.tok[0]);
    Polygon p((std::size_t)k);
    for (long long j = 0; j < k; j++) {
      if (!parse_int(in.tok[(std::size_t)(1 + j)], 0, nv - 1, v))
        return bad(in, (face + "a vertex index must be an integer in [0, vertices - 1], not").c_str(),
                   in.tok[(std::size_t)(1 + j)]);
      p[(std::size_t)j] = (std::size_t)v;
    }
    polygons.push_back(std::move(p));
  }
  return BS_OK;
}

} // namespace

int read_bytes(const char *path, std::string &bytes, bs_error *err) {
  std::FILE *f = std::fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "%s: cannot open the surface file", path);
  char buf[65536];
  std::size_t r;
  while ((r = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.append(buf, r);
  bool failed = std::ferror(f);
  std::fclose(f);
  return failed ? bs_error_set(err, BS_EIO, "%s: cannot read the surface file", path) : BS_OK;
}

int read_off_soup(const char *path, std::vector<Point> &points, std::vector<Polygon> &polygons, bs_error *err) {
  std::string bytes;
  int rc = read_bytes(path, bytes, err);
  if (rc) return rc;
  off_in in{bytes, 0, 0, path, err, {}};
  long long nv = 0, nf = 0;
  if ((rc = header(in, nv, nf))) return rc;
  if ((rc = vertices(in, nv, points))) return rc;
  return faces(in, nv, nf, polygons);
}

} // namespace bs_shim
