#include "sorpia/fairness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// Quadrature points asked of LimitSurface::rows at a time: bounds the memory
// of the rows (six CSR matrices of this many rows) whatever the mesh size.
constexpr std::size_t kChunkPoints = 32768;
// Faces a thread takes at least, so that small meshes run on one thread.
constexpr std::size_t kFacesPerTask = 256;
// Two parameters closer than this are the same point of a face's domain
// (domains have side 1; pieces are at least 2^-12 apart).
constexpr double kSame = 1e-12;

void check_options(double thin_plate, double membrane, const FairnessQuadrature& q) {
  auto weight = [](double w, const char* name) {
    if (!(std::isfinite(w) && w >= 0.0))
      throw ParameterError(std::string(name) + " must be a finite number >= 0, got " + std::to_string(w));
  };
  weight(thin_plate, "thin_plate");
  weight(membrane, "membrane");
  if (thin_plate == 0.0 && membrane == 0.0)
    throw ParameterError("thin_plate and membrane are both 0: the energy would be zero; give one a positive weight");
  if (q.gauss_points < 1 || q.gauss_points > 16)
    throw ParameterError("gauss_points must be in 1..16, got " + std::to_string(q.gauss_points));
  if (q.depth < 0 || q.depth > 12)
    throw ParameterError("depth must be in 0..12, got " + std::to_string(q.depth));
}

// The n-point Gauss-Legendre rule on [0, 1] (nodes by Newton's method on the
// Legendre polynomial; weights 2 / ((1 - t^2) P_n'(t)^2) on [-1, 1], halved).
struct Rule {
  std::vector<double> x, w;
};

Rule gauss_legendre(int n) {
  Rule r;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < n; ++i) {
    double t = std::cos(pi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = t;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      const double pn = n == 1 ? t : p1, pm = n == 1 ? 1.0 : p0;
      dp = n * (t * pn - pm) / (t * t - 1.0);
      const double step = pn / dp;
      t -= step;
      if (std::abs(step) < 1e-16) break;
    }
    r.x.push_back(0.5 * (1.0 - t));
    r.w.push_back(1.0 / ((1.0 - t * t) * dp * dp));
  }
  return r;
}

struct UV {
  double u, v;
};

UV mid(UV a, UV b) { return {0.5 * (a.u + b.u), 0.5 * (a.v + b.v)}; }

// Where a face's domain is refined: its irregular corners (points) and its
// tagged edges (segments), in the face's (u, v).
struct Marks {
  std::vector<UV> points;
  std::vector<std::pair<UV, UV>> segments;

  void clear() {
    points.clear();
    segments.clear();
  }
  // A piece meets a mark iff one of its corners lies on it: the marks are
  // corners and edges of the domain, and a piece inside a convex domain meets
  // the domain's boundary in a corner or an edge of its own.
  bool touches(const UV* c, int n) const {
    for (int i = 0; i < n; ++i) {
      for (const UV& p : points)
        if (std::abs(p.u - c[i].u) < kSame && std::abs(p.v - c[i].v) < kSame) return true;
      for (const auto& s : segments) {
        const double eu = s.second.u - s.first.u, ev = s.second.v - s.first.v;
        const double pu = c[i].u - s.first.u, pv = c[i].v - s.first.v;
        const double len2 = eu * eu + ev * ev, dot = eu * pu + ev * pv;
        if (std::abs(eu * pv - ev * pu) < kSame && dot > -kSame && dot < len2 + kSame) return true;
      }
    }
    return false;
  }
};

// Quadrature points (u, v, weight) of one face, appended to `uvw`.
class Pieces {
 public:
  Pieces(const Rule& rule, int depth) : g_(rule), depth_(depth) {}

  void square(UV o, double h, int level, const Marks& m, std::vector<double>& uvw) const {
    const UV c[4] = {o, {o.u + h, o.v}, {o.u + h, o.v + h}, {o.u, o.v + h}};
    if (level < depth_ && m.touches(c, 4)) {
      const double k = 0.5 * h;
      for (const UV& d : {UV{0, 0}, UV{k, 0}, UV{k, k}, UV{0, k}}) square({o.u + d.u, o.v + d.v}, k, level + 1, m, uvw);
      return;
    }
    const std::size_t n = g_.x.size();
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        uvw.push_back(o.u + h * g_.x[i]);
        uvw.push_back(o.v + h * g_.x[j]);
        uvw.push_back(h * h * g_.w[i] * g_.w[j]);
      }
  }

  void triangle(UV a, UV b, UV c, int level, const Marks& m, std::vector<double>& uvw) const {
    const UV t[3] = {a, b, c};
    if (level < depth_ && m.touches(t, 3)) {
      const UV ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      triangle(a, ab, ca, level + 1, m, uvw);
      triangle(ab, b, bc, level + 1, m, uvw);
      triangle(ca, bc, c, level + 1, m, uvw);
      triangle(bc, ca, ab, level + 1, m, uvw);
      return;
    }
    // The collapsed (Duffy) product rule: (s, t) = (x_i, x_j (1 - x_i)) with
    // weight w_i w_j (1 - x_i) on the unit right triangle, scaled by twice the
    // piece's area.
    const double area2 = std::abs((b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u));
    const std::size_t n = g_.x.size();
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        const double s = g_.x[i], r = g_.x[j] * (1.0 - g_.x[i]);
        uvw.push_back(a.u + s * (b.u - a.u) + r * (c.u - a.u));
        uvw.push_back(a.v + s * (b.v - a.v) + r * (c.v - a.v));
        uvw.push_back(area2 * g_.w[i] * g_.w[j] * (1.0 - g_.x[i]));
      }
  }

 private:
  const Rule& g_;
  int depth_;
};

// Columns of the grid of sub-faces of a k-gon under Catmull-Clark (surface.hpp).
int subface_columns(int k) {
  if (k < 5) return 2;
  if (k < 10) return 3;
  return 1 + static_cast<int>(std::floor(std::sqrt(static_cast<double>(k - 1)) + 1e-9));
}

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

// Which vertices and edges make a face's patch other than a regular box
// spline, so that its domain is refined towards them.
struct Irregular {
  std::vector<std::uint8_t> vertex;
  std::unordered_set<std::uint64_t> edges;  // tagged (edge_key)

  Irregular(const Topology& t, Scheme scheme, const Tags& tags) : vertex(t.n_vertices(), 0) {
    const int regular_valence = scheme == Scheme::Loop ? 6 : 4;
    const int regular_size = scheme == Scheme::Loop ? 3 : 4;
    for (std::size_t v = 0; v < t.n_vertices(); ++v)
      vertex[v] = static_cast<std::uint8_t>(t.is_boundary(v) || t.valence(v) != regular_valence);
    const auto& fi = t.face_indices();
    auto mark_face = [&](std::size_t f) {
      const std::int32_t o = t.face_offset(f);
      for (std::int32_t i = 0; i < t.face_size(f); ++i) vertex[static_cast<std::size_t>(fi[o + i])] = 1;
    };
    for (std::size_t f = 0; f < t.n_faces(); ++f)
      if (t.face_size(f) != regular_size) mark_face(f);
    for (const std::int32_t f : tags.holes) mark_face(static_cast<std::size_t>(f));
    for (std::size_t c = 0; c < tags.n_corners(); ++c)
      if (tags.corner_sharpness[c] > 0.0) vertex[static_cast<std::size_t>(tags.corner_vertices[c])] = 1;
    for (std::size_t e = 0; e < tags.n_creases(); ++e) {
      if (!(tags.crease_sharpness[e] > 0.0)) continue;
      const std::int32_t a = tags.crease_vertices[2 * e], b = tags.crease_vertices[2 * e + 1];
      vertex[static_cast<std::size_t>(a)] = vertex[static_cast<std::size_t>(b)] = 1;
      edges.insert(edge_key(a, b));
    }
  }
  bool tagged(std::int32_t a, std::int32_t b) const { return !edges.empty() && edges.count(edge_key(a, b)) != 0; }
};

// The quadrature points of face f (u, v, weight with the face's measure).
void face_points(const Topology& t, Scheme scheme, const Irregular& irr, const Pieces& pieces, std::size_t f,
                 Marks& m, std::vector<double>& uvw) {
  const std::int32_t k = t.face_size(f);
  const std::int32_t* vs = t.face_indices().data() + t.face_offset(f);
  auto corner_marks = [&](const UV* c) {
    m.clear();
    for (std::int32_t i = 0; i < k; ++i) {
      if (irr.vertex[static_cast<std::size_t>(vs[i])]) m.points.push_back(c[i]);
      if (irr.tagged(vs[i], vs[(i + 1) % k])) m.segments.push_back({c[i], c[(i + 1) % k]});
    }
  };
  if (scheme == Scheme::Loop) {
    const UV c[3] = {{0, 0}, {1, 0}, {0, 1}};
    corner_marks(c);
    const std::size_t first = uvw.size();
    pieces.triangle(c[0], c[1], c[2], 0, m, uvw);
    // The equilateral measure: dx dy = (sqrt(3) / 2) du dv.
    for (std::size_t i = first + 2; i < uvw.size(); i += 3) uvw[i] *= 0.5 * std::sqrt(3.0);
    return;
  }
  if (k == 4) {
    const UV c[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    corner_marks(c);
    pieces.square(c[0], 1.0, 0, m, uvw);
    return;
  }
  // A k-gon's sub-face j: the square of side 1/2 at corner j, its far corner the
  // face's centre (extraordinary of valence k), its sides along edges j and j - 1.
  const int w = subface_columns(k);
  for (std::int32_t j = 0; j < k; ++j) {
    const UV o{static_cast<double>(j % w), static_cast<double>(j / w)};
    const UV along{o.u + 0.5, o.v}, back{o.u, o.v + 0.5};
    m.clear();
    m.points.push_back({o.u + 0.5, o.v + 0.5});
    if (irr.vertex[static_cast<std::size_t>(vs[j])]) m.points.push_back(o);
    if (irr.tagged(vs[j], vs[(j + 1) % k])) {
      m.points.push_back(along);
      m.segments.push_back({o, along});
    }
    if (irr.tagged(vs[(j + k - 1) % k], vs[j])) {
      m.points.push_back(back);
      m.segments.push_back({o, back});
    }
    pieces.square(o, 0.5, 1, m, uvw);
  }
}

// The terms of the energy at a point, each a combination of the derivative
// rows (du, dv, duu, duv, dvv) with the weight it carries in the energy.
struct Term {
  double coef[5];
  double weight;
};

std::vector<Term> energy_terms(Scheme scheme, double thin_plate, double membrane) {
  std::vector<Term> terms;
  if (scheme == Scheme::Loop) {
    // (x, y) = (u + v/2, v sqrt(3)/2): d/dx = d/du, d/dy = (2 d/dv - d/du) / sqrt(3).
    const double r3 = 1.0 / std::sqrt(3.0);
    if (thin_plate > 0.0) {
      terms.push_back({{0, 0, 1, 0, 0}, thin_plate});                              // xx
      terms.push_back({{0, 0, -r3, 2 * r3, 0}, 2.0 * thin_plate});                 // xy
      terms.push_back({{0, 0, 1.0 / 3.0, -4.0 / 3.0, 4.0 / 3.0}, thin_plate});     // yy
    }
    if (membrane > 0.0) {
      terms.push_back({{1, 0, 0, 0, 0}, membrane});        // x
      terms.push_back({{-r3, 2 * r3, 0, 0, 0}, membrane});  // y
    }
    return terms;
  }
  if (thin_plate > 0.0) {
    terms.push_back({{0, 0, 1, 0, 0}, thin_plate});
    terms.push_back({{0, 0, 0, 1, 0}, 2.0 * thin_plate});
    terms.push_back({{0, 0, 0, 0, 1}, thin_plate});
  }
  if (membrane > 0.0) {
    terms.push_back({{1, 0, 0, 0, 0}, membrane});
    terms.push_back({{0, 1, 0, 0, 0}, membrane});
  }
  return terms;
}

using Entry = std::pair<std::uint64_t, double>;  // (row << 32 | column, value), row <= column

// Sorts entries by (row, column) and adds up repeated ones, in place.
void merge_entries(std::vector<Entry>& e) {
  std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) { return a.first < b.first; });
  std::size_t out = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (out > 0 && e[out - 1].first == e[i].first)
      e[out - 1].second += e[i].second;
    else
      e[out++] = e[i];
  }
  e.resize(out);
}

// One thread's work space and its merged share of K's upper triangle.
struct Worker {
  std::vector<Entry> merged;
  std::vector<Entry> chunk;
  std::vector<std::int32_t> local;  // column -> its place in `cols`, -1 elsewhere
  std::vector<std::int32_t> cols;
  std::vector<double> a, e;
};

// Face f's element matrix, from its points' rows [r0, r1), added to w.chunk
// (upper triangle, global indices).
void add_element(const SurfaceRows& rows, const double* weights, std::size_t r0, std::size_t r1,
                 const std::vector<Term>& terms, Worker& w) {
  const CsrMatrix* d[5] = {&rows.du, &rows.dv, &rows.duu, &rows.duv, &rows.dvv};
  bool used[5] = {false, false, false, false, false};
  for (const Term& t : terms)
    for (int i = 0; i < 5; ++i) used[i] = used[i] || t.coef[i] != 0.0;
  w.cols.clear();
  for (int i = 0; i < 5; ++i) {
    if (!used[i]) continue;
    const CsrMatrix& m = *d[i];
    for (auto p = static_cast<std::size_t>(m.indptr[r0]); p < static_cast<std::size_t>(m.indptr[r1]); ++p) {
      const std::int32_t c = m.indices[p];
      if (w.local[static_cast<std::size_t>(c)] < 0) {
        w.local[static_cast<std::size_t>(c)] = 0;
        w.cols.push_back(c);
      }
    }
  }
  std::sort(w.cols.begin(), w.cols.end());
  const std::size_t n = w.cols.size();
  for (std::size_t i = 0; i < n; ++i) w.local[static_cast<std::size_t>(w.cols[i])] = static_cast<std::int32_t>(i);
  w.e.assign(n * n, 0.0);
  w.a.resize(n);
  for (std::size_t r = r0; r < r1; ++r) {
    for (const Term& t : terms) {
      std::fill(w.a.begin(), w.a.end(), 0.0);
      for (int i = 0; i < 5; ++i) {
        if (t.coef[i] == 0.0) continue;
        const CsrMatrix& m = *d[i];
        for (auto p = static_cast<std::size_t>(m.indptr[r]); p < static_cast<std::size_t>(m.indptr[r + 1]); ++p)
          w.a[static_cast<std::size_t>(w.local[static_cast<std::size_t>(m.indices[p])])] += t.coef[i] * m.data[p];
      }
      const double s = weights[r] * t.weight;
      for (std::size_t i = 0; i < n; ++i) {
        const double ai = s * w.a[i];
        if (ai == 0.0) continue;
        double* row = w.e.data() + i * n;
        for (std::size_t j = i; j < n; ++j) row[j] += ai * w.a[j];
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto ri = static_cast<std::uint64_t>(static_cast<std::uint32_t>(w.cols[i])) << 32;
    for (std::size_t j = i; j < n; ++j)
      w.chunk.emplace_back(ri | static_cast<std::uint32_t>(w.cols[j]), w.e[i * n + j]);
    w.local[static_cast<std::size_t>(w.cols[i])] = -1;
  }
}

// The symmetric CSR matrix of the merged upper triangles.
CsrMatrix symmetric_csr(std::vector<Worker>& workers, std::size_t n_rows, bool parallel, int n_tasks) {
  // Upper triangle by rows: counts, then entries bucketed by row.
  std::vector<std::int64_t> start(n_rows + 1, 0);
  for (const Worker& w : workers)
    for (const Entry& e : w.merged) ++start[(e.first >> 32) + 1];
  for (std::size_t i = 0; i < n_rows; ++i) start[i + 1] += start[i];
  std::vector<std::int32_t> ucol(static_cast<std::size_t>(start[n_rows]));
  std::vector<double> uval(ucol.size());
  {
    std::vector<std::int64_t> cursor(start.begin(), start.end() - 1);
    for (Worker& w : workers) {
      for (const Entry& e : w.merged) {
        const auto p = static_cast<std::size_t>(cursor[e.first >> 32]++);
        ucol[p] = static_cast<std::int32_t>(e.first & 0xffffffffu);
        uval[p] = e.second;
      }
      std::vector<Entry>().swap(w.merged);
    }
  }
  // Each row's columns sorted, repeated ones (from different threads) added.
  std::vector<std::int64_t> ucount(n_rows, 0);
  detail::for_each_index(parallel, n_tasks, n_rows, [&](std::size_t i) {
    const auto b = static_cast<std::size_t>(start[i]), e = static_cast<std::size_t>(start[i + 1]);
    std::vector<std::pair<std::int32_t, double>> row;
    row.reserve(e - b);
    for (std::size_t p = b; p < e; ++p) row.emplace_back(ucol[p], uval[p]);
    std::sort(row.begin(), row.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    std::size_t out = b;
    for (std::size_t p = 0; p < row.size(); ++p) {
      if (out > b && ucol[out - 1] == row[p].first) {
        uval[out - 1] += row[p].second;
      } else {
        ucol[out] = row[p].first;
        uval[out++] = row[p].second;
      }
    }
    ucount[i] = static_cast<std::int64_t>(out - b);
  });
  // The full matrix: row i holds the mirrored entries (j, i), j < i, in
  // increasing j, then its own upper entries.
  std::vector<std::int64_t> full(n_rows + 1, 0);
  for (std::size_t i = 0; i < n_rows; ++i) {
    full[i + 1] += ucount[i];
    for (std::int64_t p = start[i]; p < start[i] + ucount[i]; ++p)
      if (static_cast<std::size_t>(ucol[static_cast<std::size_t>(p)]) != i)
        ++full[static_cast<std::size_t>(ucol[static_cast<std::size_t>(p)]) + 1];
  }
  for (std::size_t i = 0; i < n_rows; ++i) full[i + 1] += full[i];
  if (full[n_rows] > static_cast<std::int64_t>(INT32_MAX))
    throw ParameterError("the fairness matrix has " + std::to_string(full[n_rows]) +
                         " entries, more than 32-bit CSR indices address");
  CsrMatrix k;
  k.n_rows = k.n_cols = n_rows;
  k.indptr.resize(n_rows + 1);
  for (std::size_t i = 0; i <= n_rows; ++i) k.indptr[i] = static_cast<std::int32_t>(full[i]);
  k.indices.resize(static_cast<std::size_t>(full[n_rows]));
  k.data.resize(k.indices.size());
  std::vector<std::int64_t> cursor(full.begin(), full.end() - 1);
  for (std::size_t i = 0; i < n_rows; ++i) {
    for (std::int64_t p = start[i]; p < start[i] + ucount[i]; ++p) {
      const auto j = static_cast<std::size_t>(ucol[static_cast<std::size_t>(p)]);
      if (j == i) continue;
      const auto q = static_cast<std::size_t>(cursor[j]++);
      k.indices[q] = static_cast<std::int32_t>(i);
      k.data[q] = uval[static_cast<std::size_t>(p)];
    }
  }
  detail::for_each_index(parallel, n_tasks, n_rows, [&](std::size_t i) {
    auto q = static_cast<std::size_t>(cursor[i]);
    for (std::int64_t p = start[i]; p < start[i] + ucount[i]; ++p, ++q) {
      k.indices[q] = ucol[static_cast<std::size_t>(p)];
      k.data[q] = uval[static_cast<std::size_t>(p)];
    }
  });
  return k;
}

}  // namespace

CsrMatrix fairness_matrix(const LimitSurface& surface, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature) {
  check_options(thin_plate, membrane, quadrature);
  const Topology& topo = surface.topology();
  const Scheme scheme = surface.scheme();
  const std::size_t n_faces = topo.n_faces();
  const Irregular irr(topo, scheme, surface.tags());
  std::vector<std::uint8_t> hole(n_faces, 0);
  for (const std::int32_t f : surface.tags().holes) hole[static_cast<std::size_t>(f)] = 1;
  const Rule rule = gauss_legendre(quadrature.gauss_points);
  const Pieces pieces(rule, quadrature.depth);
  const std::vector<Term> terms = energy_terms(scheme, thin_plate, membrane);

  const int n_threads = std::max(1, std::min<int>(detail::available_processors(),
                                                  static_cast<int>(n_faces / kFacesPerTask)));
  std::vector<Worker> workers(static_cast<std::size_t>(n_threads));
  for (Worker& w : workers) w.local.assign(surface.n_vertices(), -1);

  std::vector<std::int32_t> chunk_faces, point_faces;
  std::vector<std::size_t> face_first;  // per chunk face, its first point; one past the end last
  std::vector<double> uvw, uv, weights;
  Marks marks;
  std::size_t f = 0;
  while (f < n_faces) {
    poll_interrupt();
    chunk_faces.clear();
    face_first.clear();
    uvw.clear();
    for (; f < n_faces && uvw.size() < 3 * kChunkPoints; ++f) {
      if (hole[f]) continue;
      chunk_faces.push_back(static_cast<std::int32_t>(f));
      face_first.push_back(uvw.size() / 3);
      face_points(topo, scheme, irr, pieces, f, marks, uvw);
    }
    const std::size_t k = uvw.size() / 3;
    face_first.push_back(k);
    if (chunk_faces.empty()) continue;
    point_faces.resize(k);
    uv.resize(2 * k);
    weights.resize(k);
    for (std::size_t c = 0; c < chunk_faces.size(); ++c)
      for (std::size_t p = face_first[c]; p < face_first[c + 1]; ++p) point_faces[p] = chunk_faces[c];
    for (std::size_t p = 0; p < k; ++p) {
      uv[2 * p] = uvw[3 * p];
      uv[2 * p + 1] = uvw[3 * p + 1];
      weights[p] = uvw[3 * p + 2];
    }
    const SurfaceRows rows = surface.rows(point_faces.data(), uv.data(), k, 2);
    const std::size_t n_chunk = chunk_faces.size();
    detail::for_each_task(n_threads > 1, n_threads, [&](int t) {
      Worker& w = workers[static_cast<std::size_t>(t)];
      const auto nt = static_cast<std::size_t>(n_threads), ut = static_cast<std::size_t>(t);
      w.chunk.clear();
      for (std::size_t c = n_chunk * ut / nt; c < n_chunk * (ut + 1) / nt; ++c)
        add_element(rows, weights.data(), face_first[c], face_first[c + 1], terms, w);
      merge_entries(w.chunk);
      w.merged.insert(w.merged.end(), w.chunk.begin(), w.chunk.end());
    });
  }
  for (Worker& w : workers) {
    std::vector<Entry>().swap(w.chunk);
    std::vector<std::int32_t>().swap(w.local);
  }
  return symmetric_csr(workers, surface.n_vertices(), n_threads > 1, n_threads);
}

}  // namespace sorpia
