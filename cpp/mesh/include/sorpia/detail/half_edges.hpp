#pragma once
// The half-edges of a triangle or polygon list (a sorpia::Mesh's
// face_vertex_indices, with offsets from its face_vertex_counts), its corners
// bucketed by vertex (CornerBuckets, what Topology's build walks), the
// half-edge matcher of face lists that may be invalid (EdgeGroups) and a
// union-find, shared by the face checks (topology.cpp), repair and the
// non-manifold split (repair.cpp) and the statistics of a raw face list
// (mesh_statistics.cpp). Not a public header.
//
// Half-edge h (0 <= h < 3 n_faces) runs from the corner faces[h] to the next
// corner of its face, faces[next_corner(h)]; it also names that corner.
// FaceList extends this to polygons through face offsets.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/mesh.hpp"

namespace sorpia {
namespace detail {

inline std::size_t next_corner(std::size_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
inline std::size_t prev_corner(std::size_t h) { return h - h % 3 + (h % 3 + 2) % 3; }

// "face f (a, b, c)", for messages.
inline std::string face_str(std::size_t f, const std::int32_t* faces) {
  return "face " + std::to_string(f) + " (" + std::to_string(faces[3 * f]) + ", " +
         std::to_string(faces[3 * f + 1]) + ", " + std::to_string(faces[3 * f + 2]) + ")";
}

// A list of triangles or polygons: face f is idx[begin(f) .. end(f)).
// Corner h (0 <= h < n_corners()) is also the half-edge from idx[h] to the
// next corner of its face. `off` (n_faces + 1 offsets) and `corner_face` (the
// face of each corner) are given for polygons; triangles need neither (3 f,
// h / 3, next_corner).
struct FaceList {
  const std::int32_t* idx;
  const std::int32_t* off;          // nullptr for triangles (3 f)
  const std::int32_t* corner_face;  // nullptr for triangles
  std::size_t n_faces;

  bool triangles() const { return corner_face == nullptr; }
  std::int32_t begin(std::size_t f) const { return off ? off[f] : static_cast<std::int32_t>(3 * f); }
  std::int32_t end(std::size_t f) const { return begin(f + 1); }
  std::size_t n_corners() const { return static_cast<std::size_t>(begin(n_faces)); }
  std::int32_t face_of(std::size_t h) const {
    return corner_face ? corner_face[h] : static_cast<std::int32_t>(h / 3);
  }
  std::size_t next(std::size_t h) const {
    if (!corner_face) return next_corner(h);
    const std::int32_t f = corner_face[h];
    return h + 1 == static_cast<std::size_t>(end(f)) ? static_cast<std::size_t>(begin(f)) : h + 1;
  }
  std::size_t prev(std::size_t h) const {
    if (!corner_face) return prev_corner(h);
    const std::int32_t f = corner_face[h];
    return h == static_cast<std::size_t>(begin(f)) ? static_cast<std::size_t>(end(f)) - 1 : h - 1;
  }
  // Whether the faces of corners a and b, at one vertex, have the same
  // vertices in the same cyclic order, b's face walked backwards when
  // `reversed`.
  bool same_cycle(std::size_t a, std::size_t b, bool reversed) const {
    const std::int32_t fa = face_of(a), fb = face_of(b), n = end(fa) - begin(fa);
    if (n != end(fb) - begin(fb)) return false;
    for (std::int32_t i = 0; i < n; ++i, a = next(a), b = reversed ? prev(b) : next(b))
      if (idx[a] != idx[b]) return false;
    return true;
  }
  // Whether the faces of half-edges g and h, which lie on one edge, have the
  // same vertices in the same cyclic order, either way round (duplicate
  // faces): for triangles, the same third vertex.
  bool same_face(std::size_t g, std::size_t h) const {
    if (triangles()) return idx[prev(g)] == idx[prev(h)];
    const bool forward = idx[g] == idx[h];
    return same_cycle(g, forward ? h : next(h), !forward);
  }
  // "face f (a, b, c, ...)", for messages.
  std::string str(std::size_t f) const {
    std::string s = "face " + std::to_string(f) + " (";
    for (std::int32_t h = begin(f); h < end(f); ++h) s += (h > begin(f) ? ", " : "") + std::to_string(idx[h]);
    return s + ")";
  }
};

// The offsets of polygons from their counts; every count at least 3 and the
// total within int32.
inline std::vector<std::int32_t> polygon_offsets(const std::int32_t* counts, std::size_t n_faces) {
  std::vector<std::int32_t> off(n_faces + 1);
  std::int64_t total = 0;
  for (std::size_t f = 0; f < n_faces; ++f) {
    off[f] = static_cast<std::int32_t>(total);
    if (counts[f] < 3)
      throw MeshError("face " + std::to_string(f) + " has " + std::to_string(counts[f]) +
                      " vertices: a face needs at least 3");
    total += counts[f];
    if (total > std::numeric_limits<std::int32_t>::max())
      throw MeshError("too many face vertices: faces 0.." + std::to_string(f) + " have more than 2^31 - 1 corners");
  }
  off[n_faces] = static_cast<std::int32_t>(total);
  return off;
}

// The offsets of n_faces faces of `face_size` corners each (a uniform
// sorpia::Mesh), the total within int32.
inline std::vector<std::int32_t> uniform_offsets(std::int32_t face_size, std::size_t n_faces) {
  if (static_cast<std::uint64_t>(face_size) * n_faces > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()))
    throw MeshError("too many face vertices: " + std::to_string(n_faces) + " faces of " + std::to_string(face_size) +
                    " have more than 2^31 - 1 corners");
  std::vector<std::int32_t> off(n_faces + 1);
  for (std::size_t f = 0; f <= n_faces; ++f) off[f] = static_cast<std::int32_t>(f) * face_size;
  return off;
}

// The number of faces of a sorpia::Mesh, its uniform form checked (face_size
// at least 3 and dividing the indices; counts are checked by polygon_offsets
// and check_counts_sum).
inline std::size_t mesh_face_count(const Mesh& m) {
  if (!m.uniform()) return m.face_vertex_counts.size();
  if (m.face_size < 3)
    throw MeshError("face_size is " + std::to_string(m.face_size) + ": a face needs at least 3 vertices");
  if (m.face_vertex_indices.size() % static_cast<std::size_t>(m.face_size) != 0)
    throw MeshError("face_vertex_indices has " + std::to_string(m.face_vertex_indices.size()) +
                    " entries, not a multiple of face_size " + std::to_string(m.face_size));
  return m.face_vertex_indices.size() / static_cast<std::size_t>(m.face_size);
}

// Offsets (polygon_offsets, uniform_offsets) that end at the number of indices given.
inline void check_counts_sum(const std::vector<std::int32_t>& off, std::size_t n_indices) {
  if (static_cast<std::size_t>(off.back()) != n_indices)
    throw MeshError("face_vertex_counts sum to " + std::to_string(off.back()) + " but face_vertex_indices has " +
                    std::to_string(n_indices) + " entries");
}

// The face of every corner of the faces with offsets `off` (FaceList::corner_face).
inline std::vector<std::int32_t> corner_faces(const std::vector<std::int32_t>& off) {
  std::vector<std::int32_t> face(static_cast<std::size_t>(off.back()));
  for (std::size_t f = 0; f + 1 < off.size(); ++f)
    std::fill(face.begin() + off[f], face.begin() + off[f + 1], static_cast<std::int32_t>(f));
  return face;
}

// The offsets and corner faces of a FaceList of polygons (none for triangles),
// owned: FaceArrays::over(indices) is the FaceList.
struct FaceArrays {
  std::size_t n_faces = 0;
  std::vector<std::int32_t> off, corner_face;

  static FaceArrays triangles(std::size_t n_faces) { return {n_faces, {}, {}}; }
  static FaceArrays polygons(const std::int32_t* counts, std::size_t n_faces) {
    FaceArrays a{n_faces, detail::polygon_offsets(counts, n_faces), {}};
    a.corner_face = detail::corner_faces(a.off);
    return a;
  }
  // The arrays of a sorpia::Mesh's faces (none for Mesh::all_triangles), its
  // form checked with sorpia::Topology's messages (mesh_face_count, polygon_offsets).
  static FaceArrays of(const Mesh& m) {
    const std::size_t n = mesh_face_count(m);
    if (m.all_triangles()) return triangles(n);
    if (!m.uniform()) {
      FaceArrays a = polygons(m.face_vertex_counts.data(), n);
      check_counts_sum(a.off, m.face_vertex_indices.size());
      return a;
    }
    FaceArrays a{n, uniform_offsets(m.face_size, n), {}};
    a.corner_face = detail::corner_faces(a.off);
    return a;
  }
  FaceList over(const std::int32_t* idx) const {
    return {idx, off.empty() ? nullptr : off.data(), corner_face.empty() ? nullptr : corner_face.data(), n_faces};
  }
  // The FaceList of the mesh these arrays were made `of`.
  FaceList over(const Mesh& m) const { return over(m.face_vertex_indices.data()); }
};

// Corner of a face (v, a, ..., b) at v, counter-clockwise: `next` = a, `prev` = b.
// Going clockwise round v, the ring passes b and then a: the step from
// neighbour x is to the `next` of the corner whose `prev` is x.
struct Corner {
  std::int32_t next;
  std::int32_t prev;
};

// The corners of a triangle list bucketed by vertex (a counting sort, linear
// time), in face order within a bucket: vertex v's corners are
// corners[start[v] .. start[v + 1]). Used by validate_faces (topology.cpp).
// `faces` must hold indices in [0, n_vertices); bucket_polygon_corners takes
// polygons (face f is indices[offsets[f] .. offsets[f + 1])) and also fills `ids`.
struct CornerBuckets {
  std::vector<std::int32_t> start;     // n_vertices + 1
  std::unique_ptr<Corner[]> corners;   // one per corner of every face
  std::unique_ptr<std::int32_t[]> ids; // polygons only: the index of each corner in the face list
};

inline CornerBuckets bucket_corners(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices) {
  CornerBuckets b;
  b.start.assign(n_vertices + 1, 0);
  for (std::size_t h = 0; h < 3 * n_faces; ++h) ++b.start[faces[h] + 1];
  for (std::size_t v = 0; v < n_vertices; ++v) b.start[v + 1] += b.start[v];
  // Left uninitialised: the fill below writes every entry.
  b.corners.reset(new Corner[3 * n_faces]);
  std::vector<std::int32_t> fill(b.start.begin(), b.start.end() - 1);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    b.corners[fill[t[0]]++] = {t[1], t[2]};
    b.corners[fill[t[1]]++] = {t[2], t[0]};
    b.corners[fill[t[2]]++] = {t[0], t[1]};
  }
  return b;
}

inline CornerBuckets bucket_polygon_corners(const std::int32_t* indices, const std::int32_t* offsets, std::size_t n_faces,
                                     std::size_t n_vertices) {
  CornerBuckets b;
  const auto n_corners = static_cast<std::size_t>(offsets[n_faces]);
  b.start.assign(n_vertices + 1, 0);
  for (std::size_t h = 0; h < n_corners; ++h) ++b.start[indices[h] + 1];
  for (std::size_t v = 0; v < n_vertices; ++v) b.start[v + 1] += b.start[v];
  b.corners.reset(new Corner[n_corners]);
  b.ids.reset(new std::int32_t[n_corners]);
  std::vector<std::int32_t> fill(b.start.begin(), b.start.end() - 1);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t lo = offsets[f], hi = offsets[f + 1];
    for (std::int32_t h = lo; h < hi; ++h) {
      const std::int32_t at = fill[indices[h]]++;
      b.corners[at] = {indices[h + 1 == hi ? lo : h + 1], indices[h == lo ? hi - 1 : h - 1]};
      b.ids[at] = h;
    }
  }
  return b;
}

// The half-edge matcher: the half-edges of a face list grouped by
// undirected edge, in (lower end, higher end, id) order, so that the
// half-edges of one edge are adjacent, in face order. A counting sort by the
// lower end, then each bucket (the edges at one vertex towards higher
// vertices: few) sorted by (higher end, id). Linear in the half-edges but for
// those small sorts. `keep(h)` leaves out half-edges (of removed or
// degenerate faces). Topology's error paths, repair, the non-manifold split
// and the statistics of a raw face list all match edges through it, in that
// order, as often as they need. Topology's one-ring build instead matches each
// vertex's edges (both ends, no order) while it walks the vertex's fan
// (topology.cpp's VertexEdges over CornerBuckets): one pass without sorts or a
// stored grouping, cheaper than this grouping alone.
template <class Faces>
class EdgeGroups {
 public:
  template <class Keep>
  EdgeGroups(const Faces& fl, std::size_t n_vertices, Keep keep) : fl_(fl), start_(n_vertices + 1, 0) {
    const std::size_t n_half = fl.n_corners();
    for (std::size_t h = 0; h < n_half; ++h)
      if (keep(h)) ++start_[lo(h) + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    order_.resize(static_cast<std::size_t>(start_[n_vertices]));
    std::vector<std::int32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t h = 0; h < n_half; ++h)
      if (keep(h)) order_[fill[lo(h)]++] = static_cast<std::int32_t>(h);
    // Each bucket by (higher end, id), compared as one integer.
    std::vector<std::uint64_t> key;
    for (std::size_t v = 0; v < n_vertices; ++v) {
      std::int32_t* b = order_.data() + start_[v];
      const std::size_t k = static_cast<std::size_t>(start_[v + 1] - start_[v]);
      if (k < 2) continue;
      key.resize(k);
      for (std::size_t i = 0; i < k; ++i)
        key[i] = static_cast<std::uint64_t>(hi(b[i])) << 32 | static_cast<std::uint32_t>(b[i]);
      std::sort(key.begin(), key.end());
      for (std::size_t i = 0; i < k; ++i) b[i] = static_cast<std::int32_t>(key[i] & 0xffffffffu);
    }
  }
  EdgeGroups(const Faces& fl, std::size_t n_vertices)
      : EdgeGroups(fl, n_vertices, [](std::size_t) { return true; }) {}

  // Calls fn(a, b, hs, k) for every edge (a < b) in (a, b) order, hs its k
  // half-edges in id order.
  template <class Fn>
  void for_each(Fn fn) const {
    for (std::size_t v = 0; v + 1 < start_.size(); ++v)
      for (std::int32_t i = start_[v], j, end = start_[v + 1]; i < end; i = j) {
        const std::int32_t b = hi(order_[i]);
        for (j = i + 1; j < end && hi(order_[j]) == b; ++j) {
        }
        fn(static_cast<std::int32_t>(v), b, order_.data() + i, j - i);
      }
  }

  // The other half-edge of each half-edge's edge where the edge has exactly
  // two (kept) half-edges; `single` where it has one, `many` where more
  // (and for the half-edges left out).
  std::vector<std::int32_t> mates(std::int32_t single = -1, std::int32_t many = -1) const {
    std::vector<std::int32_t> mate(fl_.n_corners(), many);
    for_each([&](std::int32_t, std::int32_t, const std::int32_t* hs, std::int32_t k) {
      if (k == 1) mate[hs[0]] = single;
      if (k != 2) return;
      mate[hs[0]] = hs[1];
      mate[hs[1]] = hs[0];
    });
    return mate;
  }

 private:
  std::int32_t lo(std::size_t h) const { return std::min(fl_.idx[h], fl_.idx[fl_.next(h)]); }
  std::int32_t hi(std::size_t h) const { return std::max(fl_.idx[h], fl_.idx[fl_.next(h)]); }

  Faces fl_;                         // a FaceList, or a type with the same members (repair's Faces<kPolygons>)
  std::vector<std::int32_t> start_;  // the kept half-edges of lower end v: order_[start_[v] .. start_[v + 1])
  std::vector<std::int32_t> order_;  // sorted by (higher end, id) within each lower end
};

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
