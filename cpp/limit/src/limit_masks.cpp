#include "sorpia/limit_masks.hpp"

#include <opensubdiv/sdc/catmarkScheme.h>
#include <opensubdiv/sdc/loopScheme.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "sorpia/errors.hpp"

namespace sorpia {

namespace {
namespace Sdc = OpenSubdiv::Sdc;

// The minimal vertex neighbourhood and mask types Sdc::Scheme asks for (the
// same interface Far::PrimvarRefinerReal::Limit fills from its refiner). A
// crease vertex is handed two edges, both infinitely sharp: its mask weights
// the two ends of the crease, i.e. the two boundary neighbours.
struct Neighbourhood {
  int n_edges, n_faces;
  bool crease;
  int GetNumEdges() const { return n_edges; }
  int GetNumFaces() const { return n_faces; }
  float* GetSharpnessPerEdge(float* s) const {
    for (int i = 0; i < n_edges; ++i) s[i] = crease ? Sdc::Crease::SHARPNESS_INFINITE : 0.0f;
    return s;
  }
};
struct Mask {
  typedef double Weight;
  std::array<double, 2> v{};
  double* e;
  double* f;
  int nv = 0, ne = 0, nf = 0;
  void SetNumVertexWeights(int c) { nv = c; }
  void SetNumEdgeWeights(int c) { ne = c; }
  void SetNumFaceWeights(int c) { nf = c; }
  int GetNumVertexWeights() const { return nv; }
  int GetNumEdgeWeights() const { return ne; }
  int GetNumFaceWeights() const { return nf; }
  double& VertexWeight(int i) { return v[i]; }
  double& EdgeWeight(int i) { return e[i]; }
  double& FaceWeight(int i) { return f[i]; }
  void SetFaceWeightsForFaceCenters(bool) {}
};

// The limit mask of a vertex of n_edges edges and n_faces faces under `rule`,
// from Sdc::Scheme<kScheme>: (vertex weight, first edge weight, first face
// weight). Smooth masks weight all edges alike and all faces alike; crease
// masks only the crease ends (edges 0 and 1 here).
template <Sdc::SchemeType kScheme>
CatmarkMask sdc_limit_mask(int n_edges, int n_faces, Sdc::Crease::Rule rule) {
  std::vector<double> edge_weights(std::max(n_edges, 1)), face_weights(std::max(n_faces, 1));
  Mask mask;
  mask.e = edge_weights.data();
  mask.f = face_weights.data();
  const Neighbourhood hood{n_edges, n_faces, rule == Sdc::Crease::RULE_CREASE};
  Sdc::Scheme<kScheme>().ComputeVertexLimitMask(hood, mask, rule);
  if (mask.nv != 1) throw std::logic_error("sorpia: unexpected limit mask shape");
  return CatmarkMask{mask.v[0], mask.ne ? edge_weights[0] : 0.0, mask.nf ? face_weights[0] : 0.0};
}

LimitMask sdc_limit_mask(int n_edges, int n_faces, Sdc::Crease::Rule rule) {
  const CatmarkMask m = sdc_limit_mask<Sdc::SCHEME_LOOP>(n_edges, n_faces, rule);
  // Loop limit masks have no face weights and one edge weight for every mask
  // vertex (zero for the interior edges of a crease).
  if (m.face != 0.0) throw std::logic_error("sorpia: unexpected Loop limit mask shape");
  return LimitMask{m.diag, m.edge};
}

constexpr int kTabulated = 64;  // valences up to this are looked up

const std::array<LimitMask, kTabulated + 1>& smooth_table() {
  static const std::array<LimitMask, kTabulated + 1> table = [] {
    std::array<LimitMask, kTabulated + 1> t{};
    for (int n = 2; n <= kTabulated; ++n) t[n] = sdc_limit_mask(n, n, Sdc::Crease::RULE_SMOOTH);
    return t;
  }();
  return table;
}

const std::array<CatmarkMask, kTabulated + 1>& catmark_table() {
  static const std::array<CatmarkMask, kTabulated + 1> table = [] {
    std::array<CatmarkMask, kTabulated + 1> t{};
    for (int n = 2; n <= kTabulated; ++n)
      t[n] = sdc_limit_mask<Sdc::SCHEME_CATMARK>(n, n, Sdc::Crease::RULE_SMOOTH);
    return t;
  }();
  return table;
}

}  // namespace

CatmarkMask catmark_smooth_limit_mask(int valence) {
  if (valence < 2)
    throw ParameterError("an interior vertex has valence at least 2, got " + std::to_string(valence));
  if (valence <= kTabulated) return catmark_table()[valence];
  return sdc_limit_mask<Sdc::SCHEME_CATMARK>(valence, valence, Sdc::Crease::RULE_SMOOTH);
}

CatmarkMask catmark_crease_limit_mask() {
  static const CatmarkMask mask = sdc_limit_mask<Sdc::SCHEME_CATMARK>(2, 1, Sdc::Crease::RULE_CREASE);
  return mask;
}

LimitMask smooth_limit_mask(int valence) {
  if (valence < 2) throw ParameterError("an interior vertex has valence at least 2, got " + std::to_string(valence));
  if (valence <= kTabulated) return smooth_table()[valence];
  return sdc_limit_mask(valence, valence, Sdc::Crease::RULE_SMOOTH);
}

LimitMask crease_limit_mask() {
  static const LimitMask mask = sdc_limit_mask(2, 1, Sdc::Crease::RULE_CREASE);
  return mask;
}

LimitMask corner_limit_mask() {
  static const LimitMask mask = sdc_limit_mask(2, 1, Sdc::Crease::RULE_CORNER);
  return mask;
}

LimitMask limit_mask(const Topology& topology, std::size_t i, Boundary boundary) {
  if (topology.is_unreferenced(i)) return corner_limit_mask();
  if (!topology.is_boundary(i)) return smooth_limit_mask(topology.valence(i));
  if (topology.face_count(i) == 1 && boundary == Boundary::EdgeAndCorner) return corner_limit_mask();
  return crease_limit_mask();
}

}  // namespace sorpia
