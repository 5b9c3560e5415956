#include "one_ring.hpp"

#include <stdexcept>
#include <string>

#include "sorpia/errors.hpp"

namespace sorpia::detail {

void refuse_second_fan(std::size_t v, int n_faces) {
  throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(n_faces) +
                  " faces form more than one fan (a 'bowtie'); split it into one vertex per fan");
}

CornerBuckets bucket_corners(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices) {
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

namespace {
// Scratch per neighbour id, stamped with the vertex whose fan is being
// chained, so that it is never cleared: `prev_of == v` says some corner of v
// has prev x (corner `corner`), `next_of == v` that some corner has next x.
// Neighbour ids are near v in a mesh with any index locality: cache hits.
struct Slot {
  std::int32_t prev_of = -1, corner = 0, next_of = -1;
};
}  // namespace

OneRing one_ring_direct(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices,
                        std::size_t n_edges) {
  OneRing r;
  const CornerBuckets buckets = bucket_corners(faces, n_faces, n_vertices);
  const std::vector<std::int32_t>& start = buckets.start;
  r.face_count.resize(n_vertices);
  for (std::size_t v = 0; v < n_vertices; ++v) r.face_count[v] = start[v + 1] - start[v];

  r.offsets.resize(n_vertices + 1);
  r.boundary.assign(n_vertices, 0);
  std::vector<Slot> slots(n_vertices);
  r.neighbors.resize(2 * n_edges);
  std::size_t out = 0;
  for (std::size_t v = 0; v < n_vertices; ++v) {
    r.offsets[v] = static_cast<std::int32_t>(out);
    const int k = r.face_count[v];
    if (k == 0) {
      ++r.n_unreferenced;
      continue;
    }
    const Corner* c = buckets.corners.get() + start[v];
    const auto vv = static_cast<std::int32_t>(v);
    for (int i = 0; i < k; ++i) {
      slots[c[i].prev].prev_of = vv;
      slots[c[i].prev].corner = i;
      slots[c[i].next].next_of = vv;
    }
    // A boundary vertex has exactly one corner whose `prev` is no corner's
    // `next` (the far end of its outgoing boundary edge): start there.
    std::int32_t first = c[0].next;  // interior: the lowest-numbered face's second corner
    for (int i = 0; i < k; ++i)
      if (slots[c[i].prev].next_of != vv) {
        first = c[i].prev;
        r.boundary[v] = 1;
        break;
      }
    if (out + k + r.boundary[v] > r.neighbors.size()) refuse_second_fan(v, k);
    std::int32_t x = first;
    int faces_seen = 0;
    for (;;) {
      r.neighbors[out++] = x;
      if (slots[x].prev_of != vv) break;  // the other boundary neighbour
      ++faces_seen;
      x = c[slots[x].corner].next;
      if (x == first || faces_seen > k) break;  // back round an interior vertex
    }
    if (faces_seen != k) refuse_second_fan(v, k);
  }
  if (out != r.neighbors.size())  // n_edges did not come from these faces
    throw std::logic_error("sorpia: one-ring size " + std::to_string(out) + " != 2 x " + std::to_string(n_edges) +
                           " edges");
  r.offsets[n_vertices] = static_cast<std::int32_t>(out);
  return r;
}

}  // namespace sorpia::detail
