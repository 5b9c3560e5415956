#pragma once
// The element classes of fairness_matrix (fairness.cpp): which faces share
// one element matrix (FairnessQuadrature::reuse), over which control points.
// Internal to the fit layer.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/surface.hpp"

namespace sorpia::fairness_detail {

// K as a sum of element matrices, one per face that is not a hole: a dense
// symmetric matrix over the face's columns (the vertices its stencils
// reach). Faces grouped into one class (FairnessQuadrature::reuse) share one
// matrix over their own control points (topology_control_points' order or
// Bfr's); every other face is a class of its own, its matrix over its own
// sorted columns.
struct Elements {
  FaceControlPoints cps;                     // of the non-hole faces, in face order (with reuse)
  std::vector<std::int64_t> slot;            // per face, its place in cps; -1 for a hole
  std::vector<std::int32_t> face_class;      // per face, its class; -1 for a hole
  std::vector<std::int32_t> representative;  // per class, the face integrated for it
  std::vector<std::uint8_t> shared;          // per class: 1 when its faces use their control points as columns
  std::vector<std::vector<std::int32_t>> own_columns;  // per class of one face: its sorted columns
  std::vector<std::vector<double>> element;  // per class, n x n (n its faces' column count), row-major

  bool live(std::size_t f) const { return face_class[f] >= 0; }
  const std::int32_t* columns(std::size_t f) const {
    const auto c = static_cast<std::size_t>(face_class[f]);
    return shared[c] ? cps.indices.data() + cps.offsets[static_cast<std::size_t>(slot[f])] : own_columns[c].data();
  }
  std::size_t n_columns(std::size_t f) const {
    const auto c = static_cast<std::size_t>(face_class[f]);
    if (!shared[c]) return own_columns[c].size();
    const auto s = static_cast<std::size_t>(slot[f]);
    return static_cast<std::size_t>(cps.offsets[s + 1] - cps.offsets[s]);
  }
};

// The classes of faces. With reuse, by local topology; the key: the number of
// control points, Bfr's IsRegular() (2 for a list from the topology), the
// face's size, and per corner (from corner 0) its valence, whether it is on the
// boundary and, there, the place of the next corner in its ring (where the face
// lies in the fan; inside, Bfr lists the control points from the face, so the
// place does not matter), and where the list names a vertex again (rings
// that wrap around and meet beyond the face), the places of the repeats and of
// their first listings: the element matrix is over the first listings, zero
// at the repeats. Faces whose control points touch a tag, a hole or a face of
// irregular size (their surface depends on more than the key says), and every
// face without reuse, are classes of their own.
Elements face_classes(const LimitSurface& surface, const std::vector<std::uint8_t>& hole, bool reuse);

}  // namespace sorpia::fairness_detail
