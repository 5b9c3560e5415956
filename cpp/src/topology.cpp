#include "sorpia/topology.hpp"

#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <limits>
#include <mutex>
#include <numeric>
#include <string>
#include <tuple>
#include <utility>

#include "one_ring.hpp"
#include "openmesh_types.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {
namespace detail {
void silence_openmesh() {
  static std::once_flag once;
  std::call_once(once, [] {
    omlog().disable();
    omout().disable();
    omerr().disable();
  });
}
}  // namespace detail

namespace {

std::string face_str(std::size_t f, const std::int32_t* faces) {
  return "face " + std::to_string(f) + " (" + std::to_string(faces[3 * f]) + ", " +
         std::to_string(faces[3 * f + 1]) + ", " + std::to_string(faces[3 * f + 2]) + ")";
}

// ---- validate_faces and its helpers ----------------------------------------
// Half-edge h (0 <= h < 3 n_faces) of a face list runs from the corner
// faces[h] to the next corner of its face, faces[next_corner(h)].
namespace face_checks {

inline std::size_t next_corner(std::size_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
inline std::size_t prev_corner(std::size_t h) { return h - h % 3 + (h % 3 + 2) % 3; }

// Union-find over corners (path halving): corners of one vertex that end up in
// one set form one fan of faces around it.
struct DisjointSets {
  std::vector<std::int32_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t find(std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

std::string face_list(const std::vector<std::int32_t>& ids, std::size_t shown) {
  std::string s;
  for (std::size_t i = 0; i < ids.size() && i < shown; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  return ids.size() > shown ? s + ", ..." : s;
}

// Error path only. Two faces traverse an edge in the same direction: try to
// orient the connected component of face `start` by breadth-first search
// (`mate(h)` is the other half-edge of h's edge, or -1 on the boundary). Says
// which faces to reverse, or that no orientation exists (a Moebius strip).
template <class Mate>
std::string orientation_advice(const std::int32_t* faces, std::size_t n_faces, std::size_t start, Mate mate) {
  std::vector<std::int8_t> flip(n_faces, -1);
  std::vector<std::int32_t> component{static_cast<std::int32_t>(start)};
  flip[start] = 0;
  bool orientable = true;
  for (std::size_t q = 0; q < component.size(); ++q) {
    const std::int32_t f = component[q];
    for (std::int32_t h = 3 * f; h < 3 * f + 3; ++h) {
      const std::int32_t g = mate(h);
      if (g < 0) continue;
      // opposite traversal keeps the relative orientation, the same one swaps it
      const std::int8_t want = static_cast<std::int8_t>(flip[f] ^ (faces[h] == faces[g] ? 1 : 0));
      if (flip[g / 3] < 0) {
        flip[g / 3] = want;
        component.push_back(g / 3);
      } else if (flip[g / 3] != want) {
        orientable = false;
      }
    }
  }
  if (!orientable)
    return "the surface is not orientable (like a Moebius strip: no choice of face orientations is consistent), "
           "and Loop interpolation needs an orientable surface";
  std::vector<std::int32_t> ones, zeros;
  for (std::int32_t f : component) (flip[f] ? ones : zeros).push_back(f);
  std::vector<std::int32_t>& fewer = ones.size() <= zeros.size() ? ones : zeros;
  std::sort(fewer.begin(), fewer.end());
  return "reversing the vertex order of " + std::to_string(fewer.size()) + " of the " +
         std::to_string(component.size()) + " faces of this connected part makes it consistent (faces " +
         face_list(fewer, 8) + ")";
}

}  // namespace face_checks

// Checks what OpenMesh and OpenSubdiv would not (see DEPENDENCIES.md):
// indices in range and distinct (OpenMesh aborts on a repeated vertex), no
// duplicate faces, at most two faces per edge, consistent orientation (OpenMesh
// would fail add_face without saying why) and one fan of faces per vertex (a
// 'bowtie' is accepted by OpenMesh and quietly made a corner by OpenSubdiv).
// Throws MeshError naming the first offending face, edge or vertex.
// Half-edges are bucketed by their smaller vertex (a counting sort) and each
// bucket sorted by (other vertex, third vertex of the face): O(h log k) for h
// half-edges and at most k in a bucket, never quadratic at a high-valence vertex.
// Returns the number of edges and of boundary edges.
std::pair<std::size_t, std::size_t> validate_faces(const std::int32_t* faces, std::size_t n_faces,
                                                   std::size_t n_vertices) {
  using face_checks::next_corner;
  using face_checks::prev_corner;
  constexpr auto int_max = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  if (n_vertices > int_max)
    throw MeshError("too many vertices: " + std::to_string(n_vertices) + " (at most 2^31 - 1)");
  if (n_faces > int_max / 3)
    throw MeshError("too many faces: " + std::to_string(n_faces) + " (at most (2^31 - 1) / 3)");
  if (n_faces == 0) throw MeshError("the mesh has no faces: Loop subdivision needs at least one triangle");
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= n_vertices)
        throw MeshError(face_str(f, faces) + " has vertex index " + std::to_string(t[k]) + " out of range [0, " +
                        std::to_string(n_vertices) + ")");
    for (int k = 0; k < 3; ++k)
      if (t[k] == t[(k + 1) % 3])
        throw MeshError(face_str(f, faces) + " repeats vertex " + std::to_string(t[k]) +
                        " (a degenerate triangle): remove the face");
  }
  const std::size_t n_half = 3 * n_faces;
  auto tail = [&](std::int32_t h) { return faces[h]; };
  auto head = [&](std::int32_t h) { return faces[next_corner(h)]; };
  auto lo_end = [&](std::int32_t h) { return std::min(tail(h), head(h)); };
  auto hi_end = [&](std::int32_t h) { return std::max(tail(h), head(h)); };
  auto third = [&](std::int32_t h) { return faces[prev_corner(h)]; };

  std::vector<std::int32_t> start(n_vertices + 1, 0);
  for (std::size_t h = 0; h < n_half; ++h) ++start[lo_end(static_cast<std::int32_t>(h)) + 1];
  for (std::size_t v = 0; v < n_vertices; ++v) start[v + 1] += start[v];
  std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
  std::vector<std::int32_t> bucket(n_half);
  for (std::size_t h = 0; h < n_half; ++h) {
    const auto hh = static_cast<std::int32_t>(h);
    bucket[fill[lo_end(hh)]++] = hh;
  }
  // Sorted by (other end, third vertex, id): the half-edges of one edge are
  // adjacent, and two faces with the same three vertices are next to each other.
  auto key = [&](std::int32_t h) { return std::make_tuple(hi_end(h), third(h), h); };
  for (std::size_t v = 0; v < n_vertices; ++v)
    std::sort(bucket.begin() + start[v], bucket.begin() + start[v + 1],
              [&](std::int32_t a, std::int32_t b) { return key(a) < key(b); });
  // The other half-edge of h's edge, or -1 (only used once no edge has 3+ faces).
  auto mate = [&](std::int32_t h) -> std::int32_t {
    const auto first = bucket.begin() + start[lo_end(h)], last = bucket.begin() + start[lo_end(h) + 1];
    const std::int32_t other = hi_end(h);
    auto it = std::lower_bound(first, last, other, [&](std::int32_t e, std::int32_t o) { return hi_end(e) < o; });
    for (; it != last && hi_end(*it) == other; ++it)
      if (*it != h) return *it;
    return -1;
  };

  face_checks::DisjointSets fans(n_half);
  std::vector<std::int32_t> valence(n_vertices, 0);
  std::int32_t misoriented = -1;  // a half-edge whose mate runs the same way
  std::size_t n_edges = 0, n_boundary = 0;
  for (std::size_t v = 0; v < n_vertices; ++v) {
    for (std::int32_t i = start[v], j; i < start[v + 1]; i = j) {
      const std::int32_t other = hi_end(bucket[i]);
      for (j = i + 1; j < start[v + 1] && hi_end(bucket[j]) == other; ++j)
        if (third(bucket[j]) == third(bucket[j - 1])) {
          const std::int32_t f0 = std::min(bucket[j - 1], bucket[j]) / 3, f1 = std::max(bucket[j - 1], bucket[j]) / 3;
          throw MeshError("duplicate faces: " + face_str(f0, faces) + " and " + face_str(f1, faces) +
                          " have the same three vertices; remove one of them");
        }
      ++n_edges;
      ++valence[v];
      ++valence[other];
      if (j - i > 2) {
        std::vector<std::int32_t> users;
        for (std::int32_t p = i; p < j; ++p) users.push_back(bucket[p] / 3);
        std::sort(users.begin(), users.end());
        throw MeshError("non-manifold edge (" + std::to_string(v) + ", " + std::to_string(other) + "): shared by " + std::to_string(j - i) + " faces (faces " +
                        face_checks::face_list(users, 4) + "); an edge may border at most two faces");
      }
      if (j - i == 1) {
        ++n_boundary;
        continue;
      }
      const std::int32_t h0 = bucket[i], h1 = bucket[i + 1];
      if (tail(h0) == tail(h1)) {
        if (misoriented < 0) misoriented = h0;
        continue;
      }
      // h0 and h1 run opposite ways: the faces on either side join one fan
      // at each end of the edge (a corner is named by the half-edge leaving it).
      fans.unite(h0, static_cast<std::int32_t>(next_corner(h1)));
      fans.unite(h1, static_cast<std::int32_t>(next_corner(h0)));
    }
  }
  if (misoriented >= 0) {
    const std::int32_t h0 = misoriented, h1 = mate(h0);
    const std::int32_t f0 = std::min(h0, h1) / 3, f1 = std::max(h0, h1) / 3;
    throw MeshError("inconsistent orientation at edge (" + std::to_string(lo_end(h0)) + ", " +
                    std::to_string(hi_end(h0)) + "): " + face_str(f0, faces) + " and " + face_str(f1, faces) +
                    " both run from vertex " + std::to_string(tail(h0)) + " to " + std::to_string(head(h0)) + "; " +
                    face_checks::orientation_advice(faces, n_faces, f0, mate));
  }
  // One fan per vertex: every corner of a vertex in the set of its first corner.
  std::vector<std::int32_t>& first_corner = fill;  // reused: the bucketing is done
  std::fill(first_corner.begin(), first_corner.end(), -1);
  for (std::size_t h = 0; h < n_half; ++h) {
    const auto hh = static_cast<std::int32_t>(h);
    const std::int32_t v = tail(hh);
    if (first_corner[v] < 0) {
      first_corner[v] = hh;
      continue;
    }
    if (fans.find(hh) == fans.find(first_corner[v])) continue;
    std::vector<std::int32_t> roots;
    std::size_t n_at_v = 0;
    for (std::size_t c = 0; c < n_half; ++c)
      if (faces[c] == v) {
        ++n_at_v;
        roots.push_back(fans.find(static_cast<std::int32_t>(c)));
      }
    std::sort(roots.begin(), roots.end());
    const auto n_fans = std::unique(roots.begin(), roots.end()) - roots.begin();
    throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(n_at_v) + " faces form " +
                    std::to_string(n_fans) + " fans that meet only at this vertex (a 'bowtie'; e.g. faces " +
                    std::to_string(first_corner[v] / 3) + " and " + std::to_string(hh / 3) +
                    "); split it into one vertex per fan");
  }
  // OpenSubdiv's Far refuses a vertex of more than 65535 edges (Vtr::VALENCE_LIMIT)
  // without saying which; every sorpia operation goes through it.
  constexpr std::int32_t max_valence = (1 << 16) - 1;
  for (std::size_t v = 0; v < n_vertices; ++v)
    if (valence[v] > max_valence)
      throw MeshError("vertex " + std::to_string(v) + " has " + std::to_string(valence[v]) +
                      " neighbours: OpenSubdiv supports at most " + std::to_string(max_valence) +
                      " edges at a vertex; split the fan around it");
  return {n_edges, n_boundary};
}

}  // namespace

namespace {

// The reference build: OpenMesh's half-edge mesh by add_face, flattened by
// circulating clockwise round each vertex. Rotated so that an interior ring
// starts where one_ring_direct starts it (both builds give the same arrays).
detail::OneRing one_ring_openmesh(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices,
                                  std::size_t n_edges) {
  detail::OneRing r;
  detail::OMesh mesh;
  mesh.reserve(n_vertices, n_edges, n_faces);
  for (std::size_t v = 0; v < n_vertices; ++v) mesh.add_vertex(detail::OMesh::Point(0, 0, 0));
  r.face_count.assign(n_vertices, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    for (int k = 0; k < 3; ++k) ++r.face_count[t[k]];
    const auto fh = mesh.add_face(mesh.vertex_handle(t[0]), mesh.vertex_handle(t[1]), mesh.vertex_handle(t[2]));
    if (!fh.is_valid())
      throw MeshError(face_str(f, faces) +
                      " makes a non-manifold vertex (two fans of faces meet at one vertex, a 'bowtie')");
  }

  r.offsets.assign(n_vertices + 1, 0);
  r.boundary.assign(n_vertices, 0);
  r.neighbors.reserve(2 * n_edges);
  for (std::size_t v = 0; v < n_vertices; ++v) {
    const auto vh = mesh.vertex_handle(static_cast<int>(v));
    r.offsets[v] = static_cast<std::int32_t>(r.neighbors.size());
    if (r.face_count[v] == 0) {
      ++r.n_unreferenced;
      continue;
    }
    // A boundary vertex's outgoing half-edge is its boundary half-edge: start
    // there so the ring runs from one boundary neighbour to the other.
    const auto h0 = mesh.halfedge_handle(vh);
    const bool on_boundary = mesh.is_boundary(h0);
    r.boundary[v] = on_boundary;
    int faces_seen = 0;
    int lowest_face = -1;
    std::size_t lowest_at = r.neighbors.size();
    auto h = h0;
    do {
      if (!mesh.is_boundary(h)) {
        ++faces_seen;
        if (lowest_face < 0 || mesh.face_handle(h).idx() < lowest_face) {
          lowest_face = mesh.face_handle(h).idx();
          lowest_at = r.neighbors.size();
        }
      }
      r.neighbors.push_back(mesh.to_vertex_handle(h).idx());
      h = mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(h));  // clockwise
    } while (h != h0);
    if (faces_seen != r.face_count[v])
      throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(r.face_count[v]) +
                      " faces form more than one fan (a 'bowtie'); split it into one vertex per fan");
    // h = v -> x lies in the face (v, x, .): start an interior ring at the x
    // of the lowest-numbered face.
    if (!on_boundary)
      std::rotate(r.neighbors.begin() + r.offsets[v], r.neighbors.begin() + lowest_at, r.neighbors.end());
  }
  r.offsets[n_vertices] = static_cast<std::int32_t>(r.neighbors.size());
  return r;
}

}  // namespace

Topology::Topology(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices)
    : Topology(faces, n_faces, n_vertices, TopologyBuild::Direct) {}

Topology::Topology(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices, TopologyBuild build)
    : n_vertices_(n_vertices), faces_(faces, faces + 3 * n_faces) {
  detail::silence_openmesh();
  std::tie(n_edges_, n_boundary_edges_) = validate_faces(faces, n_faces, n_vertices);
  detail::OneRing r = build == TopologyBuild::OpenMesh
                          ? one_ring_openmesh(faces, n_faces, n_vertices, n_edges_)
                          : detail::one_ring_direct(faces, n_faces, n_vertices, n_edges_);
  ring_offsets_ = std::move(r.offsets);
  ring_neighbors_ = std::move(r.neighbors);
  face_count_ = std::move(r.face_count);
  boundary_ = std::move(r.boundary);
  n_unreferenced_ = r.n_unreferenced;
}

}  // namespace sorpia
