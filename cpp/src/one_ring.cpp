#include "one_ring.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "sorpia/errors.hpp"

namespace sorpia::detail {

namespace {
// Corner of a triangle (v, a, b) at v, counter-clockwise: `next` = a, `prev` = b.
// Going clockwise round v, the ring passes b and then a: the step from
// neighbour x is to the `next` of the corner whose `prev` is x.
struct Corner {
  std::int32_t next;
  std::int32_t prev;
};

// Index in [lo, hi) of the corner whose `prev` is x, or -1. Valences are small
// (3..12 on most meshes): a linear scan; poles of high valence use a sorted copy.
struct PrevLookup {
  const Corner* c;
  int k;
  std::vector<std::pair<std::int32_t, std::int32_t>> sorted;  // (prev, corner) for k > kLinear
  std::vector<std::int32_t> nexts;                            // sorted, for k > kLinear
  static constexpr int kLinear = 24;
  PrevLookup(const Corner* corners, int count) : c(corners), k(count) {
    if (k <= kLinear) return;
    sorted.resize(k);
    nexts.resize(k);
    for (int i = 0; i < k; ++i) {
      sorted[i] = {c[i].prev, i};
      nexts[i] = c[i].next;
    }
    std::sort(sorted.begin(), sorted.end());
    std::sort(nexts.begin(), nexts.end());
  }
  int find(std::int32_t x) const {
    if (k <= kLinear) {
      for (int i = 0; i < k; ++i)
        if (c[i].prev == x) return i;
      return -1;
    }
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(x, std::int32_t{-1}));
    return it != sorted.end() && it->first == x ? it->second : -1;
  }
  bool is_next(std::int32_t x) const {  // does some corner have next == x?
    if (k > kLinear) return std::binary_search(nexts.begin(), nexts.end(), x);
    for (int i = 0; i < k; ++i)
      if (c[i].next == x) return true;
    return false;
  }
};
}  // namespace

OneRing one_ring_direct(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices,
                        std::size_t n_edges) {
  OneRing r;
  // Corners bucketed by vertex, in face order within a bucket.
  std::vector<std::int32_t> start(n_vertices + 1, 0);
  for (std::size_t h = 0; h < 3 * n_faces; ++h) ++start[faces[h] + 1];
  r.face_count.resize(n_vertices);
  for (std::size_t v = 0; v < n_vertices; ++v) {
    r.face_count[v] = start[v + 1];
    start[v + 1] += start[v];
  }
  std::vector<Corner> corners(3 * n_faces);
  {
    std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < n_faces; ++f) {
      const std::int32_t* t = faces + 3 * f;
      corners[fill[t[0]]++] = {t[1], t[2]};
      corners[fill[t[1]]++] = {t[2], t[0]};
      corners[fill[t[2]]++] = {t[0], t[1]};
    }
  }

  r.offsets.resize(n_vertices + 1);
  r.boundary.assign(n_vertices, 0);
  r.neighbors.resize(2 * n_edges);
  std::size_t out = 0;
  for (std::size_t v = 0; v < n_vertices; ++v) {
    r.offsets[v] = static_cast<std::int32_t>(out);
    const int k = r.face_count[v];
    if (k == 0) {
      ++r.n_unreferenced;
      continue;
    }
    const Corner* c = corners.data() + start[v];
    const PrevLookup lookup(c, k);
    // A boundary vertex has exactly one corner whose `prev` is no corner's
    // `next` (the far end of its outgoing boundary edge): start there.
    std::int32_t first = c[0].next;  // interior: the lowest-numbered face's second corner
    for (int i = 0; i < k; ++i)
      if (!lookup.is_next(c[i].prev)) {
        first = c[i].prev;
        r.boundary[v] = 1;
        break;
      }
    if (out + k + r.boundary[v] > r.neighbors.size())
      throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(k) +
                      " faces form more than one fan (a 'bowtie'); split it into one vertex per fan");
    std::int32_t x = first;
    int faces_seen = 0;
    for (;;) {
      r.neighbors[out++] = x;
      const int i = lookup.find(x);
      if (i < 0) break;  // the other boundary neighbour
      ++faces_seen;
      x = c[i].next;
      if (x == first || faces_seen > k) break;  // back round an interior vertex
    }
    if (faces_seen != k)
      throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(k) +
                      " faces form more than one fan (a 'bowtie'); split it into one vertex per fan");
  }
  if (out != r.neighbors.size())  // n_edges did not come from these faces
    throw std::logic_error("sorpia: one-ring size " + std::to_string(out) + " != 2 x " + std::to_string(n_edges) +
                           " edges");
  r.offsets[n_vertices] = static_cast<std::int32_t>(out);
  return r;
}

}  // namespace sorpia::detail
