// Mesh statistics: two ways to the edges (a Topology's one-ring, or a sort of
// a raw face list's half-edges) into one EdgeCounts, counted by one finish().
#include "sorpia/mesh_statistics.hpp"

#include "sorpia/detail/half_edges.hpp"

#include <algorithm>
#include <numeric>
#include <string>
#include <utility>

namespace sorpia {

namespace {

using detail::DisjointSets;
using detail::next_corner;

// What both sources supply, per vertex and in all.
struct EdgeCounts {
  explicit EdgeCounts(std::size_t n) : valence(n), corners(n), boundary(n), component(n, -1) {}
  std::vector<std::int32_t> valence;    // edges at the vertex
  std::vector<std::int32_t> corners;    // faces at the vertex
  std::vector<std::uint8_t> boundary;   // on an edge of one face
  std::vector<std::int32_t> component;  // a label shared by the vertices joined by edges (< n)
  std::vector<std::int32_t> loop_vertex;  // one vertex of each boundary loop
  std::size_t n_edges = 0, n_boundary_edges = 0;
};

// `face_vertex`: one vertex of each face, to count the faces of each component
// (null: triangles, whose corners / 3 count them). `regular`: the scheme's.
MeshStatistics finish(EdgeCounts& c, std::size_t n_faces, bool oriented_manifold, const std::int32_t* face_vertex,
                      RegularValence regular) {
  const std::size_t n = c.valence.size();
  MeshStatistics s;
  s.n_vertices = n;
  s.n_faces = n_faces;
  s.n_edges = c.n_edges;
  s.n_boundary_edges = c.n_boundary_edges;
  s.n_boundary_loops = c.loop_vertex.size();
  // Per component: referenced vertices, edge ends, face corners, faces, boundary loops.
  struct Piece {
    std::int64_t vertices = 0, edge_ends = 0, corners = 0, faces = 0, loops = 0;
  };
  std::vector<std::int32_t> piece_of(n, -1);  // indexed by a component's label
  std::vector<Piece> pieces;
  std::size_t n_referenced = 0;
  int vmin = 0, vmax = 0;
  s.extraordinary.reserve(n);  // address space only: pages are touched as entries are added
  for (std::size_t v = 0; v < n; ++v) {
    if (c.corners[v] == 0) continue;  // unreferenced
    const int valence = c.valence[v];
    vmin = n_referenced ? std::min(vmin, valence) : valence;
    vmax = n_referenced ? std::max(vmax, valence) : valence;
    ++n_referenced;
    const std::int32_t root = c.component[v];
    if (piece_of[root] < 0) {
      piece_of[root] = static_cast<std::int32_t>(pieces.size());
      pieces.emplace_back();
    }
    Piece& p = pieces[piece_of[root]];
    ++p.vertices;
    p.edge_ends += valence;
    p.corners += c.corners[v];
    auto& histogram = c.boundary[v] ? s.boundary_valences : s.interior_valences;
    if (histogram.size() <= static_cast<std::size_t>(valence)) histogram.resize(valence + 1);
    ++histogram[valence];
    if (valence != (c.boundary[v] ? regular.boundary : regular.interior))
      s.extraordinary.push_back({static_cast<std::int32_t>(v), valence, c.boundary[v] != 0});
  }
  for (const std::int32_t v : c.loop_vertex) ++pieces[piece_of[c.component[v]]].loops;
  if (face_vertex)
    for (std::size_t f = 0; f < n_faces; ++f) ++pieces[piece_of[c.component[face_vertex[f]]]].faces;
  else
    for (Piece& p : pieces) p.faces = p.corners / 3;
  s.n_components = pieces.size();
  s.n_unreferenced = n - n_referenced;
  s.valence_min = vmin;
  s.valence_max = vmax;
  s.euler_characteristic = static_cast<std::int64_t>(n_referenced) - static_cast<std::int64_t>(c.n_edges) +
                           static_cast<std::int64_t>(n_faces);
  if (oriented_manifold) {
    // chi_c = 2 - 2 g_c - b_c on each connected orientable surface.
    std::int64_t genus = 0;
    for (const Piece& p : pieces) {
      const std::int64_t chi = p.vertices - p.edge_ends / 2 + p.faces;
      const std::int64_t twice = 2 - chi - p.loops;
      genus += twice >= 0 ? twice / 2 : -((1 - twice) / 2);  // floor division
    }
    s.genus = genus;
  }
  return s;
}

// ---- the raw face list -------------------------------------------------------
// Over the half-edges of the face list (half_edges.hpp).

constexpr std::int32_t kBoundary = -1;  // mate of a half-edge whose edge has one face
constexpr std::int32_t kNoFan = -2;     // an edge of three or more faces, or a half-edge of a degenerate face

// A face with a repeated vertex has no edges of its own: its half-edges are left out.
inline bool degenerate_face(const std::int32_t* f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }

// The boundary half-edge that follows boundary half-edge h round its loop:
// from h's end vertex v, across the faces of h's fan at v (each step from the
// half-edge leaving v in a face to its mate's face), until a half-edge leaving
// v is on the boundary. -1 when the fan cannot be followed.
std::int32_t next_on_boundary(const std::int32_t* faces, const std::vector<std::int32_t>& mate, std::int32_t h,
                              std::int32_t fan_size) {
  std::size_t g = next_corner(h);  // leaves v in h's face
  for (std::int32_t step = 0; step <= fan_size; ++step) {
    if (mate[g] == kBoundary) return static_cast<std::int32_t>(g);
    if (mate[g] == kNoFan) return -1;
    const std::size_t m = static_cast<std::size_t>(mate[g]);
    if (faces[m] != faces[next_corner(g)]) return -1;  // both faces run the edge the same way
    g = next_corner(m);
  }
  return -1;
}

// Boundary loops of a raw face list into c.loop_vertex: the cycles of
// next_on_boundary where it is a one-to-one map of the boundary half-edges,
// else the connected pieces of the boundary edges.
void count_loops(const std::int32_t* faces, std::size_t n_half, const std::vector<std::int32_t>& mate,
                 EdgeCounts& c) {
  std::vector<std::int32_t> next(n_half, -1);
  std::vector<std::uint8_t> reached(n_half, 0);
  bool followed = true;
  for (std::size_t h = 0; h < n_half && followed; ++h) {
    if (mate[h] != kBoundary) continue;
    const std::int32_t g = next_on_boundary(faces, mate, static_cast<std::int32_t>(h),
                                            c.corners[faces[next_corner(h)]]);
    followed = g >= 0 && !reached[g];
    if (followed) next[h] = g, reached[g] = 1;
  }
  if (followed) {
    std::fill(reached.begin(), reached.end(), 0);
    for (std::size_t h = 0; h < n_half; ++h) {
      if (mate[h] != kBoundary || reached[h]) continue;
      c.loop_vertex.push_back(faces[h]);
      for (std::int32_t g = static_cast<std::int32_t>(h); !reached[g]; g = next[g]) reached[g] = 1;
    }
    return;
  }
  const std::size_t n = c.valence.size();
  DisjointSets pieces(n);
  for (std::size_t h = 0; h < n_half; ++h)
    if (mate[h] == kBoundary) pieces.unite(faces[h], faces[next_corner(h)]);
  for (std::size_t v = 0; v < n; ++v)
    if (c.boundary[v] && pieces.find(static_cast<std::int32_t>(v)) == static_cast<std::int32_t>(v))
      c.loop_vertex.push_back(static_cast<std::int32_t>(v));
}

}  // namespace

RegularValence regular_valence(Scheme scheme) {
  return scheme == Scheme::CatmullClark ? RegularValence{4, 3}
                                        : RegularValence{regular_interior_valence, regular_boundary_valence};
}

MeshStatistics mesh_statistics(const Topology& topology, Scheme scheme) {
  const std::size_t n = topology.n_vertices();
  const auto& offsets = topology.ring_offsets();
  const auto& ring = topology.ring_neighbors();
  EdgeCounts c(n);
  c.n_edges = topology.n_edges();
  c.n_boundary_edges = topology.n_boundary_edges();
  for (std::size_t v = 0; v < n; ++v) {
    c.valence[v] = topology.valence(v);
    c.corners[v] = topology.face_count(v);
    c.boundary[v] = topology.is_boundary(v);
  }
  // Components: breadth-first over the ring, labelled by their first vertex.
  std::vector<std::int32_t> queue(n);
  for (std::size_t v0 = 0; v0 < n; ++v0) {
    if (c.component[v0] >= 0) continue;
    const auto label = static_cast<std::int32_t>(v0);
    std::size_t head = 0, tail = 0;
    queue[tail++] = label;
    c.component[v0] = label;
    while (head < tail) {
      const std::int32_t v = queue[head++];
      for (std::int32_t q = offsets[v]; q < offsets[v + 1]; ++q)
        if (c.component[ring[q]] < 0) c.component[ring[q]] = label, queue[tail++] = ring[q];
    }
  }
  // A validated mesh has two boundary edges at each boundary vertex, to the
  // first and the last of its ring: every boundary piece is one loop.
  std::vector<std::uint8_t> walked(n, 0);
  for (std::size_t v0 = 0; v0 < n; ++v0) {
    if (!c.boundary[v0] || walked[v0]) continue;
    c.loop_vertex.push_back(static_cast<std::int32_t>(v0));
    std::int32_t prev = -1, v = static_cast<std::int32_t>(v0);
    while (!walked[v]) {
      walked[v] = 1;
      const std::int32_t first = ring[offsets[v]], last = ring[offsets[v + 1] - 1];
      const std::int32_t next = first != prev ? first : last;
      prev = v;
      v = next;
    }
  }
  std::vector<std::int32_t> face_vertex(topology.n_faces());
  for (std::size_t f = 0; f < face_vertex.size(); ++f)
    face_vertex[f] = topology.face_indices()[static_cast<std::size_t>(topology.face_offset(f))];
  return finish(c, topology.n_faces(), true, face_vertex.data(), regular_valence(scheme));
}

std::optional<MeshStatistics> face_list_statistics(const Mesh& mesh, std::size_t n_vertices) {
  if (!mesh.all_triangles())
    throw MeshError("face_list_statistics counts a triangle list (a sorpia::Mesh without face_vertex_counts, "
                    "face_size 3); this mesh has " +
                    std::string(mesh.uniform() ? "face_size " + std::to_string(mesh.face_size) : "face_vertex_counts"));
  const std::size_t n_faces = detail::mesh_face_count(mesh);
  const std::int32_t* faces = mesh.face_vertex_indices.data();
  const std::size_t n_half = 3 * n_faces;
  if (n_faces == 0) return std::nullopt;
  for (std::size_t h = 0; h < n_half; ++h)
    if (faces[h] < 0 || static_cast<std::size_t>(faces[h]) >= n_vertices) return std::nullopt;
  EdgeCounts c(n_vertices);
  for (std::size_t h = 0; h < n_half; ++h) ++c.corners[faces[h]];
  const detail::FaceList fl{faces, nullptr, nullptr, n_faces};
  const detail::EdgeGroups edges(fl, n_vertices,
                                 [&](std::size_t h) { return !degenerate_face(faces + (h - h % 3)); });
  std::vector<std::int32_t> mate = edges.mates(kBoundary, kNoFan);
  DisjointSets components(n_vertices);
  edges.for_each([&](std::int32_t a, std::int32_t b, const std::int32_t*, std::int32_t k) {
    ++c.n_edges;
    ++c.valence[a];
    ++c.valence[b];
    components.unite(a, b);
    if (k == 1) {
      ++c.n_boundary_edges;
      c.boundary[a] = c.boundary[b] = 1;
    }
  });
  for (std::size_t v = 0; v < n_vertices; ++v) c.component[v] = components.find(static_cast<std::int32_t>(v));
  count_loops(faces, n_half, mate, c);
  return finish(c, n_faces, false, nullptr, regular_valence(Scheme::Loop));
}

}  // namespace sorpia
