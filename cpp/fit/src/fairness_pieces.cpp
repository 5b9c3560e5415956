#include "fairness_pieces.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

#include "sorpia/subface_grid.hpp"

namespace sorpia::fairness_detail {

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

void Pieces::square(UV o, double h, int level, const Marks& m, std::vector<Piece>& out, std::vector<double>& uvw) const {
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

void Pieces::triangle(UV a, UV b, UV c, double h, int level, const Marks& m, std::vector<Piece>& out,
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

Irregular::Irregular(const Topology& t, Scheme scheme, const Tags& tags) : vertex(t.n_vertices(), 0) {
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
  const std::vector<std::int32_t>& twin = t.half_edge_twins();
  half_edge.assign(twin.size(), 0);
  for (const std::int32_t h : t.find_half_edges(pairs.data(), pairs.size() / 2)) {
    if (h < 0) continue;  // not an edge (check_tags refuses it): nothing to refine towards
    half_edge[static_cast<std::size_t>(h)] = 1;
    if (twin[static_cast<std::size_t>(h)] >= 0) half_edge[static_cast<std::size_t>(twin[static_cast<std::size_t>(h)])] = 1;
  }
}

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

}  // namespace sorpia::fairness_detail
