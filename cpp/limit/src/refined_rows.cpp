// Rows of B from OpenSubdiv's refinement and Limit() on local meshes, and the
// whole-mesh reference the tests compare them with.
#include "refined_rows.hpp"

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "sorpia/detail/dart_rows.hpp"
#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/errors.hpp"

namespace sorpia::detail {

namespace {

int decay_levels(float s) { return s > 0.0f && s < kInfiniteSharpness ? static_cast<int>(std::ceil(s)) : 0; }

// The vertices of face f.
struct FaceVertices {
  const std::int32_t* begin;
  int size;
};
FaceVertices face_vertices(const Topology& topology, std::size_t f) {
  return {topology.face_indices().data() + topology.face_offset(f), topology.face_size(f)};
}

bool is_edge(const Topology& topology, std::int32_t a, std::int32_t b) {
  const auto& ring = topology.ring_neighbors();
  const auto* first = ring.data() + topology.ring_offsets()[a];
  const auto* last = ring.data() + topology.ring_offsets()[a + 1];
  return std::find(first, last, b) != last;
}

// A primvar that is a dense row of weights over the local mesh's first level
// (what PrimvarRefinerReal combines with Clear and AddWithWeight).
struct RowRef {
  double* w;
  int n;
  void Clear() { std::fill(w, w + n, 0.0); }
  void AddWithWeight(const RowRef& src, double weight) {
    for (int k = 0; k < n; ++k) w[k] += weight * src.w[k];
  }
};
struct Rows {
  double* data;
  int n;
  RowRef operator[](int i) const { return RowRef{data + static_cast<std::size_t>(i) * n, n}; }
};

// The faces incident to one vertex (local index 0) with its tags (creases as
// (0, other); its own sharpness as a corner at 0).
using LocalMesh = RefinerInput;

void set_centre_sharpness(LocalMesh& m, float s) {
  if (s > 0.0f) {
    m.corners.assign(1, 0);
    m.corner_sharpness.assign(1, s);
  }
}

// The local mesh of the child `c` of the centre in `level` (its faces, the
// sharpness of its edges and its own, the holes among its faces); `to_local`
// (level's vertex count, all -1) gets the local index of each vertex taken and
// is reset; `taken` lists them, c first.
LocalMesh child_mesh(const Far::TopologyLevel& level, int c, std::vector<int>& to_local, std::vector<int>& taken) {
  LocalMesh m;
  taken.assign(1, c);
  to_local[c] = 0;
  for (const int f : level.GetVertexFaces(c)) {
    if (level.IsFaceHole(f)) m.holes.push_back(static_cast<int>(m.counts.size()));
    const auto fv = level.GetFaceVertices(f);
    m.counts.push_back(fv.size());
    for (const int u : fv) {
      if (to_local[u] < 0) {
        to_local[u] = static_cast<int>(taken.size());
        taken.push_back(u);
      }
      m.indices.push_back(to_local[u]);
    }
  }
  for (const int e : level.GetVertexEdges(c)) {
    const float s = level.GetEdgeSharpness(e);
    if (!(s > 0.0f)) continue;
    const auto ev = level.GetEdgeVertices(e);
    m.crease_pairs.push_back(0);
    m.crease_pairs.push_back(to_local[ev[0] == c ? ev[1] : ev[0]]);
    m.crease_sharpness.push_back(s);
  }
  set_centre_sharpness(m, level.GetVertexSharpness(c));
  m.n_vertices = static_cast<int>(taken.size());
  for (const int u : taken) to_local[u] = -1;
  return m;
}

// One uniform level of `m` (one local refiner): `next` gets the weights of
// the refined level's vertices over the original local mesh (`rows`: those
// of m's vertices, n0 columns); returns the refiner, refined once.
std::unique_ptr<Far::TopologyRefiner> refine_once(const LocalMesh& m, Scheme scheme, Boundary boundary,
                                                  std::vector<double>& rows, int n0, std::vector<double>& next) {
  auto refiner = create_refiner(m, scheme, boundary);
  Far::TopologyRefiner::UniformOptions options(1);
  options.fullTopologyInLastLevel = true;
  refiner->RefineUniform(options);
  next.assign(static_cast<std::size_t>(refiner->GetLevel(1).GetNumVertices()) * n0, 0.0);
  Rows src{rows.data(), n0}, dst{next.data(), n0};
  Far::PrimvarRefinerReal<double>(*refiner).Interpolate(1, src, dst);
  return refiner;
}

// The limit row of the centre of `m` over m's vertices: `levels` uniform
// levels (one local refiner each), then Limit().
std::vector<double> local_limit_row(LocalMesh m, Scheme scheme, Boundary boundary, int levels) {
  const int n0 = m.n_vertices;
  std::vector<double> rows(static_cast<std::size_t>(n0) * n0, 0.0);  // level 0: the identity
  for (int i = 0; i < n0; ++i) rows[static_cast<std::size_t>(i) * n0 + i] = 1.0;
  std::vector<double> next, limit;
  std::vector<int> to_local, taken;
  for (;;) {
    std::unique_ptr<Far::TopologyRefiner> refiner;
    int centre = 0;
    Rows src{rows.data(), n0};
    if (levels > 0) {
      refiner = refine_once(m, scheme, boundary, rows, n0, next);
      const Far::TopologyLevel& child = refiner->GetLevel(1);
      centre = refiner->GetLevel(0).GetVertexChildVertex(0);
      if (--levels > 0) {  // the faces around the centre's child are all the next level needs
        to_local.assign(child.GetNumVertices(), -1);
        m = child_mesh(child, centre, to_local, taken);
        rows.resize(taken.size() * static_cast<std::size_t>(n0));
        for (std::size_t i = 0; i < taken.size(); ++i)
          std::copy_n(next.data() + static_cast<std::size_t>(taken[i]) * n0, n0, rows.data() + i * n0);
        continue;
      }
      src = Rows{next.data(), n0};
    } else {
      refiner = create_refiner(m, scheme, boundary);
    }
    const int n_last = refiner->GetLevel(refiner->GetMaxLevel()).GetNumVertices();
    limit.assign(static_cast<std::size_t>(n_last) * n0, 0.0);
    Rows lim{limit.data(), n0};
    Far::PrimvarRefinerReal<double>(*refiner).Limit(src, lim);
    return std::vector<double>(limit.begin() + static_cast<std::size_t>(centre) * n0,
                               limit.begin() + static_cast<std::size_t>(centre + 1) * n0);
  }
}

// The u with u^T S = u^T and sum(u) = 1, for an m x m row-major S whose rows
// sum to 1 and whose eigenvalue 1 is simple: M^T u = 1/m with
// M = I - S + 1 1^T / m (M shares S's right eigenvector 1, with eigenvalue 1
// instead of 0, and I - S's other eigenvalues, so it is invertible), by
// Gaussian elimination with partial pivoting.
std::vector<double> stationary_weights(const std::vector<double>& s, int m) {
  const auto at = [m](int i, int j) { return static_cast<std::size_t>(i) * m + j; };
  std::vector<double> a(static_cast<std::size_t>(m) * m), u(m, 1.0 / m);
  for (int i = 0; i < m; ++i)  // a = M^T
    for (int j = 0; j < m; ++j) a[at(i, j)] = (i == j ? 1.0 : 0.0) - s[at(j, i)] + 1.0 / m;
  for (int c = 0; c < m; ++c) {
    int p = c;
    for (int i = c + 1; i < m; ++i)
      if (std::abs(a[at(i, c)]) > std::abs(a[at(p, c)])) p = i;
    if (!(std::abs(a[at(p, c)]) > 0.0))
      throw std::logic_error("sorpia: the subdivision matrix around a dart has eigenvalue 1 more than once");
    if (p != c) {
      for (int j = 0; j < m; ++j) std::swap(a[at(p, j)], a[at(c, j)]);
      std::swap(u[p], u[c]);
    }
    for (int i = c + 1; i < m; ++i) {
      const double f = a[at(i, c)] / a[at(c, c)];
      if (f == 0.0) continue;
      for (int j = c; j < m; ++j) a[at(i, j)] -= f * a[at(c, j)];
      u[i] -= f * u[c];
    }
  }
  for (int i = m - 1; i >= 0; --i) {
    double x = u[i];
    for (int j = i + 1; j < m; ++j) x -= a[at(i, j)] * u[j];
    u[i] = x / a[at(i, i)];
  }
  return u;
}

// The limit row of a dart, the centre of `m` (an interior vertex whose only
// infinitely sharp edge is its one tag left after `levels` >= 1 levels), over
// m's vertices: the limit as the level L grows of Far's Limit() after L
// levels, which Sdc's (smooth) limit mask does not give at any finite L.
//
// After `levels` levels the faces around the centre's child are quads
// (Catmull-Clark) or triangles (Loop) and the rules of every vertex they hold
// no longer change (semi-sharp tags have decayed, infinitely sharp edges stay
// sharp), so one level maps the local mesh's vertices to the same
// configuration one level down: the centre to its child, the other end of
// each of its edges to that edge's child, the corner opposite the centre in
// each quad to that face's child. That map is the local subdivision matrix S
// (the same at every later level), and the limit row is S^L's rows' common
// limit, u^T with u S's dominant left eigenvector (eigenvalue 1, weights
// summing to 1: stationary_weights), composed back through the levels.
std::vector<double> local_dart_row(LocalMesh m, Scheme scheme, Boundary boundary, int levels) {
  const int n0 = m.n_vertices;
  std::vector<double> rows(static_cast<std::size_t>(n0) * n0, 0.0);  // level 0: the identity
  for (int i = 0; i < n0; ++i) rows[static_cast<std::size_t>(i) * n0 + i] = 1.0;
  std::vector<double> next;
  std::vector<int> to_local, taken;
  for (int l = 0; l < levels; ++l) {
    const auto refiner = refine_once(m, scheme, boundary, rows, n0, next);
    const Far::TopologyLevel& child = refiner->GetLevel(1);
    to_local.assign(child.GetNumVertices(), -1);
    m = child_mesh(child, refiner->GetLevel(0).GetVertexChildVertex(0), to_local, taken);
    rows.resize(taken.size() * static_cast<std::size_t>(n0));
    for (std::size_t i = 0; i < taken.size(); ++i)
      std::copy_n(next.data() + static_cast<std::size_t>(taken[i]) * n0, n0, rows.data() + i * n0);
  }
  // S: one more level of m, each vertex of m followed to its counterpart.
  const int k = m.n_vertices;
  std::vector<double> identity(static_cast<std::size_t>(k) * k, 0.0), s(identity.size());
  for (int i = 0; i < k; ++i) identity[static_cast<std::size_t>(i) * k + i] = 1.0;
  const auto refiner = refine_once(m, scheme, boundary, identity, k, next);
  const Far::TopologyLevel& top = refiner->GetLevel(0);
  for (int i = 0; i < k; ++i) {
    int c = -1;
    if (i == 0) {
      c = top.GetVertexChildVertex(0);
    } else if (const int e = top.FindEdge(0, i); e >= 0) {
      c = top.GetEdgeChildVertex(e);
    } else {
      for (const int f : top.GetVertexFaces(0))
        if (top.GetFaceVertices(f).size() == 4 && top.GetFaceVertices(f)[(top.GetFaceVertices(f).FindIndex(0) + 2) % 4] == i)
          c = top.GetFaceChildVertex(f);
    }
    if (c < 0) throw std::logic_error("sorpia: a vertex around a dart is neither on an edge nor opposite in a quad");
    std::copy_n(next.data() + static_cast<std::size_t>(c) * k, k, s.data() + static_cast<std::size_t>(i) * k);
  }
  const std::vector<double> u = stationary_weights(s, k);
  std::vector<double> row(n0, 0.0);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < n0; ++j) row[j] += u[i] * rows[static_cast<std::size_t>(i) * n0 + j];
  return row;
}

// Appends the entries of a row (columns `cols`, weights `w`) to `b`, sorted,
// exact zeros dropped (OpenSubdiv's masks list interior neighbours of crease
// vertices with weight 0).
void append_row(CsrMatrix& b, const std::vector<std::int32_t>& cols, const std::vector<double>& w) {
  std::vector<std::pair<std::int32_t, double>> e;
  for (std::size_t k = 0; k < cols.size(); ++k)
    if (w[k] != 0.0) e.emplace_back(cols[k], w[k]);
  std::sort(e.begin(), e.end());
  for (const auto& [j, x] : e) {
    b.indices.push_back(j);
    b.data.push_back(x);
  }
  b.indptr.push_back(static_cast<std::int32_t>(b.indices.size()));
}

}  // namespace

int VertexTags::levels(std::int32_t v) const {
  int l = decay_levels(corner[v]);
  for (std::int32_t p = crease_offsets[v]; p < crease_offsets[v + 1]; ++p)
    l = std::max(l, decay_levels(crease_sharpness[p]));
  return l;
}

int VertexTags::infinite_creases(std::int32_t v) const {
  int count = 0;
  for (std::int32_t p = crease_offsets[v]; p < crease_offsets[v + 1]; ++p) count += infinite(crease_sharpness[p]);
  return count;
}

std::vector<int> row_levels(const Topology& topology, Scheme scheme, const VertexTags& tags) {
  const std::size_t n = topology.n_vertices();
  std::vector<int> level(n, 0);
  int deepest = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (topology.is_unreferenced(v)) continue;
    level[v] = tags.levels(static_cast<std::int32_t>(v));
    if (scheme == Scheme::CatmullClark && !topology.quad_ring(v)) level[v] = std::max(level[v], 1);
    deepest = std::max(deepest, level[v]);
  }
  if (deepest > 0)
    for (std::size_t v = 0; v < n; ++v) {
      if (topology.is_unreferenced(v)) continue;
      // Catmull-Clark only: Loop's valence-2 mask (a pillow) is the limit of refinement
      const bool valence_two = scheme == Scheme::CatmullClark && !topology.is_boundary(v) && topology.valence(v) == 2;
      if (valence_two) level[v] = deepest;
    }
  return level;
}

VertexTags vertex_tags(const Topology& topology, const Tags& tags) {
  check_surface_left(tags, topology.n_faces());
  const std::size_t n = topology.n_vertices();
  VertexTags out;
  // Last sharpness per edge: sort the creases by edge, keep the last of each run.
  std::vector<std::int32_t> order(tags.n_creases());
  std::iota(order.begin(), order.end(), 0);
  const auto edge = [&](std::int32_t i) {
    const std::int32_t a = tags.crease_vertices[2 * i], b = tags.crease_vertices[2 * i + 1];
    return std::make_pair(std::min(a, b), std::max(a, b));
  };
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t i, std::int32_t j) { return edge(i) < edge(j); });
  std::vector<std::int32_t> kept;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::int32_t i = order[k];
    const auto [a, b] = edge(i);
    if (!is_edge(topology, a, b))
      throw MeshError("creases[" + std::to_string(i) + "] = [" + std::to_string(tags.crease_vertices[2 * i]) + ", " +
                      std::to_string(tags.crease_vertices[2 * i + 1]) + "] is not an edge of the mesh");
    if (k + 1 < order.size() && edge(order[k + 1]) == edge(i)) continue;  // a later entry for the same edge
    if (tags.crease_sharpness[i] > 0.0) kept.push_back(i);
  }
  out.crease_offsets.assign(n + 1, 0);
  for (const std::int32_t i : kept) {
    ++out.crease_offsets[tags.crease_vertices[2 * i] + 1];
    ++out.crease_offsets[tags.crease_vertices[2 * i + 1] + 1];
  }
  std::partial_sum(out.crease_offsets.begin(), out.crease_offsets.end(), out.crease_offsets.begin());
  out.crease_other.resize(2 * kept.size());
  out.crease_sharpness.resize(2 * kept.size());
  std::vector<std::int32_t> fill(out.crease_offsets.begin(), out.crease_offsets.end() - 1);
  for (const std::int32_t i : kept)
    for (int end = 0; end < 2; ++end) {
      const std::int32_t v = tags.crease_vertices[2 * i + end];
      const std::int32_t p = fill[v]++;
      out.crease_other[p] = tags.crease_vertices[2 * i + 1 - end];
      out.crease_sharpness[p] = osd_sharpness(tags.crease_sharpness[i]);
    }
  out.corner.assign(n, 0.0f);
  for (std::size_t i = 0; i < tags.n_corners(); ++i)
    out.corner[tags.corner_vertices[i]] = osd_sharpness(tags.corner_sharpness[i]);
  out.hole.assign(topology.n_faces(), 0);
  for (const std::int32_t f : tags.holes) out.hole[f] = 1;
  return out;
}

CsrMatrix refined_limit_rows(const Topology& topology, Scheme scheme, Boundary boundary, const VertexTags& tags,
                             const std::vector<std::int32_t>& vertices, const std::vector<int>& levels) {
  const std::size_t n = topology.n_vertices();
  // The faces incident to each requested vertex, in one scan of the faces.
  std::vector<std::int32_t> slot(n, -1);
  for (std::size_t k = 0; k < vertices.size(); ++k) slot[vertices[k]] = static_cast<std::int32_t>(k);
  std::vector<std::int32_t> face_offsets(vertices.size() + 1, 0), incident;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      std::partial_sum(face_offsets.begin(), face_offsets.end(), face_offsets.begin());
      incident.resize(face_offsets.back());
    }
    std::vector<std::int32_t> fill(face_offsets.begin(), face_offsets.end() - 1);
    for (std::size_t f = 0; f < topology.n_faces(); ++f) {
      const FaceVertices fv = face_vertices(topology, f);
      for (int j = 0; j < fv.size; ++j) {
        const std::int32_t k = slot[fv.begin[j]];
        if (k < 0) continue;
        if (pass == 0)
          ++face_offsets[k + 1];
        else
          incident[fill[k]++] = static_cast<std::int32_t>(f);
      }
    }
  }

  CsrMatrix b;
  b.n_rows = vertices.size();
  b.n_cols = n;
  b.indptr.assign(1, 0);
  std::vector<std::int32_t> base;  // local vertex -> vertex of the mesh
  std::vector<int> to_local(n, -1);
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    const std::int32_t v = vertices[k];
    if (face_offsets[k] == face_offsets[k + 1]) {  // unreferenced: its own limit
      append_row(b, {v}, {1.0});
      continue;
    }
    LocalMesh m;
    base.assign(1, v);
    to_local[v] = 0;
    for (std::int32_t p = face_offsets[k]; p < face_offsets[k + 1]; ++p) {
      const std::int32_t f = incident[p];
      if (tags.hole[f]) m.holes.push_back(static_cast<int>(m.counts.size()));
      const FaceVertices fv = face_vertices(topology, f);
      m.counts.push_back(fv.size);
      for (int j = 0; j < fv.size; ++j) {
        const std::int32_t u = fv.begin[j];
        if (to_local[u] < 0) {
          to_local[u] = static_cast<int>(base.size());
          base.push_back(u);
        }
        m.indices.push_back(to_local[u]);
      }
    }
    for (std::int32_t p = tags.crease_offsets[v]; p < tags.crease_offsets[v + 1]; ++p) {
      m.crease_pairs.push_back(0);
      m.crease_pairs.push_back(to_local[tags.crease_other[p]]);
      m.crease_sharpness.push_back(tags.crease_sharpness[p]);
    }
    set_centre_sharpness(m, tags.corner[v]);
    m.n_vertices = static_cast<int>(base.size());
    for (const std::int32_t u : base) to_local[u] = -1;
    if (tags.dart(topology, v))
      append_row(b, base, local_dart_row(std::move(m), scheme, boundary, std::max(levels[k], 1)));
    else
      append_row(b, base, local_limit_row(std::move(m), scheme, boundary, levels[k]));
  }
  return b;
}

DartRows dart_rows(const Topology& topology, Scheme scheme, Boundary boundary, const Tags& tags) {
  DartRows out;
  if (tags.n_creases() == 0) return out;
  const VertexTags vt = vertex_tags(topology, tags);
  const std::vector<int> level = row_levels(topology, scheme, vt);
  std::vector<int> levels;
  for (std::size_t v = 0; v < topology.n_vertices(); ++v)
    if (!topology.is_unreferenced(v) && vt.dart(topology, static_cast<std::int32_t>(v))) {
      out.vertices.push_back(static_cast<std::int32_t>(v));
      levels.push_back(level[v]);
    }
  out.rows = refined_limit_rows(topology, scheme, boundary, vt, out.vertices, levels);
  return out;
}

}  // namespace sorpia::detail

namespace sorpia {

namespace {

// A primvar that is a sparse row of weights over the control vertices.
struct SparseRow {
  std::vector<std::pair<std::int32_t, double>> e;
  void Clear() { e.clear(); }
  void AddWithWeight(const SparseRow& src, double w) {
    for (const auto& [j, x] : src.e) {
      auto it = std::find_if(e.begin(), e.end(), [j = j](const auto& q) { return q.first == j; });
      if (it == e.end())
        e.emplace_back(j, w * x);
      else
        it->second += w * x;
    }
  }
};

}  // namespace

CsrMatrix reference_limit_matrix(const Topology& topology, const Rules& rules) {
  using namespace detail;
  const Scheme scheme = rules.scheme;
  const Boundary boundary = rules.boundary;
  const Tags& tags = rules.tags;
  const std::size_t n = topology.n_vertices();
  const VertexTags vt = vertex_tags(topology, tags);  // checks the creases against the topology
  const Refiner osd = make_refiner(topology, scheme, boundary, tags);
  const auto& refiner = osd.refiner;
  const std::vector<std::int32_t>& to_osd = osd.to_osd;
  const std::vector<std::int32_t>& from_osd = osd.from_osd;

  const std::vector<int> row_level = row_levels(topology, scheme, vt);
  const int levels = row_level.empty() ? 0 : *std::max_element(row_level.begin(), row_level.end());
  std::vector<SparseRow> rows(from_osd.size()), next;
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i].e.emplace_back(from_osd[i], 1.0);
  if (levels > 0) {
    Far::TopologyRefiner::UniformOptions options(levels);
    options.fullTopologyInLastLevel = true;
    refiner->RefineUniform(options);
  }
  const Far::PrimvarRefinerReal<double> primvar(*refiner);
  std::vector<int> descendant(from_osd.size());
  std::iota(descendant.begin(), descendant.end(), 0);
  for (int l = 1; l <= levels; ++l) {
    next.assign(refiner->GetLevel(l).GetNumVertices(), SparseRow{});
    primvar.Interpolate(l, rows, next);
    rows.swap(next);
    for (int& c : descendant) c = refiner->GetLevel(l - 1).GetVertexChildVertex(c);
  }
  std::vector<SparseRow> limit(rows.size());
  primvar.Limit(rows, limit);

  CsrMatrix b;
  b.n_rows = b.n_cols = n;
  b.indptr.assign(1, 0);
  std::vector<std::int32_t> cols;
  std::vector<double> w;
  for (std::size_t v = 0; v < n; ++v) {
    cols.clear();
    w.clear();
    if (to_osd[v] < 0) {
      cols.push_back(static_cast<std::int32_t>(v));
      w.push_back(1.0);
    } else {
      for (const auto& [j, x] : limit[descendant[to_osd[v]]].e) {
        cols.push_back(j);
        w.push_back(x);
      }
    }
    append_row(b, cols, w);
  }
  return b;
}

}  // namespace sorpia
