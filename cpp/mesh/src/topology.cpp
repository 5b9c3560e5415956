#include "sorpia/topology.hpp"

#include <algorithm>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "sorpia/detail/half_edges.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

namespace detail {

// What sorpia::Topology keeps of the half-edge structure: per vertex its
// neighbours in clockwise order (a boundary vertex from one boundary neighbour
// to the other; an interior vertex starting at the second corner of the
// lowest-numbered face around it), its number of faces and whether it is on
// the boundary.
// For polygon meshes also the faces round each vertex in ring order and their
// other vertices (Topology::vertex_faces, face_ring_neighbors).
struct OneRing {
  std::vector<std::int32_t> offsets;    // n_vertices + 1
  std::vector<std::int32_t> neighbors;  // 2 n_edges
  std::vector<std::int32_t> face_count;
  std::vector<std::uint8_t> boundary;
  std::size_t n_unreferenced = 0;
  // polygons only (empty for triangles)
  std::vector<std::int32_t> face_offsets;        // n_vertices + 1
  std::vector<std::int32_t> faces;               // sum of face_count
  std::vector<std::int32_t> face_ring_offsets;   // n_vertices + 1
  std::vector<std::int32_t> face_ring;           // the faces' other vertices
  std::vector<std::uint8_t> quad_ring;           // every face at the vertex is a quad
};

}  // namespace detail

namespace {

using detail::FaceList;

// ---- validate_faces and its helpers ----------------------------------------
// Over the half-edges of the face list.
namespace face_checks {

using Edge = std::pair<std::int32_t, std::int32_t>;  // (lower end, higher end)
inline Edge edge(std::int32_t a, std::int32_t b) { return {std::min(a, b), std::max(a, b)}; }
constexpr auto none = std::numeric_limits<std::int32_t>::max();

std::string face_list(const std::vector<std::int32_t>& ids, std::size_t shown) {
  std::string s;
  for (std::size_t i = 0; i < ids.size() && i < shown; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  return ids.size() > shown ? s + ", ..." : s;
}

// Error path only. Marks in `seen` the corners of the fan round the vertex of
// corner h0 (the faces reached from h0's across edges at that vertex).
// `mate[h]` is the other half-edge of h's edge or -1; needs edges of at most
// two faces, consistently oriented, so that the step to the next corner round
// the vertex, next_corner(mate[h]), is one-to-one and the walk ends.
void mark_fan(const FaceList& fl, const std::vector<std::int32_t>& mate, std::int32_t h0,
              std::vector<std::uint8_t>& seen) {
  std::int32_t h = h0;
  do {
    seen[h] = 1;
    if (mate[h] < 0) {  // a boundary edge: walk back from h0 to the other one
      for (h = mate[fl.prev(h0)]; h >= 0; h = mate[fl.prev(h)]) seen[h] = 1;
      return;
    }
    h = static_cast<std::int32_t>(fl.next(mate[h]));
  } while (h != h0);
}

// Error path only: the faces of half-edges g and h, on one edge, are
// duplicates (FaceList::same_face).
[[noreturn]] void refuse_duplicate(const FaceList& fl, std::int32_t g, std::int32_t h) {
  const std::int32_t f0 = std::min(fl.face_of(g), fl.face_of(h)), f1 = std::max(fl.face_of(g), fl.face_of(h));
  const std::int32_t n = fl.end(f0) - fl.begin(f0);
  const bool reversed = fl.idx[g] != fl.idx[h];
  throw MeshError("duplicate faces: " + fl.str(f0) + " and " + fl.str(f1) + " have the same " +
                  (n == 3 ? std::string("three vertices") + (reversed ? ", in the opposite order" : "")
                          : std::to_string(n) + " vertices in the " + (reversed ? "opposite" : "same") +
                                " cyclic order") +
                  "; remove one of them");
}

// Error path only. Some edge (v, x > v) has three or more faces or two
// duplicate faces (the same order; in the opposite order only beside a third
// face on the edge): sort the half-edges of the edges (v, x > v) by (x, third
// vertex (triangles), id), so that the half-edges of one edge, and two
// triangles with the same three vertices, are adjacent, and name the first
// such edge. (Two polygons may share two edges at a vertex of two faces
// without being duplicates; two duplicate polygons with a third face on an
// edge are named by that edge.)
[[noreturn]] void refuse_edge(const FaceList& fl, std::int32_t v) {
  const std::int32_t* faces = fl.idx;
  const std::size_t n_half = fl.n_corners();
  auto other = [&](std::int32_t h) { return std::max(faces[h], faces[fl.next(h)]); };
  std::vector<std::int32_t> hs;
  for (std::size_t h = 0; h < n_half; ++h)
    if (std::min(faces[h], faces[fl.next(h)]) == v) hs.push_back(static_cast<std::int32_t>(h));
  auto third = [&](std::int32_t h) { return fl.triangles() ? faces[fl.prev(h)] : h; };
  auto key = [&](std::int32_t h) { return std::make_tuple(other(h), third(h), h); };
  std::sort(hs.begin(), hs.end(), [&](std::int32_t a, std::int32_t b) { return key(a) < key(b); });
  for (std::size_t i = 0, j; i < hs.size(); i = j) {
    for (j = i + 1; j < hs.size() && other(hs[j]) == other(hs[i]); ++j) {
    }
    // Triangles: two of the same third vertex are adjacent. Polygons: an
    // edge of two faces is checked; an edge of more is named as such.
    for (std::size_t p = i + 1; p < j && (fl.triangles() || j - i == 2); ++p)
      if (fl.same_face(hs[p - 1], hs[p]) && (j - i > 2 || faces[hs[p - 1]] == faces[hs[p]]))
        refuse_duplicate(fl, hs[p - 1], hs[p]);  // not a pillow: the same order, or a third face on the edge
    if (j - i > 2) {
      std::vector<std::int32_t> users;
      for (std::size_t p = i; p < j; ++p) users.push_back(fl.face_of(hs[p]));
      std::sort(users.begin(), users.end());
      throw MeshError("non-manifold edge (" + std::to_string(v) + ", " + std::to_string(other(hs[i])) +
                      "): shared by " + std::to_string(j - i) + " faces (faces " + face_list(users, 4) +
                      "); an edge may border at most two faces");
    }
  }
  throw std::logic_error("sorpia: refuse_edge found no bad edge at vertex " + std::to_string(v));
}

// Error path only: the other half-edge of each half-edge's edge, or -1
// (needs edges of at most two faces).
std::vector<std::int32_t> mates(const FaceList& fl, std::size_t n_vertices) {
  return detail::EdgeGroups(fl, n_vertices).mates();
}

// Error path only. Some vertex has more than one fan of faces: name the vertex
// of the first corner (in face order) outside the fan of its vertex's first
// corner, with its number of faces and of fans.
[[noreturn]] void refuse_bowtie(const FaceList& fl, std::size_t n_vertices) {
  const std::int32_t* faces = fl.idx;
  const std::size_t n_half = fl.n_corners();
  const std::vector<std::int32_t> mate = mates(fl, n_vertices);
  std::vector<std::int32_t> first_corner(n_vertices, -1);
  for (std::size_t h = 0; h < n_half; ++h)
    if (first_corner[faces[h]] < 0) first_corner[faces[h]] = static_cast<std::int32_t>(h);
  std::vector<std::uint8_t> seen(n_half, 0);
  for (std::int32_t c : first_corner)
    if (c >= 0) mark_fan(fl, mate, c, seen);
  const auto hh = static_cast<std::int32_t>(std::find(seen.begin(), seen.end(), 0) - seen.begin());
  if (static_cast<std::size_t>(hh) == n_half) throw std::logic_error("sorpia: refuse_bowtie found one fan everywhere");
  const std::int32_t v = faces[hh];
  std::size_t n_at_v = 0, n_fans = 1;  // the first fan is marked
  for (std::size_t c = 0; c < n_half; ++c)
    if (faces[c] == v) {
      ++n_at_v;
      if (!seen[c]) {
        ++n_fans;
        mark_fan(fl, mate, static_cast<std::int32_t>(c), seen);
      }
    }
  throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(n_at_v) + " faces form " +
                  std::to_string(n_fans) + " fans that meet only at this vertex (a 'bowtie'; e.g. faces " +
                  std::to_string(fl.face_of(first_corner[v])) + " and " + std::to_string(fl.face_of(hh)) +
                  "); split it into one vertex per fan");
}

// Error path only. Two faces traverse an edge in the same direction: try to
// orient the connected component of face `start` by breadth-first search
// (`mate(h)` is the other half-edge of h's edge, or -1 on the boundary). Says
// which faces to reverse, or that no orientation exists (a Moebius strip).
template <class Mate>
std::string orientation_advice(const FaceList& fl, std::size_t start, Mate mate) {
  const std::int32_t* faces = fl.idx;
  std::vector<std::int8_t> flip(fl.n_faces, -1);
  std::vector<std::int32_t> component{static_cast<std::int32_t>(start)};
  flip[start] = 0;
  bool orientable = true;
  for (std::size_t q = 0; q < component.size(); ++q) {
    const std::int32_t f = component[q];
    for (std::int32_t h = fl.begin(f); h < fl.end(f); ++h) {
      const std::int32_t g = mate(h);
      if (g < 0) continue;
      // opposite traversal keeps the relative orientation, the same one swaps it
      const std::int8_t want = static_cast<std::int8_t>(flip[f] ^ (faces[h] == faces[g] ? 1 : 0));
      const std::int32_t fg = fl.face_of(g);
      if (flip[fg] < 0) {
        flip[fg] = want;
        component.push_back(fg);
      } else if (flip[fg] != want) {
        orientable = false;
      }
    }
  }
  if (!orientable)
    return "the surface is not orientable (like a Moebius strip: no choice of face orientations is consistent), "
           "and subdivision needs an orientable surface";
  std::vector<std::int32_t> ones, zeros;
  for (std::int32_t f : component) (flip[f] ? ones : zeros).push_back(f);
  std::vector<std::int32_t>& fewer = ones.size() <= zeros.size() ? ones : zeros;
  std::sort(fewer.begin(), fewer.end());
  return "reversing the vertex order of " + std::to_string(fewer.size()) + " of the " +
         std::to_string(component.size()) + " faces of this connected part makes it consistent (faces " +
         face_list(fewer, 8) + ")";
}

// Error path only. Edge e is run the same way by two faces: names them and
// says how to fix the orientation of their connected part.
[[noreturn]] void refuse_misoriented(const FaceList& fl, std::size_t n_vertices, Edge e) {
  const std::int32_t* faces = fl.idx;
  const std::vector<std::int32_t> mate = mates(fl, n_vertices);
  std::int32_t h0 = 0;
  while (edge(faces[h0], faces[fl.next(h0)]) != e) ++h0;
  const std::int32_t h1 = mate[h0];
  const std::int32_t f0 = fl.face_of(std::min(h0, h1)), f1 = fl.face_of(std::max(h0, h1));
  throw MeshError("inconsistent orientation at edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                  "): " + fl.str(f0) + " and " + fl.str(f1) + " both run from vertex " + std::to_string(faces[h0]) +
                  " to " + std::to_string(faces[fl.next(h0)]) + "; " +
                  orientation_advice(fl, f0, [&](std::int32_t h) { return mate[h]; }));
}

// Every index in [0, n_vertices) and three distinct vertices per triangle, face by face.
void check_face_indices(const FaceList& fl, std::size_t n_vertices) {
  const std::int32_t* faces = fl.idx;
  for (std::size_t f = 0; f < fl.n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= n_vertices)
        throw MeshError(fl.str(f) + " has vertex index " + std::to_string(t[k]) + " out of range [0, " +
                        std::to_string(n_vertices) + ")");
    for (int k = 0; k < 3; ++k)
      if (t[k] == t[(k + 1) % 3])
        throw MeshError(fl.str(f) + " repeats vertex " + std::to_string(t[k]) +
                        " (a degenerate triangle): remove the face");
  }
}

// The same for polygons (their sizes, at least 3, are checked when the
// offsets are made): indices in range, no vertex twice in a face.
void check_polygon_indices(const FaceList& fl, std::size_t n_vertices) {
  std::vector<std::int32_t> sorted;
  for (std::size_t f = 0; f < fl.n_faces; ++f) {
    const std::int32_t *lo = fl.idx + fl.off[f], *hi = fl.idx + fl.off[f + 1];
    for (const std::int32_t* t = lo; t < hi; ++t)
      if (*t < 0 || static_cast<std::size_t>(*t) >= n_vertices)
        throw MeshError(fl.str(f) + " has vertex index " + std::to_string(*t) + " out of range [0, " +
                        std::to_string(n_vertices) + ")");
    sorted.assign(lo, hi);
    std::sort(sorted.begin(), sorted.end());
    const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
    if (twice != sorted.end())
      throw MeshError(fl.str(f) + " repeats vertex " + std::to_string(*twice) +
                      " (a degenerate polygon): remove the repeated corner or the face");
  }
}

// OpenSubdiv's Far refuses a vertex of more than 65535 edges (Vtr::VALENCE_LIMIT)
// without saying which; every sorpia operation goes through it.
constexpr std::int32_t max_valence = (1 << 16) - 1;

// What the vertex-by-vertex pass found, each problem the first of its kind in
// the order its error path names it, and the edge counts (every edge is seen
// from both ends).
struct Findings {
  std::int32_t bad_lo = none;       // the lowest lower end of an edge of 3+ faces or of two equal faces
  Edge misoriented{none, none};     // the first edge two faces run the same way
  bool bowtie = false;              // some vertex has more than one fan
  std::int32_t crowded = -1, crowded_valence = 0;  // the first vertex of more than max_valence edges
  std::size_t n_edge_ends = 0, n_boundary_ends = 0;
  bool any() const { return bad_lo != none || misoriented.first != none || bowtie || crowded >= 0; }
};

// Throws the MeshError of the first problem in `found`, in this order: an edge
// of 3+ faces or a duplicate face, a misoriented edge, a bowtie, a crowded
// vertex. Each error path looks again (sorting) to name the same edge, face or
// vertex whatever order the pass met them in.
void refuse_findings(const Findings& found, const FaceList& fl, std::size_t n_vertices) {
  if (found.bad_lo != none) refuse_edge(fl, found.bad_lo);
  if (found.misoriented.first != none) refuse_misoriented(fl, n_vertices, found.misoriented);
  if (found.bowtie) refuse_bowtie(fl, n_vertices);
  if (found.crowded >= 0)
    throw MeshError("vertex " + std::to_string(found.crowded) + " has " + std::to_string(found.crowded_valence) +
                    " neighbours: OpenSubdiv supports at most " + std::to_string(max_valence) +
                    " edges at a vertex; split the fan around it");
}

// The edges of one vertex v at a time, matched through a slot per neighbour x
// stamped with v so that it is never cleared: the faces at v using edge
// (v, x) (`users`, at most 3 counted; `outs` of them run v -> x), the third
// vertex of the first one, and the neighbour after x clockwise round v: the
// `next` of the corner whose `prev` is x (as half_edges.hpp's Corner chains a
// fan). No sort, so a high-valence vertex costs no more than its edges.
// kPolygons: the slot also keeps that corner (the face between x and the next
// neighbour, for the face ring), and two faces sharing both edges at v are a
// vertex of two faces, not duplicate triangles.
template <bool kPolygons>
class VertexEdges {
 public:
  VertexEdges(const FaceList& fl, std::size_t n_vertices) : fl_(fl), slots_(n_vertices) {}

  // Matches the edges of v's k corners c (with their corner ids for
  // polygons), recording problems in `found`; returns whether the fan can be
  // walked (every edge at v of at most two faces, distinct, consistently oriented).
  bool match(std::int32_t v, const detail::Corner* c, const std::int32_t* ids, std::int32_t k, Findings& found) {
    v_ = v;
    n_edges_ = n_single_ = 0;
    checkable_ = true;
    for (std::int32_t i = 0; i < k; ++i) {
      const std::int32_t id = kPolygons ? ids[i] : 0;
      use(c[i].next, c[i].prev, true, id, found);
      use(c[i].prev, c[i].next, false, id, found);
    }
    if (n_edges_ > max_valence && found.crowded < 0) {
      found.crowded = v;
      found.crowded_valence = n_edges_;
    }
    found.n_edge_ends += static_cast<std::size_t>(n_edges_);
    found.n_boundary_ends += static_cast<std::size_t>(n_single_);
    return checkable_;
  }

  // Edges at v of one face (boundary edges), after match.
  std::int32_t n_single() const { return n_single_; }

  // Where the clockwise walk round v starts: the far end of the boundary edge
  // that only runs into v, or (interior vertex) the second corner of v's
  // lowest-numbered face.
  std::int32_t fan_start(const detail::Corner* c, std::int32_t k) const {
    for (std::int32_t i = 0; i < k && n_single_ > 0; ++i) {
      const EdgeSlot& s = slots_[c[i].prev];
      if (s.outs == 0 && s.users == 1) return c[i].prev;
    }
    return c[0].next;
  }

  // Walks the fan clockwise from `first`, calling emit(x) for each neighbour
  // passed and (polygons) face(corner) for each face passed between two
  // neighbours, until it closes, reaches the fan's other boundary edge or has
  // passed more than k faces; returns the number of faces passed (k when v
  // has a single fan).
  template <class Emit, class Face>
  std::int32_t walk_fan(std::int32_t first, std::int32_t k, Emit emit, Face face) const {
    std::int32_t seen = 0;
    for (std::int32_t x = first;;) {
      emit(x);
      const EdgeSlot& s = slots_[x];
      if (s.users == s.outs) break;  // no face runs x -> v: the fan's other boundary edge
      ++seen;
      if constexpr (kPolygons) {
        if (seen <= k) face(s.corner);
      }
      x = s.after;
      if (x == first || seen > k) break;
    }
    return seen;
  }

 private:
  struct TriangleSlot {
    std::int32_t stamp = -1, third = 0, after = 0;
    std::uint8_t users = 0, outs = 0;
  };
  struct PolygonSlot : TriangleSlot {
    std::int32_t corner = -1;  // the corner whose prev is x: the face between x and `after`
  };
  using EdgeSlot = std::conditional_t<kPolygons, PolygonSlot, TriangleSlot>;

  // One face at v (corner `id`) uses edge (v, x) with third vertex `third`,
  // running v -> x if `out`.
  void use(std::int32_t x, std::int32_t third, bool out, std::int32_t id, Findings& found) {
    EdgeSlot& s = slots_[x];
    if (s.stamp != v_) {
      s.stamp = v_;
      s.third = s.after = third;
      s.users = 1;
      s.outs = static_cast<std::uint8_t>(out);
      if constexpr (kPolygons) s.corner = id;
      ++n_edges_;
      ++n_single_;
      return;
    }
    if (s.users == 1) {
      --n_single_;
      // Two faces running the edge both ways are manifold there, even with
      // the same vertices in the opposite order (a closed 'pillow' of two
      // faces, which OpenSubdiv takes); the same way, equal faces are duplicates.
      if (s.outs == static_cast<std::uint8_t>(out) && s.third == third && duplicate(s, id, out)) {
        found.bad_lo = std::min(found.bad_lo, std::min(v_, x));
        checkable_ = false;
      } else if (s.outs == static_cast<std::uint8_t>(out)) {
        found.misoriented = std::min(found.misoriented, edge(v_, x));
        checkable_ = false;
      }
    } else if (s.users == 2) {
      found.bad_lo = std::min(found.bad_lo, std::min(v_, x));
      checkable_ = false;
    }
    s.users = static_cast<std::uint8_t>(std::min(s.users + 1, 3));
    s.outs = static_cast<std::uint8_t>(s.outs + out);
    if (!out) {
      s.after = third;
      if constexpr (kPolygons) s.corner = id;
    }
  }

  // Whether the second face at v on the edge of slot `s`, running it the same
  // way and with the same third vertex as the first (both share both their
  // edges at v), is a duplicate of the first: always for triangles; for
  // polygons, the same cycle (corner `id`, running the edge out of v if `out`).
  bool duplicate(const EdgeSlot& s, std::int32_t id, bool out) const {
    if constexpr (kPolygons)
      return fl_.same_cycle(static_cast<std::size_t>(s.corner), static_cast<std::size_t>(id),
                            s.outs != static_cast<std::uint8_t>(out));
    return true;
  }

  FaceList fl_;
  std::vector<EdgeSlot> slots_;
  std::int32_t v_ = -1, n_edges_ = 0, n_single_ = 0;  // the vertex, its edges, those of one face
  bool checkable_ = true;
};

// Fills a detail::OneRing vertex by vertex with the fans the walk passes (for
// polygons also the faces passed and their other vertices); does nothing
// without a ring (validation alone).
class RingBuilder {
 public:
  RingBuilder(detail::OneRing* ring, const FaceList& fl, std::size_t n_vertices) : r_(ring), fl_(fl) {
    if (!r_) return;
    const std::size_t n_half = fl.n_corners();
    r_->offsets.resize(n_vertices + 1);
    r_->face_count.resize(n_vertices);
    r_->boundary.assign(n_vertices, 0);
    // Exact for a closed mesh (2 n_edges = n_half); a boundary adds one entry
    // per boundary edge.
    r_->neighbors.reserve(n_half + n_half / 16);
    if (fl.triangles()) return;
    r_->face_offsets.resize(n_vertices + 1);
    r_->faces.reserve(n_half);
    r_->face_ring_offsets.resize(n_vertices + 1);
    r_->quad_ring.assign(n_vertices, 0);
  }
  void begin_vertex(std::int32_t v, std::int32_t n_faces) {
    if (!r_) return;
    v_ = v;
    r_->offsets[v] = static_cast<std::int32_t>(r_->neighbors.size());
    r_->face_count[v] = n_faces;
    r_->n_unreferenced += n_faces == 0;
    if (fl_.triangles()) return;
    r_->face_offsets[v] = static_cast<std::int32_t>(r_->faces.size());
    r_->face_ring_offsets[v] = static_cast<std::int32_t>(r_->face_ring.size());
    r_->quad_ring[v] = n_faces > 0;
  }
  void set_boundary(std::int32_t v, bool on_boundary) {
    if (r_) r_->boundary[v] = on_boundary;
  }
  void push(std::int32_t x) {
    if (r_) r_->neighbors.push_back(x);
  }
  // The face of corner h (at the current vertex), passed between two
  // neighbours: its vertices after the next one up to the one before the
  // previous one, counter-clockwise.
  void push_face(std::int32_t h) {
    if (!r_) return;
    const std::int32_t f = fl_.face_of(h), lo = fl_.off[f], n = fl_.off[f + 1] - lo, p = h - lo;
    r_->faces.push_back(f);
    for (std::int32_t t = 2; t < n - 1; ++t) r_->face_ring.push_back(fl_.idx[lo + (p + t) % n]);
    if (n != 4) r_->quad_ring[v_] = 0;
  }
  void finish(std::size_t n_vertices) {
    if (!r_) return;
    r_->offsets[n_vertices] = static_cast<std::int32_t>(r_->neighbors.size());
    if (fl_.triangles()) return;
    r_->face_offsets[n_vertices] = static_cast<std::int32_t>(r_->faces.size());
    r_->face_ring_offsets[n_vertices] = static_cast<std::int32_t>(r_->face_ring.size());
  }

 private:
  detail::OneRing* r_;
  FaceList fl_;
  std::int32_t v_ = -1;
};

}  // namespace face_checks

// Checks what OpenMesh and OpenSubdiv would not: indices in range and distinct
// (OpenMesh aborts on a repeated vertex), no duplicate faces (a pair in the
// opposite order alone on its edges is a closed 'pillow', kept), at most two
// faces per edge, consistent orientation (OpenMesh would fail add_face without
// saying why) and one fan of faces per vertex (a 'bowtie' is accepted by
// OpenMesh and quietly made a corner by OpenSubdiv). Throws MeshError naming
// the first offending face, edge or vertex.
// Linear time: the corners are bucketed by vertex (detail::bucket_corners),
// each vertex's edges matched (face_checks::VertexEdges) and its faces
// chained into a fan; problems are named afterwards by
// face_checks::refuse_findings.
// Returns the number of edges and of boundary edges. With `ring`, also fills
// it with the fans that walk passes, which are the one-ring.
// With `valid`, the walk stops at the first problem and sets *valid = false
// instead of naming it (naming may sort every half-edge).
// kPolygons is fl.triangles() == false: triangles take the path without corner ids.
template <bool kPolygons>
std::pair<std::size_t, std::size_t> validate_faces(const FaceList& fl, std::size_t n_vertices, detail::OneRing* ring,
                                                   bool* valid) {
  if constexpr (kPolygons)
    face_checks::check_polygon_indices(fl, n_vertices);
  else
    face_checks::check_face_indices(fl, n_vertices);
  detail::CornerBuckets buckets = kPolygons ? detail::bucket_polygon_corners(fl.idx, fl.off, fl.n_faces, n_vertices)
                                            : detail::bucket_corners(fl.idx, fl.n_faces, n_vertices);
  face_checks::RingBuilder builder(ring, fl, n_vertices);
  face_checks::VertexEdges<kPolygons> edges(fl, n_vertices);
  face_checks::Findings found;
  for (std::size_t vi = 0; vi < n_vertices; ++vi) {
    if (valid && found.any()) break;  // a yes-or-no answer is known at the first problem
    const auto v = static_cast<std::int32_t>(vi);
    const std::int32_t k = buckets.start[v + 1] - buckets.start[v];
    const detail::Corner* c = buckets.corners.get() + buckets.start[v];
    const std::int32_t* ids = kPolygons ? buckets.ids.get() + buckets.start[v] : nullptr;
    builder.begin_vertex(v, k);
    if (!edges.match(v, c, ids, k, found) || k == 0 || found.bowtie) continue;
    if (edges.n_single() > 2) {  // a fan has two boundary edges or none
      found.bowtie = true;
      continue;
    }
    builder.set_boundary(v, edges.n_single() > 0);
    if (edges.walk_fan(
            edges.fan_start(c, k), k, [&](std::int32_t x) { builder.push(x); },
            [&](std::int32_t h) { builder.push_face(h); }) != k)
      found.bowtie = true;
  }
  buckets.corners.reset();
  buckets.ids.reset();
  if (valid && found.any()) {
    *valid = false;
    return {0, 0};
  }
  face_checks::refuse_findings(found, fl, n_vertices);
  builder.finish(n_vertices);
  return {found.n_edge_ends / 2, found.n_boundary_ends / 2};
}

std::pair<std::size_t, std::size_t> validate_faces(const FaceList& fl, std::size_t n_vertices, detail::OneRing* ring,
                                                   bool* valid = nullptr) {
  return fl.triangles() ? validate_faces<false>(fl, n_vertices, ring, valid)
                        : validate_faces<true>(fl, n_vertices, ring, valid);
}

// Counts the core's int32 indices can hold, and at least one face.
// (Every face has at least three corners, and the corners are int32 indices.)
void check_counts(std::size_t n_faces, std::size_t n_vertices) {
  constexpr auto int_max = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  if (n_vertices > int_max)
    throw MeshError("too many vertices: " + std::to_string(n_vertices) + " (at most 2^31 - 1)");
  if (n_faces > int_max / 3)
    throw MeshError("too many faces: " + std::to_string(n_faces) + " (at most (2^31 - 1) / 3)");
  if (n_faces == 0) throw MeshError("the mesh has no faces: subdivision needs at least one face");
}

}  // namespace

bool faces_valid(const Mesh& faces, std::size_t n_vertices) {
  bool valid = true;
  try {
    const detail::FaceArrays arrays = detail::FaceArrays::of(faces);  // none for a triangle list
    check_counts(arrays.n_faces, n_vertices);
    validate_faces(arrays.over(faces), n_vertices, nullptr, &valid);
  } catch (const MeshError&) {
    return false;
  }
  return valid;
}

Topology::Topology(const Mesh& mesh) : n_vertices_(mesh.n_vertices()) {
  init(Mesh{{}, mesh.face_vertex_counts, mesh.face_vertex_indices, mesh.face_size});  // the faces copied, not the vertices
}

Topology::Topology(Mesh faces, std::size_t n_vertices) : n_vertices_(n_vertices) { init(std::move(faces)); }

void Topology::init(Mesh faces) {
  n_faces_ = detail::mesh_face_count(faces);
  check_counts(n_faces_, n_vertices_);
  if (faces.all_triangles()) {  // the triangle fast path: no counts, no offsets
    face_indices_ = std::move(faces.face_vertex_indices);
    build();
    return;
  }
  face_offsets_ = faces.uniform() ? detail::uniform_offsets(faces.face_size, n_faces_)
                                  : detail::polygon_offsets(faces.face_vertex_counts.data(), n_faces_);
  detail::check_counts_sum(face_offsets_, faces.face_vertex_indices.size());
  face_indices_ = std::move(faces.face_vertex_indices);
  auto size = [&](std::size_t f) { return face_offsets_[f + 1] - face_offsets_[f]; };
  all_triangles_ = all_quads_ = true;
  for (std::size_t f = 0; f < n_faces_; ++f) {
    all_triangles_ = all_triangles_ && size(f) == 3;
    all_quads_ = all_quads_ && size(f) == 4;
  }
  if (all_triangles_) face_offsets_.clear();
  build();
}

std::vector<std::int32_t> Topology::face_counts() const {
  std::vector<std::int32_t> counts(n_faces_);
  for (std::size_t f = 0; f < n_faces_; ++f) counts[f] = face_size(f);
  return counts;
}

std::vector<std::int32_t> Topology::face_offsets() const {
  if (!all_triangles_) return face_offsets_;
  std::vector<std::int32_t> off(n_faces_ + 1);
  for (std::size_t f = 0; f <= n_faces_; ++f) off[f] = static_cast<std::int32_t>(3 * f);
  return off;
}

const std::vector<std::int32_t>& Topology::half_edge_twins() const {
  if (!twins_) twins_ = std::make_shared<Twins>();  // a Topology moved from (not shared with another thread)
  std::call_once(twins_->made, [&] {
    if (all_triangles_) {
      twins_->twins = detail::EdgeGroups(detail::FaceArrays::triangles(n_faces_).over(face_indices_.data()),
                                         n_vertices_).mates();
      return;
    }
    const std::vector<std::int32_t> corner_face = detail::corner_faces(face_offsets_);
    const detail::FaceList fl{face_indices_.data(), face_offsets_.data(), corner_face.data(), n_faces_};
    twins_->twins = detail::EdgeGroups(fl, n_vertices_).mates();
  });
  return twins_->twins;
}

std::vector<std::int32_t> Topology::find_half_edges(const std::int32_t* pairs, std::size_t k) const {
  // The queries sorted by (lower end, higher end), merged with EdgeGroups'
  // edges, which come in that order.
  std::vector<std::pair<std::uint64_t, std::size_t>> queries(k);
  for (std::size_t i = 0; i < k; ++i) {
    const auto a = static_cast<std::uint32_t>(std::min(pairs[2 * i], pairs[2 * i + 1]));
    const auto b = static_cast<std::uint32_t>(std::max(pairs[2 * i], pairs[2 * i + 1]));
    queries[i] = {static_cast<std::uint64_t>(a) << 32 | b, i};
  }
  std::sort(queries.begin(), queries.end());
  std::vector<std::int32_t> out(k, -1);
  std::size_t q = 0;
  const auto visit = [&](std::int32_t a, std::int32_t b, const std::int32_t* hs, std::int32_t) {
    const std::uint64_t key = static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32 | static_cast<std::uint32_t>(b);
    while (q < k && queries[q].first < key) ++q;
    for (; q < k && queries[q].first == key; ++q) out[queries[q].second] = hs[0];
  };
  if (all_triangles_) {
    detail::EdgeGroups(detail::FaceArrays::triangles(n_faces_).over(face_indices_.data()), n_vertices_).for_each(visit);
  } else {
    const std::vector<std::int32_t> corner_face = detail::corner_faces(face_offsets_);
    const detail::FaceList fl{face_indices_.data(), face_offsets_.data(), corner_face.data(), n_faces_};
    detail::EdgeGroups(fl, n_vertices_).for_each(visit);
  }
  return out;
}

const std::vector<std::int32_t>& Topology::faces() const {
  if (!all_triangles_)
    throw std::logic_error("sorpia::Topology::faces: the mesh has faces that are not triangles (use face_indices)");
  return face_indices_;
}

void Topology::build() {
  const std::vector<std::int32_t> corner_face =
      all_triangles_ ? std::vector<std::int32_t>{} : detail::corner_faces(face_offsets_);
  const FaceList fl{face_indices_.data(), all_triangles_ ? nullptr : face_offsets_.data(),
                    all_triangles_ ? nullptr : corner_face.data(), n_faces_};
  detail::OneRing r;
  std::tie(n_edges_, n_boundary_edges_) = validate_faces(fl, n_vertices_, &r);
  ring_offsets_ = std::move(r.offsets);
  ring_neighbors_ = std::move(r.neighbors);
  face_count_ = std::move(r.face_count);
  boundary_ = std::move(r.boundary);
  n_unreferenced_ = r.n_unreferenced;
  vertex_face_offsets_ = std::move(r.face_offsets);
  vertex_faces_ = std::move(r.faces);
  face_ring_offsets_ = std::move(r.face_ring_offsets);
  face_ring_neighbors_ = std::move(r.face_ring);
  quad_ring_ = std::move(r.quad_ring);
}

}  // namespace sorpia
