#include "sorpia/fairness.hpp"

// fairness_matrix: the driver. Its parts, each in its own unit: the
// quadrature of a face's domain (fairness_pieces), the closed forms of
// bicubic pieces (fairness_exact), the integrands (fairness_terms), the
// classes of faces that share an element matrix (fairness_elements), and the
// element matrices with K's assembly (fairness_assembly).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "fairness_assembly.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

using namespace fairness_detail;

namespace {

// Quadrature points asked of LimitSurface::rows at a time: bounds the memory
// of the rows (six CSR matrices of this many rows) whatever the mesh size.
constexpr std::size_t kChunkPoints = 32768;
// Faces a thread takes at least, so that small meshes run on one thread.
constexpr std::size_t kFacesPerTask = 256;

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
