#pragma once
// The half-edges of a triangle list, and a union-find, shared by the face
// checks (topology.cpp), repair (repair.cpp) and the statistics of a raw face
// list (mesh_statistics.cpp). Not a public header.
//
// Half-edge h (0 <= h < 3 n_faces) runs from the corner faces[h] to the next
// corner of its face, faces[next_corner(h)]; it also names that corner.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

namespace sorpia {
namespace detail {

inline std::size_t next_corner(std::size_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
inline std::size_t prev_corner(std::size_t h) { return h - h % 3 + (h % 3 + 2) % 3; }

// "face f (a, b, c)", for messages.
inline std::string face_str(std::size_t f, const std::int32_t* faces) {
  return "face " + std::to_string(f) + " (" + std::to_string(faces[3 * f]) + ", " +
         std::to_string(faces[3 * f + 1]) + ", " + std::to_string(faces[3 * f + 2]) + ")";
}

// Union-find over indices 0..n-1 with path halving; the root of a class is its
// lowest index.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::int32_t find(std::int32_t v) {
    while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];
    return v;
  }
  void unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::int32_t> parent_;
};

}  // namespace detail
}  // namespace sorpia
