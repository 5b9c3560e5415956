// sorpia::repair (repair.hpp). Works on the half-edges of the face list
// (half_edges.hpp's FaceList, triangles or polygons): half-edge h runs from
// corner h to the next corner of its face and also names corner h, as in
// topology.cpp. Linear time apart
// from the faces of one edge, which are few: the half-edges are grouped by
// edge (half_edges.hpp's EdgeGroups), the
// fans are the classes of a union-find over corners, the orientation a
// breadth-first search over the joined edges.
#include "sorpia/repair.hpp"

#include <algorithm>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "sorpia/detail/half_edges.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

bool RepairReport::empty() const {
  return degenerate_faces.empty() && collapsed_faces.empty() && duplicate_faces.empty() && reversed_duplicate_faces.empty() &&
         nonmanifold_edges.empty() && sheet_vertices.empty() && bowtie_vertices.empty() &&
         cut_nonmanifold_edges.empty() && cut_edges.empty() && cut_vertices.empty() && flipped_faces.empty();
}

namespace {

using detail::FaceArrays;
using detail::FaceList;
// Union-find over corners: the root of a class is its lowest corner.
using Corners = detail::DisjointSets;

// A FaceList whose kind is fixed at compile time: the triangle path steps
// round a face by arithmetic (next_corner, h / 3), with no branch on the kind.
template <bool kPolygons>
struct Faces : FaceList {
  bool triangles() const { return !kPolygons; }
  std::int32_t face_of(std::size_t h) const {
    if constexpr (kPolygons) return corner_face[h];
    return static_cast<std::int32_t>(h / 3);
  }
  std::size_t next(std::size_t h) const {
    if constexpr (kPolygons) return FaceList::next(h);
    return detail::next_corner(h);
  }
  std::size_t prev(std::size_t h) const {
    if constexpr (kPolygons) return FaceList::prev(h);
    return detail::prev_corner(h);
  }
  // Face f's corners are [begin(f), end(f)).
  std::int32_t begin(std::size_t f) const {
    if constexpr (kPolygons) return off[f];
    return static_cast<std::int32_t>(3 * f);
  }
  std::int32_t end(std::size_t f) const { return begin(f + 1); }
};

// A polygon list owning its arrays.
struct OwnedFaces {
  std::vector<std::int32_t> idx;
  FaceArrays arrays;

  bool empty() const { return idx.empty(); }
  FaceList view() const { return arrays.over(idx.data()); }
};

// Rule 1 of repair.hpp: marks in `removed` (and reports) the faces that
// repeat a vertex and are not a polygon once their consecutive repeats are
// dropped. Returns `fl` with the repeated corners of the other faces that
// repeat a vertex dropped ("collapsed_faces"), the faces numbered as in `fl`,
// or an empty list where no face collapses (triangles never do).
OwnedFaces drop_repeated_corners(const FaceList& fl, std::size_t n_vertices, std::vector<std::uint8_t>& removed,
                                 RepairReport& rep) {
  OwnedFaces out;
  if (fl.triangles()) {
    for (std::size_t f = 0; f < fl.n_faces; ++f) {
      const std::int32_t* t = fl.idx + 3 * f;
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
        removed[f] = 1;
        rep.degenerate_faces.push_back(static_cast<std::int32_t>(f));
      }
    }
    return out;
  }
  // stamp[v] == 2 f: v seen in face f; 2 f + 1: v kept in face f's collapsed cycle.
  std::vector<std::int32_t> stamp(n_vertices, -1);
  std::vector<std::int32_t> kept_off{0}, kept;  // the collapsed faces' corners
  for (std::size_t f = 0; f < fl.n_faces; ++f) {
    const std::int32_t lo = fl.off[f], hi = fl.off[f + 1];
    const auto seen = static_cast<std::int32_t>(2 * f), in_cycle = seen + 1;
    bool repeats = false;
    for (std::int32_t h = lo; h < hi; ++h) {
      repeats |= stamp[fl.idx[h]] == seen;
      stamp[fl.idx[h]] = seen;
    }
    if (!repeats) continue;
    const std::size_t start = kept.size();
    bool polygon = true;
    for (std::int32_t h = lo; h < hi; ++h) {
      const std::int32_t v = fl.idx[h];
      if (v == fl.idx[fl.prev(h)]) continue;  // a consecutive repeat (cyclically)
      polygon &= stamp[v] != in_cycle;
      stamp[v] = in_cycle;
      kept.push_back(v);
    }
    if (polygon && kept.size() - start >= 3) {
      rep.collapsed_faces.push_back(static_cast<std::int32_t>(f));
      kept_off.push_back(static_cast<std::int32_t>(kept.size()));
    } else {
      kept.resize(start);
      removed[f] = 1;
      rep.degenerate_faces.push_back(static_cast<std::int32_t>(f));
    }
  }
  if (rep.collapsed_faces.empty()) return out;
  std::vector<std::int32_t>& off = out.arrays.off;
  off.reserve(fl.n_faces + 1);
  out.idx.reserve(fl.n_corners());
  off.push_back(0);
  for (std::size_t f = 0, c = 0; f < fl.n_faces; ++f) {
    if (c < rep.collapsed_faces.size() && rep.collapsed_faces[c] == static_cast<std::int32_t>(f)) {
      out.idx.insert(out.idx.end(), kept.begin() + kept_off[c], kept.begin() + kept_off[c + 1]);
      ++c;
    } else {
      out.idx.insert(out.idx.end(), fl.idx + fl.off[f], fl.idx + fl.off[f + 1]);
    }
    off.push_back(static_cast<std::int32_t>(out.idx.size()));
  }
  out.arrays.corner_face = detail::corner_faces(off);
  out.arrays.n_faces = fl.n_faces;
  return out;
}

// Rules 2 and 3 of repair.hpp: removes (in `removed`, reported in `rep`) the
// duplicate faces, and returns for each half-edge the half-edge of the face it
// is joined to across its edge, or -1. The half-edges of the faces not yet
// removed are grouped by edge (detail::EdgeGroups, in face order within an
// edge). A duplicate face shares each of its edges with the face it repeats,
// so it is found at its first edge, before it could be joined, and the face
// kept is the first of its copies whichever edge finds them. The ends of edges of three or more faces are marked in
// `sheet_end`, the half-edges of the faces paired there in `paired`. Needs
// faces without a repeated vertex (rule 1).
template <bool kPolygons>
std::vector<std::int32_t> join_edges(const Faces<kPolygons>& fl, std::size_t n_vertices, bool pair_sheets,
                                     std::vector<std::uint8_t>& removed, RepairReport& rep,
                                     std::vector<std::uint8_t>& sheet_end, std::vector<std::uint8_t>& paired) {
  const std::int32_t* faces = fl.idx;
  auto drop_duplicate = [&](std::int32_t kept, std::int32_t h) {
    removed[fl.face_of(h)] = 1;
    (faces[kept] == faces[h] ? rep.duplicate_faces : rep.reversed_duplicate_faces).push_back(fl.face_of(h));
  };
  std::vector<std::int32_t> mate(fl.n_corners(), -1);
  std::vector<std::int32_t> live;
  const detail::EdgeGroups edges(fl, n_vertices, [&](std::size_t h) { return !removed[fl.face_of(h)]; });
  // The faces with an edge of three or more faces: two duplicate faces in the
  // opposite order none of which has one are a pillow (a closed surface of
  // two faces, valid), kept.
  std::vector<std::uint8_t> crowded(fl.n_faces, 0);
  edges.for_each([&](std::int32_t, std::int32_t, const std::int32_t* b, std::int32_t k) {
    if (k > 2)
      for (std::int32_t j = 0; j < k; ++j) crowded[fl.face_of(b[j])] = 1;
  });
  auto pillow = [&](std::int32_t g, std::int32_t h) {
    return faces[g] != faces[h] && !crowded[fl.face_of(g)] && !crowded[fl.face_of(h)];
  };
  edges.for_each([&](std::int32_t v, std::int32_t x, const std::int32_t* b, std::int32_t k) {
    if (k == 2) {  // most edges: joined, or one face a duplicate of the other
      const std::int32_t g = b[0], h = b[1];
      if (removed[fl.face_of(g)] || removed[fl.face_of(h)]) return;  // a duplicate found at another edge
      if (fl.same_face(g, h) && !pillow(g, h)) {
        drop_duplicate(g, h);
      } else {
        mate[g] = h;
        mate[h] = g;
      }
      return;
    }
    // The faces of edge (v, x) not removed (a duplicate found at another
    // edge), each compared with those kept before it.
    live.clear();
    for (std::int32_t j = 0; j < k; ++j) {
      const std::int32_t hj = b[j];
      if (removed[fl.face_of(hj)]) continue;
      const auto same = std::find_if(live.begin(), live.end(), [&](std::int32_t g) { return fl.same_face(g, hj); });
      if (same != live.end())
        drop_duplicate(*same, hj);
      else
        live.push_back(hj);
    }
    if (live.size() == 2) {
      mate[live[0]] = live[1];
      mate[live[1]] = live[0];
    } else if (live.size() > 2) {
      rep.nonmanifold_edges.push_back({v, x});
      sheet_end[v] = sheet_end[x] = 1;
      for (std::size_t p = 0; p < live.size() && pair_sheets; ++p) {
        if (mate[live[p]] >= 0) continue;
        std::size_t partner = 0;
        for (std::size_t q = p + 1; q < live.size() && !partner; ++q)
          if (mate[live[q]] < 0 && faces[live[q]] != faces[live[p]]) partner = q;
        for (std::size_t q = p + 1; q < live.size() && !partner; ++q)
          if (mate[live[q]] < 0) partner = q;
        if (!partner) break;
        mate[live[p]] = live[partner];
        mate[live[partner]] = live[p];
        paired[live[p]] = paired[live[partner]] = 1;
      }
    }
  });
  std::sort(rep.duplicate_faces.begin(), rep.duplicate_faces.end());
  std::sort(rep.reversed_duplicate_faces.begin(), rep.reversed_duplicate_faces.end());
  std::sort(rep.nonmanifold_edges.begin(), rep.nonmanifold_edges.end());
  return mate;
}

// Whether the faces of joined half-edges h and g run their edge the same way
// (then one of them must be reversed).
inline bool same_way(const std::int32_t* faces, std::int32_t h, std::int32_t g) { return faces[h] == faces[g]; }

// An edge (lower, higher end) for the report.
inline std::array<std::int32_t, 2> edge_of(const std::int32_t* faces, std::size_t h, std::size_t h_next) {
  return {std::min(faces[h], faces[h_next]), std::max(faces[h], faces[h_next])};
}

void sort_unique(std::vector<std::array<std::int32_t, 2>>& edges) {
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
}

// Rules 4 and 6 of repair.hpp: breaks (sets to -1 in `mate`) the joins that
// no orientation of the faces keeps, so that every connected part can be
// oriented, and returns for each face whether to reverse it (empty: none).
// First the joins of edges of two faces, per part joined by them: a
// breadth-first search orients the faces it reaches; where a join disagrees
// (a twist), a second search from the face farthest from the part's boundary
// breaks each join that disagrees ("cut_edges", their ends marked in
// `cut_end`); then the pairs of faces at edges of three or more
// (`paired`), in half-edge order: a pair that would join two parts already
// oriented against each other is broken ("cut_nonmanifold_edges"), every
// other pair joins its two parts. The joins broken are then exactly those
// that disagree with one orientation of the whole, and each fan round a
// vertex holds an even number of them or is not closed, so that every
// broken join separates its two faces at both ends of the edge (rule 5).
// The union-find's classes are then the connected parts, each rooted at its
// lowest face, against which every face's `odd` says its orientation.
template <bool kPolygons>
std::vector<std::uint8_t> orient(const Faces<kPolygons>& fl, std::vector<std::int32_t>& mate,
                                 const std::vector<std::uint8_t>& paired, const std::vector<std::uint8_t>& removed,
                                 RepairReport& rep, std::vector<std::uint8_t>& cut_end) {
  const std::int32_t* faces = fl.idx;
  const std::size_t n_faces = fl.n_faces, n_half = fl.n_corners();
  bool any_same_way = false;
  for (std::size_t h = 0; h < n_half && !any_same_way; ++h)
    any_same_way = mate[h] >= 0 && same_way(faces, static_cast<std::int32_t>(h), mate[h]);
  if (!any_same_way) return {};  // every join keeps the faces as they are
  auto cut = [&](std::int32_t h) {
    const std::int32_t g = mate[h];
    mate[h] = mate[g] = -1;
    return edge_of(faces, static_cast<std::size_t>(h), fl.next(h));
  };
  // The parts joined by edges of two faces: `up` is each face's part (its
  // lowest face), `odd` whether the face is reversed against that face.
  std::vector<std::int32_t> up(n_faces, -1), queue, depth;
  std::vector<std::uint8_t> odd(n_faces, 0);
  auto joined = [&](std::int32_t h) { return mate[h] >= 0 && !paired[h]; };
  // The breadth-first search of part `part` from face `root` (queue: the
  // part's faces in the order reached); with `cut`, breaks each join that
  // disagrees; returns whether one does.
  auto search = [&](std::int32_t root, std::int32_t part, bool cut_them) {
    bool twisted = false;
    queue.assign(1, root);
    up[root] = part;
    odd[root] = 0;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::int32_t f = queue[q];
      for (std::int32_t h = fl.begin(f); h < fl.end(f); ++h) {
        if (!joined(h)) continue;
        const std::int32_t g = mate[h], fg = fl.face_of(g);
        const auto want = static_cast<std::uint8_t>(odd[f] ^ same_way(faces, h, g));
        if (up[fg] < 0) {
          up[fg] = part;
          odd[fg] = want;
          queue.push_back(fg);
        } else if (odd[fg] != want) {
          twisted = true;
          if (!cut_them) continue;
          const auto e = cut(h);
          rep.cut_edges.push_back(e);
          cut_end[e[0]] = cut_end[e[1]] = 1;
        }
      }
    }
    return twisted;
  };
  // The face of a part farthest from its boundary (the faces with an edge
  // not joined; the lowest face of those farthest), or `part` where it has
  // none: searched from there, a twist is cut where the fronts meet, across
  // a band from side to side rather than on a slant.
  auto farthest_from_boundary = [&](std::int32_t part) {
    depth.resize(n_faces);
    std::vector<std::int32_t> ring;
    for (std::int32_t f : queue) {
      depth[f] = -1;
      for (std::int32_t h = fl.begin(f); h < fl.end(f) && depth[f] < 0; ++h)
        if (!joined(h)) depth[f] = 0;
      if (depth[f] == 0) ring.push_back(f);
    }
    if (ring.empty()) return part;
    std::int32_t best = part;
    for (std::size_t q = 0; q < ring.size(); ++q) {
      const std::int32_t f = ring[q];
      if (depth[f] > depth[best] || (depth[f] == depth[best] && f < best)) best = f;
      for (std::int32_t h = fl.begin(f); h < fl.end(f); ++h) {
        if (!joined(h)) continue;
        const std::int32_t fg = fl.face_of(mate[h]);
        if (depth[fg] < 0) {
          depth[fg] = depth[f] + 1;
          ring.push_back(fg);
        }
      }
    }
    return best;
  };
  for (std::size_t fi = 0; fi < n_faces; ++fi) {
    const auto f0 = static_cast<std::int32_t>(fi);
    if (removed[f0] || up[f0] >= 0 || !search(f0, f0, false)) continue;
    // A twist: searched again from the face farthest from the boundary,
    // cutting; `odd` then made relative to the part's lowest face.
    const std::int32_t root = farthest_from_boundary(f0);
    for (std::int32_t f : queue) up[f] = -1;
    search(root, f0, true);
    const std::uint8_t at_f0 = odd[f0];
    for (std::int32_t f : queue) odd[f] ^= at_f0;
  }
  // The pairs at edges of three or more faces join parts: `up` and `odd`
  // become a union-find over the faces, `odd` whether a face is reversed
  // against the one `up` names.
  auto find = [&](std::int32_t f) {  // the root of face f, and whether f is reversed against it
    std::int32_t root = f;
    std::uint8_t flipped = 0;
    for (; up[root] != root; root = up[root]) flipped ^= odd[root];
    for (std::uint8_t rest = flipped; up[f] != f;) {  // path compression
      const std::int32_t next = up[f];
      const std::uint8_t step = odd[f];
      up[f] = root;
      odd[f] = rest;
      rest ^= step;
      f = next;
    }
    return std::make_pair(root, flipped);
  };
  for (std::size_t hi = 0; hi < n_half; ++hi) {
    const auto h = static_cast<std::int32_t>(hi);
    const std::int32_t g = mate[h];
    if (g < h || !paired[h]) continue;
    const auto [ph, oh] = find(fl.face_of(h));
    const auto [pg, og] = find(fl.face_of(g));
    const auto differ = static_cast<std::uint8_t>(same_way(faces, h, g));  // the two faces' orientations must differ
    if (ph != pg) {
      const std::int32_t lo = std::min(ph, pg), other = std::max(ph, pg);
      up[other] = lo;
      odd[other] = static_cast<std::uint8_t>(oh ^ og ^ differ);
    } else if ((oh ^ og) != differ) {
      rep.cut_nonmanifold_edges.push_back(cut(h));
    }
  }
  sort_unique(rep.cut_edges);
  sort_unique(rep.cut_nonmanifold_edges);
  // Rule 6: per part, the smaller class reversed (on a tie, the faces
  // disagreeing with its lowest face, the root).
  std::vector<std::int32_t> n_faces_of(n_faces, 0), n_odd(n_faces, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (removed[f]) continue;
    const auto [root, flipped] = find(static_cast<std::int32_t>(f));  // compressed: up[f] is the root from now on
    ++n_faces_of[root];
    n_odd[root] += flipped;
  }
  std::vector<std::uint8_t> flip(n_faces, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (removed[f]) continue;
    const std::int32_t root = up[f];
    flip[f] = odd[f] == (n_odd[root] <= n_faces_of[root] - n_odd[root] ? 1 : 0);
    if (flip[f]) rep.flipped_faces.push_back(static_cast<std::int32_t>(f));
  }
  return flip;
}

// Rule 5: the output vertex of each corner of the faces not removed (-1 for
// the others): one per fan, the corners of one vertex joined across joined
// edges. `vertex_map` holds the input vertices on entry; the copies are
// appended, and counted per input vertex in `copies`.
template <bool kPolygons>
std::vector<std::int32_t> fan_vertices(const Faces<kPolygons>& fl, const std::vector<std::int32_t>& mate,
                                       const std::vector<std::uint8_t>& removed, std::vector<std::int32_t>& vertex_map,
                                       std::vector<std::int32_t>& copies) {
  const std::int32_t* faces = fl.idx;
  const std::size_t n_half = fl.n_corners();
  Corners fans(n_half);
  for (std::size_t h = 0; h < n_half; ++h) {
    const std::int32_t g = mate[h];
    if (g < static_cast<std::int32_t>(h)) continue;  // unjoined, or joined from g already
    const auto hn = static_cast<std::int32_t>(fl.next(h)), gn = static_cast<std::int32_t>(fl.next(g));
    const bool same_way = faces[g] == faces[h];
    fans.unite(static_cast<std::int32_t>(h), same_way ? g : gn);
    fans.unite(hn, same_way ? gn : g);
  }
  // A fan's root is its lowest corner, so in corner order the root's vertex
  // is known before the fan's other corners.
  std::vector<std::int32_t> vertex_of(n_half, -1);
  std::vector<std::uint8_t> taken(copies.size(), 0);
  for (std::size_t h = 0; h < n_half; ++h) {
    if (removed[fl.face_of(h)]) continue;
    const std::int32_t root = fans.find(static_cast<std::int32_t>(h));
    if (root != static_cast<std::int32_t>(h)) {
      vertex_of[h] = vertex_of[root];
      continue;
    }
    const std::int32_t v = faces[h];
    if (!taken[v]) {
      taken[v] = 1;
      vertex_of[h] = v;
    } else {
      vertex_of[h] = static_cast<std::int32_t>(vertex_map.size());
      vertex_map.push_back(v);
      ++copies[v];
    }
  }
  return vertex_of;
}

// One pass of the rules in repair.hpp over valid indices; without
// `pair_sheets`, every face of an edge of three or more borders it alone.
// The output faces are polygons (with face_vertex_counts) unless `input` is triangles.
template <bool kPolygons>
RepairResult repair_pass(const FaceList& input, std::size_t n_vertices, bool pair_sheets) {
  RepairResult r;
  RepairReport& rep = r.report;
  std::vector<std::uint8_t> removed(input.n_faces, 0);
  const OwnedFaces collapsed = drop_repeated_corners(input, n_vertices, removed, rep);
  const Faces<kPolygons> fl{collapsed.empty() ? input : collapsed.view()};
  const std::size_t n_faces = fl.n_faces, n_half = fl.n_corners();
  std::vector<std::uint8_t> sheet_end(n_vertices, 0), cut_end(n_vertices, 0), paired(n_half, 0);
  std::vector<std::int32_t> mate = join_edges(fl, n_vertices, pair_sheets, removed, rep, sheet_end, paired);
  const std::vector<std::uint8_t> flip = orient(fl, mate, paired, removed, rep, cut_end);

  std::vector<std::int32_t> copies(n_vertices, 0);
  r.vertex_map.resize(n_vertices);
  std::iota(r.vertex_map.begin(), r.vertex_map.end(), 0);
  const std::vector<std::int32_t> vertex_of = fan_vertices(fl, mate, removed, r.vertex_map, copies);
  for (std::size_t vi = 0; vi < n_vertices; ++vi) {
    if (!copies[vi]) continue;
    const auto v = static_cast<std::int32_t>(vi);
    if (sheet_end[v]) {
      rep.sheet_vertices.push_back(v);
      rep.sheet_copies.push_back(copies[v]);
    } else if (cut_end[v]) {
      rep.cut_vertices.push_back(v);
      rep.cut_copies.push_back(copies[v]);
    } else {
      rep.bowtie_vertices.push_back(v);
      rep.bowtie_copies.push_back(copies[v]);
    }
  }


  // A reversed face keeps its first corner: (a, b, c, d) becomes (a, d, c, b).
  r.faces.face_vertex_indices.reserve(n_half);
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (removed[f]) continue;
    const std::int32_t lo = fl.begin(f), hi = fl.end(f);
    r.faces.face_vertex_indices.push_back(vertex_of[lo]);
    if (!flip.empty() && flip[f])
      for (std::int32_t h = hi - 1; h > lo; --h) r.faces.face_vertex_indices.push_back(vertex_of[h]);
    else
      for (std::int32_t h = lo + 1; h < hi; ++h) r.faces.face_vertex_indices.push_back(vertex_of[h]);
    if (kPolygons) r.faces.face_vertex_counts.push_back(hi - lo);
    r.face_map.push_back(static_cast<std::int32_t>(f));
  }
  return r;
}

// `later`, a pass over `first`'s output, in `first`'s input indices, appended to `first`.
void compose(RepairResult& first, RepairResult&& later) {
  RepairReport& a = first.report;
  const RepairReport& b = later.report;
  auto faces_of = [&](const std::vector<std::int32_t>& fs, std::vector<std::int32_t>& into) {
    for (std::int32_t f : fs) into.push_back(first.face_map[f]);
    std::sort(into.begin(), into.end());
  };
  faces_of(b.degenerate_faces, a.degenerate_faces);
  faces_of(b.collapsed_faces, a.collapsed_faces);
  faces_of(b.duplicate_faces, a.duplicate_faces);
  faces_of(b.reversed_duplicate_faces, a.reversed_duplicate_faces);
  std::vector<std::int32_t> flipped;
  faces_of(b.flipped_faces, flipped);
  std::vector<std::int32_t> both;  // reversed twice: not reversed
  std::set_symmetric_difference(a.flipped_faces.begin(), a.flipped_faces.end(), flipped.begin(), flipped.end(),
                                std::back_inserter(both));
  a.flipped_faces = std::move(both);
  auto edges_of = [&](const std::vector<std::array<std::int32_t, 2>>& es,
                      std::vector<std::array<std::int32_t, 2>>& into) {  // an edge of both passes once
    for (const auto& [u, v] : es) {
      const std::int32_t p = first.vertex_map[u], q = first.vertex_map[v];
      into.push_back({std::min(p, q), std::max(p, q)});
    }
    sort_unique(into);
  };
  edges_of(b.nonmanifold_edges, a.nonmanifold_edges);
  edges_of(b.cut_nonmanifold_edges, a.cut_nonmanifold_edges);
  edges_of(b.cut_edges, a.cut_edges);
  auto add_copies = [&](const std::vector<std::int32_t>& vs, const std::vector<std::int32_t>& ns,
                        std::vector<std::int32_t>& into_v, std::vector<std::int32_t>& into_n) {
    for (std::size_t i = 0; i < vs.size(); ++i) {
      const std::int32_t v = first.vertex_map[vs[i]];
      const auto at = std::find(into_v.begin(), into_v.end(), v);
      if (at != into_v.end()) {
        into_n[at - into_v.begin()] += ns[i];
      } else {
        const auto pos = std::lower_bound(into_v.begin(), into_v.end(), v) - into_v.begin();
        into_v.insert(into_v.begin() + pos, v);
        into_n.insert(into_n.begin() + pos, ns[i]);
      }
    }
  };
  add_copies(b.sheet_vertices, b.sheet_copies, a.sheet_vertices, a.sheet_copies);
  add_copies(b.bowtie_vertices, b.bowtie_copies, a.bowtie_vertices, a.bowtie_copies);
  add_copies(b.cut_vertices, b.cut_copies, a.cut_vertices, a.cut_copies);
  std::vector<std::int32_t> vertex_map(later.vertex_map.size()), face_map(later.face_map.size());
  for (std::size_t i = 0; i < vertex_map.size(); ++i) vertex_map[i] = first.vertex_map[later.vertex_map[i]];
  for (std::size_t i = 0; i < face_map.size(); ++i) face_map[i] = first.face_map[later.face_map[i]];
  first.vertex_map = std::move(vertex_map);
  first.face_map = std::move(face_map);
  first.faces = std::move(later.faces);
}

}  // namespace

namespace {

// Throws sorpia::Topology's MeshError for faces it refuses.
void validate(const Mesh& faces, std::size_t n_vertices) { static_cast<void>(Topology(faces, n_vertices)); }

// The index checks repair does not change (`fl` the FaceList of `faces`), by the validation's message.
void check_indices(const Mesh& faces, const FaceList& fl, std::size_t n_vertices) {
  const bool ok = fl.n_faces > 0 && n_vertices <= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) &&
                  std::all_of(fl.idx, fl.idx + fl.n_corners(), [&](std::int32_t v) {
                    return v >= 0 && static_cast<std::size_t>(v) < n_vertices;
                  });
  if (!ok) {
    validate(faces, n_vertices);
    throw std::logic_error("sorpia::split_nonmanifold: the validation accepted faces with an index out of range");
  }
}

// repair() of faces sorpia::Topology refuses (`fl` their FaceList).
RepairResult repair_faces(const Mesh& faces, const FaceList& fl, std::size_t n_vertices) {
  check_indices(faces, fl, n_vertices);  // what repair does not change: refused as the validation refuses it
  const bool polygons = !faces.all_triangles();
  auto pass = [&](const FaceList& in, std::size_t n, bool pair_sheets) {
    return polygons ? repair_pass<true>(in, n, pair_sheets) : repair_pass<false>(in, n, pair_sheets);
  };
  RepairResult result = pass(fl, n_vertices, true);
  if (result.faces.face_vertex_indices.empty())
    throw MeshError("every face repeats a vertex (" + std::to_string(fl.n_faces) +
                    " degenerate faces): no face is left, and subdivision needs at least one face");
  // Pairing sheets can join them into one fan at both ends of their edge (two
  // sheets that touch along several edges), which leaves that edge with more
  // than two faces: a further pass makes each face of such an edge border it alone.
  constexpr int max_passes = 4;
  for (int n_pass = 1;; ++n_pass) {
    const std::size_t n_out = result.vertex_map.size();
    if (faces_valid(result.faces, n_out)) return result;
    const FaceArrays arrays = FaceArrays::of(result.faces);
    RepairResult next;
    if (n_pass < max_passes) next = pass(arrays.over(result.faces), n_out, false);
    if (next.report.empty()) {  // nothing more repair changes (e.g. a vertex of too many edges)
      try {
        validate(result.faces, n_out);
      } catch (const MeshError& e) {
        throw MeshError(std::string("repair could not make a valid mesh: ") + e.what());
      }
      throw std::logic_error("sorpia::repair: faces_valid and Topology disagree");
    }
    compose(result, std::move(next));
  }
}

}  // namespace

// A valid mesh costs the validation alone, and comes back as it is.
RepairResult repair(const Mesh& faces, std::size_t n_vertices) {
  if (faces_valid(faces, n_vertices)) return {};  // before FaceArrays: a valid mesh allocates nothing
  const FaceArrays arrays = FaceArrays::of(faces);
  return repair_faces(faces, arrays.over(faces), n_vertices);
}

namespace {

// split_nonmanifold (repair.hpp) over valid indices.
template <bool kPolygons>
NonmanifoldSplit split_pass(const Faces<kPolygons>& fl, std::size_t n_vertices) {
  NonmanifoldSplit s;
  const std::int32_t* faces = fl.idx;
  const std::size_t n_half = fl.n_corners();
  std::vector<std::int32_t> stamp(n_vertices, -1), n_faces_at(n_vertices, 0);
  for (std::size_t f = 0; f < fl.n_faces; ++f)
    for (std::int32_t h = fl.begin(f); h < fl.end(f); ++h) {
      if (stamp[faces[h]] == static_cast<std::int32_t>(f))
        throw MeshError(fl.str(f) + " repeats vertex " + std::to_string(faces[h]) +
                        ": nonmanifold=\"sharp\" keeps every face as it is, and a face cannot repeat a vertex "
                        "(OpenSubdiv makes a degenerate edge of it); sorpia.repair (--repair) drops the repeat");
      stamp[faces[h]] = static_cast<std::int32_t>(f);
      ++n_faces_at[faces[h]];
    }
  std::vector<std::int32_t> mate(n_half, -1), n_edges(n_vertices, 0), n_boundary(n_vertices, 0),
      n_nonmanifold(n_vertices, 0);
  std::vector<std::array<std::int32_t, 2>> nonmanifold_ends(n_vertices, {-1, -1});  // the first two
  auto nonmanifold_end = [&](std::int32_t v, std::int32_t x) {
    if (n_nonmanifold[v] < 2) nonmanifold_ends[v][n_nonmanifold[v]] = x;
    ++n_nonmanifold[v];
  };
  const detail::EdgeGroups edges(fl, n_vertices);
  std::vector<std::pair<const std::int32_t*, std::int32_t>> nonmanifold_groups;  // their half-edges, in `edges`
  edges.for_each([&](std::int32_t v, std::int32_t x, const std::int32_t* b, std::int32_t k) {
    ++n_edges[v];
    ++n_edges[x];
    if (k == 1) {
      ++n_boundary[v];
      ++n_boundary[x];
    } else if (k == 2 && faces[b[0]] != faces[b[1]]) {
      mate[b[0]] = b[1];
      mate[b[1]] = b[0];
    } else {
      s.nonmanifold_edges.push_back({v, x});
      nonmanifold_groups.emplace_back(b, k);
      nonmanifold_end(v, x);
      nonmanifold_end(x, v);
    }
  });
  const std::vector<std::uint8_t> removed(fl.n_faces, 0);
  std::vector<std::int32_t> copies(n_vertices, 0);
  s.vertex_map.resize(n_vertices);
  std::iota(s.vertex_map.begin(), s.vertex_map.end(), 0);
  const std::vector<std::int32_t> vertex_of = fan_vertices(fl, mate, removed, s.vertex_map, copies);

  // Two faces of a non-manifold edge that run it opposite ways and lie in one
  // fan at each end (a pillow beside a third face: joined through the
  // pillow's other edges) have the same output vertices at both ends: the
  // split mesh joins them across that edge, which OpenSubdiv makes
  // infinitely sharp (sharp_edges). Two faces of an edge lie in one fan only
  // as its two open ends, so no output edge gets more than two faces.
  for (const auto& [b, k] : nonmanifold_groups)
    for (std::int32_t i = 0; i < k; ++i)
      for (std::int32_t j = i + 1; j < k; ++j) {
        const std::int32_t g = b[i], h = b[j];
        if (faces[g] != faces[h] && vertex_of[g] == vertex_of[fl.next(h)] && vertex_of[fl.next(g)] == vertex_of[h])
          s.sharp_edges.push_back({std::min(vertex_of[g], vertex_of[h]), std::max(vertex_of[g], vertex_of[h])});
      }
  std::sort(s.sharp_edges.begin(), s.sharp_edges.end());
  std::vector<std::uint8_t> crease(n_vertices, 0);
  for (std::size_t vi = 0; vi < n_vertices; ++vi) {
    if (n_nonmanifold[vi] == 0 && copies[vi] == 0) continue;
    const auto v = static_cast<std::int32_t>(vi);
    s.nonmanifold_vertices.push_back(v);
    crease[v] = n_nonmanifold[v] == 2 && n_boundary[v] == 0 && n_faces_at[v] > n_edges[v];
    if (!crease[v]) s.corners.push_back(v);
  }
  // Each fan of a crease vertex must lie between copies of its two
  // non-manifold edges (the boundary rule of the split is then its crease
  // rule): per output vertex, its faces and the far ends of its open edges.
  const std::size_t n_out = s.vertex_map.size();
  std::vector<std::int32_t> fan_faces(n_out, 0), n_open(n_out, 0);
  std::vector<std::array<std::int32_t, 2>> open_ends(n_out, {-1, -1});
  auto open_end = [&](std::int32_t o, std::int32_t x) {
    if (n_open[o] < 2) open_ends[o][n_open[o]] = x;
    ++n_open[o];
  };
  for (std::size_t h = 0; h < n_half; ++h) {
    const std::int32_t v = faces[h];
    if (!crease[v]) continue;
    const std::int32_t o = vertex_of[h];
    ++fan_faces[o];
    if (mate[h] < 0) open_end(o, faces[fl.next(h)]);
    if (mate[fl.prev(h)] < 0) open_end(o, faces[fl.prev(h)]);
  }
  for (std::size_t o = 0; o < n_out; ++o) {
    const std::int32_t v = s.vertex_map[o];
    if (!crease[v]) continue;
    auto ends = open_ends[o], want = nonmanifold_ends[v];
    std::sort(ends.begin(), ends.end());
    std::sort(want.begin(), want.end());
    if (n_open[o] != 2 || ends != want || want[0] == want[1])
      throw MeshError("vertex " + std::to_string(v) + " is on an interior non-manifold crease (edges (" +
                      std::to_string(v) + ", " + std::to_string(want[0]) + ") and (" + std::to_string(v) + ", " +
                      std::to_string(want[1]) + "), where OpenSubdiv gives it the crease rule), but one of its fans "
                      "of faces does not lie between those two edges: nonmanifold=\"sharp\" cannot reproduce "
                      "OpenSubdiv's rule there; sorpia.repair (--repair) makes the mesh manifold");
    if (fan_faces[o] == 1 &&
        (s.single_face_sheets.empty() || s.single_face_sheets.back() != v))
      s.single_face_sheets.push_back(v);
  }
  std::sort(s.single_face_sheets.begin(), s.single_face_sheets.end());
  s.single_face_sheets.erase(std::unique(s.single_face_sheets.begin(), s.single_face_sheets.end()),
                             s.single_face_sheets.end());
  if (s.empty()) return {};
  s.faces.face_vertex_indices.reserve(n_half);
  for (std::size_t h = 0; h < n_half; ++h) s.faces.face_vertex_indices.push_back(vertex_of[h]);
  return s;
}

}  // namespace

NonmanifoldSplit split_nonmanifold(const Mesh& faces, std::size_t n_vertices) {
  if (faces_valid(faces, n_vertices)) return {};
  const FaceArrays arrays = FaceArrays::of(faces);
  const FaceList fl = arrays.over(faces);
  check_indices(faces, fl, n_vertices);
  NonmanifoldSplit s = faces.all_triangles() ? split_pass(Faces<false>{fl}, n_vertices)
                                             : split_pass(Faces<true>{fl}, n_vertices);
  if (!s.empty()) {  // faces are neither removed nor resized: the input's counts
    s.faces.face_vertex_counts = faces.face_vertex_counts;
    s.faces.face_size = faces.face_size;
  }
  return s;
}

}  // namespace sorpia
