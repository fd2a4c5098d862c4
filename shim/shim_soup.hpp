// shim_soup.hpp — the polygon soup of a surface file, shared by the shim's
// readers (not public API; C++ only).
//
// shim_off.cpp: read_off_soup reads OFF text itself (CGAL's OFF scanner
// overflows on huge numbers and sizes its arrays from the header's counts).
// shim_surface_check.cpp: check_stl / check_ply validate a binary STL's
// triangle count and a PLY header's element counts against the file's size
// before CGAL reads them. All return BS_OK or fill err (BS_EINPUT / BS_EIO /
// BS_ENOMEM) naming the file and, for text, the line.
#ifndef BS_SHIM_SOUP_HPP
#define BS_SHIM_SOUP_HPP

#include <CGAL/Simple_cartesian.h>

#include <cstddef>
#include <string>
#include <vector>

#include "bs_shim.h"

namespace bs_shim {

typedef CGAL::Simple_cartesian<double> Kernel;
typedef Kernel::Point_3 Point;
typedef std::vector<std::size_t> Polygon;

// The whole file into bytes (BS_EIO when it cannot be read).
int read_bytes(const char *path, std::string &bytes, bs_error *err);

int read_off_soup(const char *path, std::vector<Point> &points, std::vector<Polygon> &polygons, bs_error *err);

int check_stl(const char *path, const std::string &bytes, bs_error *err);
int check_ply(const char *path, const std::string &bytes, bs_error *err);

} // namespace bs_shim

#endif
