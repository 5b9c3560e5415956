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

CornerBuckets bucket_polygon_corners(const std::int32_t* indices, const std::int32_t* offsets, std::size_t n_faces,
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

}  // namespace sorpia::detail
