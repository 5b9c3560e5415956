#pragma once
/// @file subface_grid.hpp
/// Where the quad sub-faces of a Catmull-Clark k-gon (k != 4) lie in the
/// face's (u, v): the layout of OpenSubdiv Bfr's QUAD_SUBFACES
/// parameterisation (surface.hpp), the one definition that surface
/// evaluation, the fairness quadrature, the footpoint search and Python's
/// sorpia.surface (through the binding) use. tests/cpp/test_surface.cpp
/// compares it with Bfr::Parameterization for k = 3..64.

#include <string>

#include "sorpia/errors.hpp"

namespace sorpia {

/// The integer square root, floor(sqrt(n)) for n >= 0, exact (no floating point).
constexpr int isqrt(int n) {
  int r = 0;
  while ((r + 1) * (r + 1) <= n) ++r;
  return r;
}

/// Columns w of the grid of sub-faces of a k-gon: sub-face j is the square
/// [x_j, x_j + 1/2] x [y_j, y_j + 1/2] at (x_j, y_j) = (j mod w, j div w), its
/// corner (x_j, y_j) the face's corner j, (x_j + 1/2, y_j) the midpoint of
/// edge j (corner j to j + 1), (x_j, y_j + 1/2) that of edge j - 1, and
/// (x_j + 1/2, y_j + 1/2) the face's centre. w = 2 for k < 5, 3 for k = 5..9,
/// 1 + floor(sqrt(k - 1)) from k = 10.
/// @throws ParameterError for k < 3
inline int subface_columns(int face_size) {
  if (face_size < 3)
    throw ParameterError("face_size must be at least 3, got " + std::to_string(face_size));
  if (face_size < 5) return 2;
  if (face_size < 10) return 3;
  return 1 + isqrt(face_size - 1);
}

/// (x_j, y_j): the corner of sub-face j in the grid of `columns` columns
/// (subface_columns), which is the face's corner j.
inline void subface_origin(int columns, int j, double uv[2]) {
  uv[0] = static_cast<double>(j % columns);
  uv[1] = static_cast<double>(j / columns);
}

}  // namespace sorpia
