#pragma once
// The quadrature of fairness_matrix (fairness.cpp) over a face's domain: the
// Gauss-Legendre rule, the marks a face's domain is refined towards (its
// irregular corners and tagged edges), and the pieces of that refinement with
// their points and weights. Internal to the fit layer.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::fairness_detail {

// Two parameters closer than this are the same point of a face's domain
// (domains have side 1; pieces are at least 2^-12 apart).
constexpr double kSame = 1e-12;

// The n-point Gauss-Legendre rule on [0, 1] (nodes by Newton's method on the
// Legendre polynomial; weights 2 / ((1 - t^2) P_n'(t)^2) on [-1, 1], halved).
struct Rule {
  std::vector<double> x, w;
};

Rule gauss_legendre(int n);

struct UV {
  double u, v;
};

inline UV mid(UV a, UV b) { return {0.5 * (a.u + b.u), 0.5 * (a.v + b.v)}; }

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

  void square(UV o, double h, int level, const Marks& m, std::vector<Piece>& out, std::vector<double>& uvw) const;

  void triangle(UV a, UV b, UV c, double h, int level, const Marks& m, std::vector<Piece>& out,
                std::vector<double>& uvw) const;

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

// Which vertices and edges make a face's patch other than a regular box
// spline, so that its domain is refined towards them.
struct Irregular {
  std::vector<std::uint8_t> vertex;
  std::vector<std::uint8_t> half_edge;  // per half-edge (Topology::half_edge_twins): its edge is tagged; empty if none

  Irregular(const Topology& t, Scheme scheme, const Tags& tags);
  // Whether the edge of half-edge h (corner i to i + 1 of a face: face_offset + i) is tagged.
  bool tagged(std::int32_t h) const { return !half_edge.empty() && half_edge[static_cast<std::size_t>(h)] != 0; }
};

// The pieces of face f and their points (u, v, Gauss weight with the face's measure).
void face_pieces(const Topology& t, Scheme scheme, const Irregular& irr, const Pieces& pieces, std::size_t f,
                 Marks& m, std::vector<Piece>& out, std::vector<double>& uvw);

}  // namespace sorpia::fairness_detail
