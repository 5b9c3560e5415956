#include "sorpia/fairness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/subface_grid.hpp"

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

// A leaf of a face's domain split: under Catmull-Clark, a bicubic B-spline
// piece (it touches no mark and lies within Bfr's isolation level, outside its
// Gregory corner patch) is integrated in closed form from the derivatives at
// four points; every other piece, and every Loop piece, by the Gauss rule.
// (Loop's pieces are quartic, but Bfr's second derivatives change sign on the
// rotated middle sub-triangles of its irregular patches, which squares do not
// see and a fit to first and second derivatives would.)
struct Piece {
  bool exact;
  double scale;  // side (squares) or leg (triangles) of the piece: 2^-level
  double e[4];   // the piece's local axes in (u, v): s along (e[0], e[1]), t along (e[2], e[3])
  std::size_t first, count;  // its points
};

// Points of the closed-form pieces, in a piece's local (s, t) on the unit
// square (see ExactForms).
constexpr double kSquareData[2] = {0.5 - 0.5 / 1.7320508075688772, 0.5 + 0.5 / 1.7320508075688772};
// The deepest level at which a piece away from the marks is a polynomial
// piece of Bfr's surface: Bfr's own isolation level at extraordinary vertices
// (surface.cpp); below it lies its Gregory corner patch.
constexpr int kExactLevel = 4;
// Dunavant's 6-point rule on a triangle, exact to degree 4: barycentric
// (a, a, 1 - 2a) and its rotations, with weight w each (weights sum to 1).
constexpr double kDegree4[2][3] = {{0.445948490915965, 0.108103018168070, 0.223381589678011},
                                   {0.091576213509771, 0.816847572980459, 0.109951743655322}};

// The pieces of one face and their points (u, v, Gauss weight or 0).
class Pieces {
 public:
  // closed_forms: integrate Catmull-Clark's polynomial pieces by ExactForms
  // (the parametric energy); false: by the Gauss rule (a face metric).
  Pieces(const Rule& rule, int depth, bool thin_plate_only, bool closed_forms = true)
      : g_(rule), depth_(depth), thin_plate_only_(thin_plate_only), closed_forms_(closed_forms) {}

  void square(UV o, double h, int level, const Marks& m, std::vector<Piece>& out, std::vector<double>& uvw) const {
    const UV c[4] = {o, {o.u + h, o.v}, {o.u + h, o.v + h}, {o.u, o.v + h}};
    const bool touches = m.touches(c, 4);
    if (touches && level < depth_) {
      const double k = 0.5 * h;
      for (const UV& d : {UV{0, 0}, UV{k, 0}, UV{k, k}, UV{0, k}})
        square({o.u + d.u, o.v + d.v}, k, level + 1, m, out, uvw);
      return;
    }
    const bool exact = closed_forms_ && !touches && level <= kExactLevel;
    out.push_back({exact, h, {h, 0.0, 0.0, h}, uvw.size() / 3, 0});
    if (exact) {
      for (const double t : kSquareData)
        for (const double s : kSquareData) add(o.u + h * s, o.v + h * t, 0.0, uvw);
    } else {
      const std::size_t n = g_.x.size();
      for (std::size_t j = 0; j < n; ++j)
        for (std::size_t i = 0; i < n; ++i) add(o.u + h * g_.x[i], o.v + h * g_.x[j], h * h * g_.w[i] * g_.w[j], uvw);
    }
    out.back().count = uvw.size() / 3 - out.back().first;
  }

  void triangle(UV a, UV b, UV c, double h, int level, const Marks& m, std::vector<Piece>& out,
                std::vector<double>& uvw) const {
    const UV t[3] = {a, b, c};
    const bool touches = m.touches(t, 3);
    if (touches && level < depth_) {
      const UV ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      triangle(a, ab, ca, 0.5 * h, level + 1, m, out, uvw);
      triangle(ab, b, bc, 0.5 * h, level + 1, m, out, uvw);
      triangle(ca, bc, c, 0.5 * h, level + 1, m, out, uvw);
      triangle(bc, ca, ab, 0.5 * h, level + 1, m, out, uvw);
      return;
    }
    const double e[4] = {b.u - a.u, b.v - a.v, c.u - a.u, c.v - a.v};
    out.push_back({false, h, {e[0], e[1], e[2], e[3]}, uvw.size() / 3, 0});
    auto at = [&](double s, double r, double w) { add(a.u + s * e[0] + r * e[2], a.v + s * e[1] + r * e[3], w, uvw); };
    const double area2 = std::abs(e[0] * e[3] - e[1] * e[2]);
    if (!touches && level <= kExactLevel && thin_plate_only_) {
      // A quartic piece, the thin-plate integrand of degree 4 whatever the
      // sign of Bfr's second derivatives: the 6-point rule exact to degree 4
      // (Dunavant 1985), weights summing to 1 times the piece's area.
      for (const auto& q : kDegree4) {  // (s, t) the barycentrics of b and c
        at(q[0], q[1], 0.5 * area2 * q[2]);
        at(q[1], q[0], 0.5 * area2 * q[2]);
        at(q[0], q[0], 0.5 * area2 * q[2]);
      }
    } else {
      // The collapsed (Duffy) product rule: (s, t) = (x_i, x_j (1 - x_i))
      // with weight w_i w_j (1 - x_i) on the unit right triangle, times twice
      // the piece's area in (u, v).
      const std::size_t n = g_.x.size();
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j)
          at(g_.x[i], g_.x[j] * (1.0 - g_.x[i]), area2 * g_.w[i] * g_.w[j] * (1.0 - g_.x[i]));
    }
    out.back().count = uvw.size() / 3 - out.back().first;
  }

 private:
  static void add(double u, double v, double w, std::vector<double>& uvw) {
    uvw.push_back(u);
    uvw.push_back(v);
    uvw.push_back(w);
  }
  const Rule& g_;
  int depth_;
  bool thin_plate_only_;
  bool closed_forms_;
};

// Solves a x = b for the columns of b (n x m, row-major) in place, a (n x n)
// destroyed: Gauss-Jordan with partial pivoting, for the small fixed systems
// of ExactForms.
void solve_dense(std::vector<double> a, std::vector<double>& b, std::size_t n, std::size_t m) {
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t piv = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::abs(a[r * n + c]) > std::abs(a[piv * n + c])) piv = r;
    for (std::size_t k = 0; k < n; ++k) std::swap(a[c * n + k], a[piv * n + k]);
    for (std::size_t k = 0; k < m; ++k) std::swap(b[c * m + k], b[piv * m + k]);
    const double d = a[c * n + c];
    for (std::size_t r = 0; r < n; ++r) {
      if (r == c) continue;
      const double f = a[r * n + c] / d;
      if (f == 0.0) continue;
      for (std::size_t k = 0; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
      for (std::size_t k = 0; k < m; ++k) b[r * m + k] -= f * b[c * m + k];
    }
  }
  for (std::size_t c = 0; c < n; ++c)
    for (std::size_t k = 0; k < m; ++k) b[c * m + k] /= a[c * n + c];
}

// The energy of a bicubic piece as a quadratic form in its data: the
// derivatives (f_s, f_t, f_ss, f_st, f_tt) in the piece's local (s, t) on the
// unit square at the 2 x 2 points kSquareData. These 20 values determine a
// bicubic up to a constant (on each line t = t_j, f_s is the quadratic with
// those values and slopes, likewise f_t on s = s_i; a bicubic vanishing on
// the four lines is (s - s0)(s - s1)(t - t0)(t - t1) g with g bilinear, which
// f_st at the four points makes zero), and positions, whose weights are of
// order 1 where the energy's are of order h^2, are left out for accuracy.
// Q = C^T G C: C the least-squares data-to-coefficients map (exact on
// bicubics), G the energy's Gram matrix of the monomials (Gauss 4 x 4:
// exact). For a piece of side h the thin-plate form scales as h^-2, the
// membrane form stays.
struct ExactForms {
  static constexpr std::size_t kData = 20;
  std::vector<double> thin_plate, membrane;  // kData x kData

  ExactForms() {
    std::vector<std::pair<int, int>> mono;  // s^a t^b but the constant
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a + b > 0) mono.emplace_back(a, b);
    const std::size_t nm = mono.size();
    // d^(i, j) of monomial (a, b) at (s, t), centred on the piece (better conditioned)
    auto deriv = [](std::pair<int, int> m, int i, int j, double s, double t) {
      if (m.first < i || m.second < j) return 0.0;
      double c = 1.0;
      for (int k = 0; k < i; ++k) c *= m.first - k;
      for (int k = 0; k < j; ++k) c *= m.second - k;
      return c * std::pow(s - 0.5, m.first - i) * std::pow(t - 0.5, m.second - j);
    };
    const std::pair<int, int> orders[5] = {{1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
    std::vector<std::pair<UV, std::pair<int, int>>> data;
    for (const double t : kSquareData)
      for (const double s : kSquareData)
        for (const auto& o : orders) data.push_back({{s, t}, o});
    // C = (P^T P)^-1 P^T, P (kData x nm) the functionals on the monomials.
    std::vector<double> pm(kData * nm), ptp(nm * nm, 0.0), c(nm * kData);
    for (std::size_t d = 0; d < kData; ++d)
      for (std::size_t k = 0; k < nm; ++k)
        pm[d * nm + k] = deriv(mono[k], data[d].second.first, data[d].second.second, data[d].first.u, data[d].first.v);
    for (std::size_t i = 0; i < nm; ++i)
      for (std::size_t j = 0; j < nm; ++j)
        for (std::size_t d = 0; d < kData; ++d) ptp[i * nm + j] += pm[d * nm + i] * pm[d * nm + j];
    for (std::size_t k = 0; k < nm; ++k)
      for (std::size_t d = 0; d < kData; ++d) c[k * kData + d] = pm[d * nm + k];
    solve_dense(ptp, c, nm, kData);
    const Rule g = gauss_legendre(4);
    std::vector<double> gtp(nm * nm, 0.0), gmb(nm * nm, 0.0);
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = 0; j < 4; ++j) {
        const double s = g.x[i], t = g.x[j], w = g.w[i] * g.w[j];
        for (std::size_t a = 0; a < nm; ++a)
          for (std::size_t b = 0; b < nm; ++b) {
            auto dd = [&](int p, int q) { return deriv(mono[a], p, q, s, t) * deriv(mono[b], p, q, s, t); };
            gtp[a * nm + b] += w * (dd(2, 0) + 2.0 * dd(1, 1) + dd(0, 2));
            gmb[a * nm + b] += w * (dd(1, 0) + dd(0, 1));
          }
      }
    auto form = [&](const std::vector<double>& gm) {
      std::vector<double> q(kData * kData, 0.0);
      for (std::size_t a = 0; a < kData; ++a)
        for (std::size_t b = 0; b < kData; ++b) {
          double sum = 0.0;
          for (std::size_t i = 0; i < nm; ++i)
            for (std::size_t j = 0; j < nm; ++j) sum += c[i * kData + a] * gm[i * nm + j] * c[j * kData + b];
          q[a * kData + b] = sum;
        }
      return q;
    };
    thin_plate = form(gtp);
    membrane = form(gmb);
  }
};

// Which vertices and edges make a face's patch other than a regular box
// spline, so that its domain is refined towards them.
struct Irregular {
  std::vector<std::uint8_t> vertex;
  std::vector<std::uint8_t> half_edge;  // per half-edge (Topology::half_edge_twins): its edge is tagged; empty if none

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
    std::vector<std::int32_t> pairs;
    for (std::size_t e = 0; e < tags.n_creases(); ++e) {
      if (!(tags.crease_sharpness[e] > 0.0)) continue;
      const std::int32_t a = tags.crease_vertices[2 * e], b = tags.crease_vertices[2 * e + 1];
      vertex[static_cast<std::size_t>(a)] = vertex[static_cast<std::size_t>(b)] = 1;
      pairs.insert(pairs.end(), {a, b});
    }
    if (pairs.empty()) return;
    const std::vector<std::int32_t> twin = t.half_edge_twins();
    half_edge.assign(twin.size(), 0);
    for (const std::int32_t h : t.find_half_edges(pairs.data(), pairs.size() / 2)) {
      if (h < 0) continue;  // not an edge (check_tags refuses it): nothing to refine towards
      half_edge[static_cast<std::size_t>(h)] = 1;
      if (twin[static_cast<std::size_t>(h)] >= 0) half_edge[static_cast<std::size_t>(twin[static_cast<std::size_t>(h)])] = 1;
    }
  }
  // Whether the edge of half-edge h (corner i to i + 1 of a face: face_offset + i) is tagged.
  bool tagged(std::int32_t h) const { return !half_edge.empty() && half_edge[static_cast<std::size_t>(h)] != 0; }
};

// The pieces of face f and their points (u, v, Gauss weight with the face's measure).
void face_pieces(const Topology& t, Scheme scheme, const Irregular& irr, const Pieces& pieces, std::size_t f,
                 Marks& m, std::vector<Piece>& out, std::vector<double>& uvw) {
  const std::int32_t k = t.face_size(f), h0 = t.face_offset(f);  // h0 + i: the half-edge from corner i
  const std::int32_t* vs = t.face_indices().data() + h0;
  auto corner_marks = [&](const UV* c) {
    m.clear();
    for (std::int32_t i = 0; i < k; ++i) {
      if (irr.vertex[static_cast<std::size_t>(vs[i])]) m.points.push_back(c[i]);
      if (irr.tagged(h0 + i)) m.segments.push_back({c[i], c[(i + 1) % k]});
    }
  };
  if (scheme == Scheme::Loop) {
    const UV c[3] = {{0, 0}, {1, 0}, {0, 1}};
    corner_marks(c);
    const std::size_t first = uvw.size();
    pieces.triangle(c[0], c[1], c[2], 1.0, 0, m, out, uvw);
    // The equilateral measure: dx dy = (sqrt(3) / 2) du dv.
    for (std::size_t i = first + 2; i < uvw.size(); i += 3) uvw[i] *= 0.5 * std::sqrt(3.0);
    return;
  }
  if (k == 4) {
    const UV c[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    corner_marks(c);
    pieces.square(c[0], 1.0, 0, m, out, uvw);
    return;
  }
  // A k-gon's sub-face j: the square of side 1/2 at corner j, its far corner the
  // face's centre (extraordinary of valence k), its sides along edges j and j - 1.
  const int w = subface_columns(k);
  for (std::int32_t j = 0; j < k; ++j) {
    double origin[2];
    subface_origin(w, j, origin);
    const UV o{origin[0], origin[1]};
    const UV along{o.u + 0.5, o.v}, back{o.u, o.v + 0.5};
    m.clear();
    m.points.push_back({o.u + 0.5, o.v + 0.5});
    if (irr.vertex[static_cast<std::size_t>(vs[j])]) m.points.push_back(o);
    if (irr.tagged(h0 + j)) {
      m.points.push_back(along);
      m.segments.push_back({o, along});
    }
    if (irr.tagged(h0 + (j + k - 1) % k)) {
      m.points.push_back(back);
      m.segments.push_back({o, back});
    }
    pieces.square(o, 0.5, 1, m, out, uvw);
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

// K as a sum of element matrices, one per face that is not a hole: a dense
// symmetric matrix over the face's columns (the vertices its stencils
// reach). Faces grouped into one class (FairnessQuadrature::reuse) share one
// matrix over their own control points (topology_control_points' order or
// Bfr's); every other face is a class of its own, its matrix over its own
// sorted columns.
struct Elements {
  FaceControlPoints cps;                     // of the non-hole faces, in face order (with reuse)
  std::vector<std::int64_t> slot;            // per face, its place in cps; -1 for a hole
  std::vector<std::int32_t> face_class;      // per face, its class; -1 for a hole
  std::vector<std::int32_t> representative;  // per class, the face integrated for it
  std::vector<std::uint8_t> shared;          // per class: 1 when its faces use their control points as columns
  std::vector<std::vector<std::int32_t>> own_columns;  // per class of one face: its sorted columns
  std::vector<std::vector<double>> element;  // per class, n x n (n its faces' column count), row-major

  bool live(std::size_t f) const { return face_class[f] >= 0; }
  const std::int32_t* columns(std::size_t f) const {
    const auto c = static_cast<std::size_t>(face_class[f]);
    return shared[c] ? cps.indices.data() + cps.offsets[static_cast<std::size_t>(slot[f])] : own_columns[c].data();
  }
  std::size_t n_columns(std::size_t f) const {
    const auto c = static_cast<std::size_t>(face_class[f]);
    if (!shared[c]) return own_columns[c].size();
    const auto s = static_cast<std::size_t>(slot[f]);
    return static_cast<std::size_t>(cps.offsets[s + 1] - cps.offsets[s]);
  }
};

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

// The terms of the energy of face f measured in a fixed first fundamental
// form G of the reference surface (fairness_matrix's reference): with G^-1 =
// L L^T (L lower triangular), tr(G^-1 H G^-1 H) = |L^T H L|_F^2 and
// tr(G^-1 J^T J) = |J L|_F^2, each term weighted by sqrt(det G).
std::vector<Term> metric_terms(const double g[3], double thin_plate, double membrane) {
  const double det = g[0] * g[2] - g[1] * g[1];
  // G^-1 = [[g2, -g1], [-g1, g0]] / det; its Cholesky factor
  const double i00 = g[2] / det, i01 = -g[1] / det, i11 = g[0] / det;
  const double l11 = std::sqrt(i00), l21 = i01 / l11, l22 = std::sqrt(i11 - l21 * l21);
  const double area = std::sqrt(det);
  std::vector<Term> terms;
  if (thin_plate > 0.0) {
    terms.push_back({{0, 0, l11 * l11, 2 * l11 * l21, l21 * l21}, thin_plate * area});  // (L^T H L)_11
    terms.push_back({{0, 0, 0, l22 * l11, l22 * l21}, 2.0 * thin_plate * area});        // (L^T H L)_12
    terms.push_back({{0, 0, 0, 0, l22 * l22}, thin_plate * area});                      // (L^T H L)_22
  }
  if (membrane > 0.0) {
    terms.push_back({{l11, l21, 0, 0, 0}, membrane * area});
    terms.push_back({{0, l22, 0, 0, 0}, membrane * area});
  }
  return terms;
}

// Per face, the terms of fairness_matrix's reference metric: G the first
// fundamental form of the limit surface of `reference` at the face's
// centre; at a face with an extraordinary corner (inside the mesh, valence
// other than the scheme's), where Bfr's parameterisation is far from affine
// within the face and a constant G would charge that, the face's parametric
// shape (the unit square, or the equilateral triangle of Loop) scaled to the
// area sqrt(det G).
std::vector<std::vector<Term>> reference_terms(const LimitSurface& surface, const double* reference,
                                               const std::vector<std::uint8_t>& hole, double thin_plate,
                                               double membrane) {
  const Topology& t = surface.topology();
  const bool loop = surface.scheme() == Scheme::Loop;
  const std::int32_t size = loop ? 3 : 4, regular_valence = loop ? 6 : 4;
  std::vector<std::int32_t> faces;
  std::vector<double> uv;
  for (std::size_t f = 0; f < t.n_faces(); ++f) {
    if (hole[f]) continue;
    if (t.face_size(f) != size)
      throw ParameterError("the reference metric needs a mesh of " + std::string(loop ? "triangles" : "quads") +
                           ": face " + std::to_string(f) + " has " + std::to_string(t.face_size(f)) +
                           " corners (refine the mesh first)");
    faces.push_back(static_cast<std::int32_t>(f));
    uv.insert(uv.end(), {loop ? 1.0 / 3.0 : 0.5, loop ? 1.0 / 3.0 : 0.5});
  }
  const SurfaceRows rows = surface.rows(faces.data(), uv.data(), faces.size(), 1);
  const auto& fi = t.face_indices();
  auto times_reference = [&](const CsrMatrix& m, std::size_t q, double out[3]) {
    for (auto p = static_cast<std::size_t>(m.indptr[q]); p < static_cast<std::size_t>(m.indptr[q + 1]); ++p)
      for (std::size_t c = 0; c < 3; ++c) out[c] += m.data[p] * reference[3 * static_cast<std::size_t>(m.indices[p]) + c];
  };
  std::vector<std::vector<Term>> out(t.n_faces());
  for (std::size_t q = 0; q < faces.size(); ++q) {
    const auto f = static_cast<std::size_t>(faces[q]);
    double su[3] = {0, 0, 0}, sv[3] = {0, 0, 0};
    times_reference(rows.du, q, su);
    times_reference(rows.dv, q, sv);
    double g[3] = {su[0] * su[0] + su[1] * su[1] + su[2] * su[2], su[0] * sv[0] + su[1] * sv[1] + su[2] * sv[2],
                   sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]};
    // A guard against a degenerate G (a reference face folded flat): a floor
    // of 1e-9 of its trace on both axes.
    const double trace = g[0] + g[2];
    if (!(trace > 0.0) || !std::isfinite(trace))
      throw ParameterError("the reference surface is degenerate at face " + std::to_string(f) +
                           ": its derivatives there are zero or not finite");
    g[0] += 1e-9 * trace;
    g[2] += 1e-9 * trace;
    bool extraordinary = false;
    for (std::int32_t i = 0; i < size; ++i) {
      const auto v = static_cast<std::size_t>(fi[static_cast<std::size_t>(t.face_offset(f) + i)]);
      if (!t.is_boundary(v) && t.valence(v) != regular_valence) extraordinary = true;
    }
    if (extraordinary) {
      const double area = std::sqrt(g[0] * g[2] - g[1] * g[1]);
      // unit square: I; Loop's equilateral triangle in (u, v): [[1, 1/2], [1/2, 1]] / sqrt(3/4), determinant 1
      const double k = loop ? area / std::sqrt(0.75) : area;
      g[0] = k;
      g[1] = loop ? 0.5 * k : 0.0;
      g[2] = k;
    }
    out[f] = metric_terms(g, thin_plate, membrane);
  }
  return out;
}

// One thread's work space.
struct Worker {
  std::vector<std::int32_t> local;  // column -> its place in `cols`, -1 elsewhere
  std::vector<std::int32_t> cols;
  std::vector<double> a, e, qd;
  std::vector<std::int32_t> first;  // per control point of a shared class: its place in `cols`, or -1
};

// What an element needs besides the rows: the weights, the Gauss terms and
// the closed forms.
struct ElementRules {
  const std::vector<Term>& terms;
  const ExactForms& exact;
  double thin_plate, membrane;
};

// Adds coef * row r of m to the dense row `a` (over the element's columns).
void add_row(const CsrMatrix& m, std::size_t r, double coef, const std::vector<std::int32_t>& local, double* a) {
  if (coef == 0.0) return;
  for (auto p = static_cast<std::size_t>(m.indptr[r]); p < static_cast<std::size_t>(m.indptr[r + 1]); ++p)
    a[static_cast<std::size_t>(local[static_cast<std::size_t>(m.indices[p])])] += coef * m.data[p];
}

// E += s a a^T on the upper triangle (n x n, row-major).
void add_outer(double s, const double* a, std::size_t n, double* e) {
  for (std::size_t i = 0; i < n; ++i) {
    const double ai = s * a[i];
    if (ai == 0.0) continue;
    double* row = e + i * n;
    for (std::size_t j = i; j < n; ++j) row[j] += ai * a[j];
  }
}

// A face's element matrix from the rows of its pieces' points: w.e (upper
// triangle, row-major) over the sorted global columns w.cols, w.local their
// places (store_element clears them).
void element_matrix(const SurfaceRows& rows, const double* weights, const Piece* pieces, std::size_t n_pieces,
                 const ElementRules& er, const std::vector<Term>& terms, Worker& w) {
  const CsrMatrix* d[6] = {&rows.position, &rows.du, &rows.dv, &rows.duu, &rows.duv, &rows.dvv};
  const std::size_t r0 = pieces[0].first, r1 = pieces[n_pieces - 1].first + pieces[n_pieces - 1].count;
  w.cols.clear();
  for (const CsrMatrix* m : d) {
    if (m == d[0]) continue;  // positions do not enter the energy
    for (auto p = static_cast<std::size_t>(m->indptr[r0]); p < static_cast<std::size_t>(m->indptr[r1]); ++p) {
      const std::int32_t c = m->indices[p];
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
  const std::size_t nd = ExactForms::kData;
  for (std::size_t pi = 0; pi < n_pieces; ++pi) {
    const Piece& pc = pieces[pi];
    if (!pc.exact) {
      w.a.resize(n);
      for (std::size_t r = pc.first; r < pc.first + pc.count; ++r)
        for (const Term& t : terms) {
          std::fill(w.a.begin(), w.a.end(), 0.0);
          for (int i = 0; i < 5; ++i) add_row(*d[i + 1], r, t.coef[i], w.local, w.a.data());
          add_outer(weights[r] * t.weight, w.a.data(), n, w.e.data());
        }
      continue;
    }
    // The data (derivatives in the piece's (s, t) = (u, v) / h) as dense rows.
    w.a.assign(nd * n, 0.0);
    const double h = pc.scale;
    for (std::size_t q = 0; q < pc.count; ++q) {
      const std::size_t r = pc.first + q;
      double* a = w.a.data() + q * 5 * n;
      add_row(*d[1], r, h, w.local, a);
      add_row(*d[2], r, h, w.local, a + n);
      add_row(*d[3], r, h * h, w.local, a + 2 * n);
      add_row(*d[4], r, h * h, w.local, a + 3 * n);
      add_row(*d[5], r, h * h, w.local, a + 4 * n);
    }
    // E += D^T Q D, Q = thin_plate h^-2 Q_tp + membrane Q_mb.
    const double tp = er.thin_plate / (pc.scale * pc.scale);
    w.qd.assign(nd * n, 0.0);
    for (std::size_t i = 0; i < nd; ++i)
      for (std::size_t j = 0; j < nd; ++j) {
        const double q = tp * er.exact.thin_plate[i * nd + j] + er.membrane * er.exact.membrane[i * nd + j];
        if (q == 0.0) continue;
        const double* dj = w.a.data() + j * n;
        double* out = w.qd.data() + i * n;
        for (std::size_t k = 0; k < n; ++k) out[k] += q * dj[k];
      }
    for (std::size_t i = 0; i < nd; ++i) {
      const double* di = w.a.data() + i * n;
      const double* qi = w.qd.data() + i * n;
      for (std::size_t a = 0; a < n; ++a) {
        if (di[a] == 0.0) continue;
        double* row = w.e.data() + a * n;
        for (std::size_t b = a; b < n; ++b) row[b] += di[a] * qi[b];
      }
    }
  }
}

// The element matrix of element_matrix (w.e, upper triangle over w.cols) as
// the full symmetric matrix of class c over its columns: for a shared class
// the control points `cv` of its representative (distinct, in its class's order),
// else the face's own columns w.cols. Clears w.local.
void store_element(Worker& w, const std::int32_t* cv, std::size_t n_cv, std::size_t c, Elements& el) {
  const std::size_t n = w.cols.size();
  std::vector<double>& out = el.element[c];
  if (!el.shared[c]) {
    el.own_columns[c] = w.cols;
    out.resize(n * n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i; j < n; ++j) out[i * n + j] = out[j * n + i] = w.e[i * n + j];
  } else {
    out.assign(n_cv * n_cv, 0.0);
    // Each column at its first listing; a repeat (the list names the vertex
    // again) and a control point without weight at any point stay zero.
    std::size_t found = 0;
    w.first.assign(n_cv, -1);
    for (std::size_t i = 0; i < n_cv; ++i) {
      const std::int32_t a = w.local[static_cast<std::size_t>(cv[i])];
      if (a < 0 || std::find(cv, cv + i, cv[i]) != cv + i) continue;
      w.first[i] = a;
      ++found;
    }
    if (found != n)
      throw std::logic_error("a face's stencils reach beyond its control points: the fairness matrix would lose "
                             "entries");
    for (std::size_t i = 0; i < n_cv; ++i) {
      const std::int32_t a = w.first[i];
      if (a < 0) continue;
      for (std::size_t j = 0; j < n_cv; ++j) {
        const std::int32_t b = w.first[j];
        if (b < 0) continue;
        const auto lo = static_cast<std::size_t>(std::min(a, b)), hi = static_cast<std::size_t>(std::max(a, b));
        out[i * n_cv + j] = w.e[lo * n + hi];
      }
    }
  }
  for (const std::int32_t col : w.cols) w.local[static_cast<std::size_t>(col)] = -1;
}

// A face's element as assemble reads it: its columns and its matrix.
struct FaceElement {
  const std::int32_t* columns;
  const double* matrix;  // n x n, row-major
  std::size_t n;
};

// Per face (empty for holes), its element, once every class's matrix is stored.
std::vector<FaceElement> face_elements(const Elements& el) {
  std::vector<FaceElement> out(el.face_class.size(), FaceElement{nullptr, nullptr, 0});
  for (std::size_t f = 0; f < out.size(); ++f)
    if (el.live(f))
      out[f] = {el.columns(f), el.element[static_cast<std::size_t>(el.face_class[f])].data(), el.n_columns(f)};
  return out;
}

// Row i of a face's element matrix (its row of the face's i-th column) added
// into `row` at the slots of the face's columns: row[slot[j]] += E[i][j]. The
// one step where a face's element matrix enters K.
inline void add_element_row(const FaceElement& face, std::size_t i, const std::int32_t* slot, double* row) {
  const double* e = face.matrix + i * face.n;
  for (std::size_t j = 0; j < face.n; ++j) row[slot[j]] += e[j];
}

// Rows assemble builds before it reserves the rest of its arrays by their
// lengths so far.
constexpr std::size_t kRowsToEstimate = 1024;

// K in CSR from the element matrices, assembled row by row (threads take
// ranges of rows): row r's columns are the union of the columns of the faces
// that have r among theirs, sorted (or, without sorted_columns, in the order
// they first appear); its values the sum of those faces' rows for r
// (add_element_row, from the slots found with the columns). No list of
// entries, no sort of all entries: each row's few columns are sorted on
// their own.
CsrMatrix assemble(const Elements& el, std::size_t n_rows, int n_threads, bool sorted_columns) {
  const std::vector<FaceElement> faces = face_elements(el);
  const std::size_t n_faces = faces.size();
  std::size_t max_n = 0;
  for (const FaceElement& face : faces) max_n = std::max(max_n, face.n);
  // Per vertex, its incidences (face, place among the face's columns).
  std::vector<std::int64_t> start(n_rows + 1, 0);
  for (const FaceElement& face : faces)
    for (std::size_t i = 0; i < face.n; ++i) ++start[static_cast<std::size_t>(face.columns[i]) + 1];
  for (std::size_t v = 0; v < n_rows; ++v) start[v + 1] += start[v];
  std::vector<std::pair<std::int32_t, std::int32_t>> incidence(static_cast<std::size_t>(start[n_rows]));
  {
    std::vector<std::int64_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < n_faces; ++f)
      for (std::size_t i = 0; i < faces[f].n; ++i)
        incidence[static_cast<std::size_t>(cursor[static_cast<std::size_t>(faces[f].columns[i])]++)] = {
            static_cast<std::int32_t>(f), static_cast<std::int32_t>(i)};
  }
  // Each task's rows, into arrays of its own (the final ones for one task).
  struct Part {
    std::vector<std::int32_t> indices;
    std::vector<double> data;
  };
  std::vector<Part> parts(static_cast<std::size_t>(n_threads));
  std::vector<std::int64_t> count(n_rows + 1, 0);
  const auto nt = static_cast<std::size_t>(n_threads);
  detail::for_each_task(n_threads > 1, n_threads, [&](int t) {
    const auto ut = static_cast<std::size_t>(t);
    const std::size_t r0 = n_rows * ut / nt, r1 = n_rows * (ut + 1) / nt;
    Part& part = parts[ut];
    // place[col]: the column's slot in the row being built (its first
    // appearance), -1 elsewhere; slots[q]: the slot of the q-th (incidence,
    // column) pair of the row, so that the values are summed from this
    // buffer without looking the columns up again.
    std::vector<std::int32_t> place(n_rows, -1), slots;
    std::vector<std::int32_t> cols;
    std::vector<double> sums;
    for (std::size_t r = r0; r < r1; ++r) {
      if (r == r0 + kRowsToEstimate) {  // the entries per incidence so far, times the incidences left, and a tenth
        const double per_incidence = static_cast<double>(part.indices.size()) /
                                     static_cast<double>(std::max<std::int64_t>(1, start[r] - start[r0]));
        const auto want = part.indices.size() +
                          static_cast<std::size_t>(1.1 * per_incidence * static_cast<double>(start[r1] - start[r]));
        part.indices.reserve(want);
        part.data.reserve(want);
      }
      const auto p0 = static_cast<std::size_t>(start[r]), p1 = static_cast<std::size_t>(start[r + 1]);
      if (slots.size() < (p1 - p0) * max_n) slots.resize((p1 - p0) * max_n);
      if (cols.size() < (p1 - p0) * max_n) cols.resize((p1 - p0) * max_n);
      std::int32_t* slot = slots.data();
      std::int32_t n_cols = 0;
      for (std::size_t p = p0; p < p1; ++p) {
        const FaceElement& face = faces[static_cast<std::size_t>(incidence[p].first)];
        for (std::size_t j = 0; j < face.n; ++j) {
          const std::int32_t c = face.columns[j];
          std::int32_t at = place[static_cast<std::size_t>(c)];
          if (at < 0) {
            at = n_cols++;
            place[static_cast<std::size_t>(c)] = at;
            cols[static_cast<std::size_t>(at)] = c;
          }
          *slot++ = at;
        }
      }
      // The values in the incidences' order (each slot's sum as add_element_row forms it).
      sums.assign(static_cast<std::size_t>(n_cols), 0.0);
      slot = slots.data();
      for (std::size_t p = p0; p < p1; ++p) {
        const FaceElement& face = faces[static_cast<std::size_t>(incidence[p].first)];
        add_element_row(face, static_cast<std::size_t>(incidence[p].second), slot, sums.data());
        slot += face.n;
      }
      if (sorted_columns) std::sort(cols.begin(), cols.begin() + n_cols);
      for (std::int32_t k = 0; k < n_cols; ++k) {
        const std::int32_t c = cols[static_cast<std::size_t>(k)];
        part.indices.push_back(c);
        part.data.push_back(sums[static_cast<std::size_t>(place[static_cast<std::size_t>(c)])]);
        place[static_cast<std::size_t>(c)] = -1;
      }
      count[r + 1] = n_cols;
    }
  });
  for (std::size_t r = 0; r < n_rows; ++r) count[r + 1] += count[r];
  if (count[n_rows] > static_cast<std::int64_t>(INT32_MAX))
    throw ParameterError("the fairness matrix has " + std::to_string(count[n_rows]) +
                         " entries, more than 32-bit CSR indices address");
  CsrMatrix k;
  k.n_rows = k.n_cols = n_rows;
  k.indptr.resize(n_rows + 1);
  for (std::size_t r = 0; r <= n_rows; ++r) k.indptr[r] = static_cast<std::int32_t>(count[r]);
  if (n_threads == 1) {
    k.indices = std::move(parts[0].indices);
    k.data = std::move(parts[0].data);
    return k;
  }
  k.indices.resize(static_cast<std::size_t>(count[n_rows]));
  k.data.resize(k.indices.size());
  detail::for_each_task(true, n_threads, [&](int t) {
    const auto ut = static_cast<std::size_t>(t);
    const auto at = static_cast<std::size_t>(count[n_rows * ut / nt]);
    std::copy(parts[ut].indices.begin(), parts[ut].indices.end(), k.indices.begin() + static_cast<std::ptrdiff_t>(at));
    std::copy(parts[ut].data.begin(), parts[ut].data.end(), k.data.begin() + static_cast<std::ptrdiff_t>(at));
  });
  return k;
}

}  // namespace

CsrMatrix fairness_matrix(const LimitSurface& surface, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature, const double* reference, bool sorted_columns) {
  check_options(thin_plate, membrane, quadrature);
  const Topology& topo = surface.topology();
  const Scheme scheme = surface.scheme();
  const std::size_t n_faces = topo.n_faces();
  const Irregular irr(topo, scheme, surface.tags());
  std::vector<std::uint8_t> hole(n_faces, 0);
  for (const std::int32_t f : surface.tags().holes) hole[static_cast<std::size_t>(f)] = 1;
  const Rule rule = gauss_legendre(quadrature.gauss_points);
  const Pieces pieces(rule, quadrature.depth, membrane == 0.0, reference == nullptr);
  const std::vector<Term> terms = energy_terms(scheme, thin_plate, membrane);
  const std::vector<std::vector<Term>> face_terms =
      reference ? reference_terms(surface, reference, hole, thin_plate, membrane) : std::vector<std::vector<Term>>{};

  const int n_threads = std::max(1, std::min<int>(detail::available_processors(),
                                                  static_cast<int>(n_faces / kFacesPerTask)));
  std::vector<Worker> workers(static_cast<std::size_t>(n_threads));
  for (Worker& w : workers) w.local.assign(surface.n_vertices(), -1);

  const ExactForms exact;
  const ElementRules er{terms, exact, thin_plate, membrane};
  Elements el = face_classes(surface, hole, quadrature.reuse && reference == nullptr);
  // The faces integrated here: each class's representative, in face order.
  const std::vector<std::int32_t>& direct = el.representative;
  std::vector<std::int32_t> point_faces;
  std::vector<std::size_t> face_first;  // per chunk face, its first piece; one past the end last
  std::vector<std::int32_t> chunk_faces;
  std::vector<Piece> chunk_pieces;
  std::vector<double> uvw, uv, weights;
  Marks marks;
  std::size_t d = 0;
  while (d < direct.size()) {
    poll_interrupt();
    face_first.clear();
    chunk_faces.clear();
    chunk_pieces.clear();
    uvw.clear();
    point_faces.clear();
    for (; d < direct.size() && uvw.size() < 3 * kChunkPoints; ++d) {
      const auto f = static_cast<std::size_t>(direct[d]);
      face_first.push_back(chunk_pieces.size());
      chunk_faces.push_back(direct[d]);
      face_pieces(topo, scheme, irr, pieces, f, marks, chunk_pieces, uvw);
      point_faces.resize(uvw.size() / 3, direct[d]);
    }
    const std::size_t k = uvw.size() / 3;
    const std::size_t n_chunk = face_first.size();
    face_first.push_back(chunk_pieces.size());
    uv.resize(2 * k);
    weights.resize(k);
    for (std::size_t p = 0; p < k; ++p) {
      uv[2 * p] = uvw[3 * p];
      uv[2 * p + 1] = uvw[3 * p + 1];
      weights[p] = uvw[3 * p + 2];
    }
    const SurfaceRows rows = surface.rows(point_faces.data(), uv.data(), k, 2);
    detail::for_each_task(n_threads > 1, n_threads, [&](int t) {
      Worker& w = workers[static_cast<std::size_t>(t)];
      const auto nt = static_cast<std::size_t>(n_threads), ut = static_cast<std::size_t>(t);
      for (std::size_t c = n_chunk * ut / nt; c < n_chunk * (ut + 1) / nt; ++c) {
        const auto f = static_cast<std::size_t>(chunk_faces[c]);
        element_matrix(rows, weights.data(), chunk_pieces.data() + face_first[c], face_first[c + 1] - face_first[c],
                       er, reference ? face_terms[f] : terms, w);
        const auto cls = static_cast<std::size_t>(el.face_class[f]);
        store_element(w, el.shared[cls] ? el.columns(f) : nullptr, el.shared[cls] ? el.n_columns(f) : 0, cls, el);
      }
    });
  }
  workers.clear();
  return assemble(el, surface.n_vertices(), n_threads, sorted_columns);
}

CsrMatrix fairness_matrix(const Topology& topology, const Rules& rules, double thin_plate, double membrane,
                          const FairnessQuadrature& quadrature, const double* reference, bool sorted_columns) {
  const std::vector<double> zeros(3 * topology.n_vertices(), 0.0);
  const LimitSurface surface(topology, zeros.data(), rules.scheme, rules.boundary, rules.tags);
  return fairness_matrix(surface, thin_plate, membrane, quadrature, reference, sorted_columns);
}

}  // namespace sorpia
