#include "fairness_elements.hpp"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace sorpia::fairness_detail {

namespace {

// The control points of an interior face listed from the topology, for
// faces whose corners are all interior (Bfr is then not asked): the face's
// corners, then for each corner i its ring (Catmull-Clark: each edge
// neighbour followed by the opposite corner of the face after it) from the
// next corner on, clockwise, each vertex once. Where the corners' rings meet
// only as they must around one face (a number of repeats fixed by the face's
// size: 9 for a triangle, 20 for a quad), this is the face's neighbourhood,
// the vertices its surface depends on, in an order fixed by the corners'
// valences; otherwise (rings that wrap around and meet again) it returns
// false. `stamp` marks listed vertices with `mark` (no clearing needed).
bool topology_control_points(const Topology& t, bool quads, std::size_t f, std::vector<std::int32_t>& out,
                             std::vector<std::int32_t>& stamp, std::int32_t mark) {
  const std::int32_t k = t.face_size(f);
  if (k != (quads ? 4 : 3)) return false;
  const std::int32_t* vs = t.face_indices().data() + t.face_offset(f);
  for (std::int32_t i = 0; i < k; ++i) {
    const auto v = static_cast<std::size_t>(vs[i]);
    if (t.is_boundary(v) || (quads && !t.quad_ring(v))) return false;
  }
  out.clear();
  int repeats = 0;
  const auto list = [&](std::int32_t u) {
    if (stamp[static_cast<std::size_t>(u)] == mark) {
      ++repeats;
      return;
    }
    stamp[static_cast<std::size_t>(u)] = mark;
    out.push_back(u);
  };
  for (std::int32_t i = 0; i < k; ++i) list(vs[i]);
  repeats = 0;
  const auto& ro = t.ring_offsets();
  const auto& rn = t.ring_neighbors();
  for (std::int32_t i = 0; i < k; ++i) {
    const auto v = static_cast<std::size_t>(vs[i]);
    const std::int32_t b = ro[v], n = ro[v + 1] - b;
    std::int32_t s0 = 0;
    while (s0 < n && rn[static_cast<std::size_t>(b + s0)] != vs[(i + 1) % k]) ++s0;
    if (s0 == n) return false;
    for (std::int32_t j = 0; j < n; ++j) {
      const std::int32_t at = (s0 + j) % n;
      list(rn[static_cast<std::size_t>(b + at)]);
      if (quads) list(t.face_ring_neighbors()[static_cast<std::size_t>(t.face_ring_offsets()[v] + at)]);
    }
  }
  return repeats == (quads ? 20 : 9);
}

}  // namespace

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
Elements face_classes(const LimitSurface& surface, const std::vector<std::uint8_t>& hole, bool reuse) {
  const Topology& t = surface.topology();
  Elements s;
  s.face_class.assign(t.n_faces(), -1);
  const auto own_class = [&](std::size_t f) {
    s.face_class[f] = static_cast<std::int32_t>(s.representative.size());
    s.representative.push_back(static_cast<std::int32_t>(f));
    s.shared.push_back(0);
  };
  if (!reuse) {
    for (std::size_t f = 0; f < t.n_faces(); ++f)
      if (!hole[f]) own_class(f);
    s.own_columns.resize(s.representative.size());
    s.element.resize(s.representative.size());
    return s;
  }
  const Tags& tags = surface.tags();
  const std::int32_t regular_size = surface.scheme() == Scheme::Loop ? 3 : 4;
  const auto& fi = t.face_indices();
  std::vector<std::uint8_t> special(t.n_vertices(), 0);
  for (std::size_t f = 0; f < t.n_faces(); ++f)
    if (hole[f] || t.face_size(f) != regular_size)
      for (std::int32_t i = 0; i < t.face_size(f); ++i) special[static_cast<std::size_t>(fi[t.face_offset(f) + i])] = 1;
  for (const std::int32_t v : tags.corner_vertices) special[static_cast<std::size_t>(v)] = 1;
  for (const std::int32_t v : tags.crease_vertices) special[static_cast<std::size_t>(v)] = 1;

  std::vector<std::int32_t> live;
  s.slot.assign(t.n_faces(), -1);
  for (std::size_t f = 0; f < t.n_faces(); ++f)
    if (!hole[f]) {
      s.slot[f] = static_cast<std::int64_t>(live.size());
      live.push_back(static_cast<std::int32_t>(f));
    }
  // Control points: from the topology where it gives them (regular[] = 2
  // for those, a key of their own), Bfr's for the other faces.
  {
    const bool quads = surface.scheme() == Scheme::CatmullClark;
    std::vector<std::int32_t> stamp(t.n_vertices(), -1), listed, ask;
    std::vector<std::int64_t> from_topology(live.size(), -1);  // per live face: its start in `listed`, or -1
    std::vector<std::int32_t> topo_indices;
    for (std::size_t l = 0; l < live.size(); ++l) {
      const auto f = static_cast<std::size_t>(live[l]);
      if (topology_control_points(t, quads, f, listed, stamp, static_cast<std::int32_t>(f))) {
        from_topology[l] = static_cast<std::int64_t>(topo_indices.size());
        topo_indices.insert(topo_indices.end(), listed.begin(), listed.end());
        topo_indices.push_back(-1);  // end of this face's list
      } else {
        ask.push_back(live[l]);
      }
    }
    const FaceControlPoints bfr = surface.control_points(ask.data(), ask.size());
    s.cps.offsets.assign(1, 0);
    s.cps.indices.reserve(topo_indices.size() + bfr.indices.size());
    s.cps.regular.reserve(live.size());
    std::size_t a = 0;
    for (std::size_t l = 0; l < live.size(); ++l) {
      if (from_topology[l] >= 0) {
        for (auto p = static_cast<std::size_t>(from_topology[l]); topo_indices[p] >= 0; ++p)
          s.cps.indices.push_back(topo_indices[p]);
        s.cps.regular.push_back(2);
      } else {
        s.cps.indices.insert(s.cps.indices.end(), bfr.indices.begin() + bfr.offsets[a],
                             bfr.indices.begin() + bfr.offsets[a + 1]);
        s.cps.regular.push_back(bfr.regular[a]);
        ++a;
      }
      s.cps.offsets.push_back(static_cast<std::int64_t>(s.cps.indices.size()));
    }
  }
  const auto& ro = t.ring_offsets();
  const auto& rn = t.ring_neighbors();
  struct KeyHash {
    std::size_t operator()(const std::vector<std::int32_t>& key) const {
      std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the entries
      for (const std::int32_t x : key) h = (h ^ static_cast<std::uint32_t>(x)) * 1099511628211ull;
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<std::vector<std::int32_t>, std::int32_t, KeyHash> classes;
  std::vector<std::int32_t> key, repeats;
  // Per vertex, the last face that listed it and its place in that list.
  std::vector<std::int32_t> seen(t.n_vertices(), -1), seen_at(t.n_vertices(), -1);
  for (const std::int32_t f : live) {
    const auto uf = static_cast<std::size_t>(f);
    const auto sl = static_cast<std::size_t>(s.slot[uf]);
    const std::int32_t* cv = s.cps.indices.data() + s.cps.offsets[sl];
    const auto n_cv = static_cast<std::size_t>(s.cps.offsets[sl + 1] - s.cps.offsets[sl]);
    bool alone = false;  // a special control point
    repeats.clear();
    for (std::size_t i = 0; i < n_cv && !alone; ++i) {
      const auto v = static_cast<std::size_t>(cv[i]);
      alone = special[v] != 0;
      if (seen[v] == f) {
        repeats.insert(repeats.end(), {static_cast<std::int32_t>(i), seen_at[v]});
      } else {
        seen[v] = f;
        seen_at[v] = static_cast<std::int32_t>(i);
      }
    }
    if (alone) {
      own_class(uf);
      continue;
    }
    const std::int32_t k = t.face_size(uf);
    const std::int32_t* vs = fi.data() + t.face_offset(uf);
    key.assign({static_cast<std::int32_t>(n_cv), s.cps.regular[sl], k});
    for (std::int32_t i = 0; i < k; ++i) {
      const auto v = static_cast<std::size_t>(vs[i]);
      const bool boundary = t.is_boundary(v);
      std::int32_t place = -1;
      if (boundary)
        place = static_cast<std::int32_t>(std::find(rn.begin() + ro[v], rn.begin() + ro[v + 1], vs[(i + 1) % k]) -
                                          (rn.begin() + ro[v]));
      key.insert(key.end(), {t.valence(v), boundary ? 1 : 0, place});
    }
    key.insert(key.end(), repeats.begin(), repeats.end());
    auto it = classes.find(key);  // looked up first: emplace would build a node (a copy of the key) every time
    if (it == classes.end()) {
      it = classes.emplace(key, static_cast<std::int32_t>(s.representative.size())).first;
      s.representative.push_back(f);
      s.shared.push_back(1);
    }
    s.face_class[uf] = it->second;
  }
  s.own_columns.resize(s.representative.size());
  s.element.resize(s.representative.size());
  return s;
}

}  // namespace sorpia::fairness_detail
