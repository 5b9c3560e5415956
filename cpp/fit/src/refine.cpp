#include "sorpia/refine.hpp"

#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyRefiner.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/memory.hpp"
#include "sorpia/surface.hpp"

namespace sorpia {

namespace {

namespace Far = OpenSubdiv::Far;

// Bytes per fine vertex beyond the refiner (tessellation_bytes counts it): R
// (a stencil of about 8 to 40 weights, 12 bytes each), the fine mesh's limit
// rows, a fairness matrix (the vertices within two rings: up to about 50
// entries of 12 bytes) and a dozen (n, 3) vectors of the solver, with room to
// spare for the copies Python makes.
constexpr double kFairBytesPerVertex = 2000.0;

// Faces of the fine mesh `levels` below a coarse mesh.
double fine_faces(Scheme scheme, std::size_t n_faces, std::size_t n_face_vertices, int levels) {
  const double first =
      scheme == Scheme::Loop ? 4.0 * static_cast<double>(n_faces) : static_cast<double>(n_face_vertices);
  return first * std::pow(4.0, levels - 1);
}

}  // namespace

std::size_t refinement_bytes(Scheme scheme, std::size_t n_vertices, std::size_t n_faces, std::size_t n_face_vertices,
                             int levels) {
  if (n_face_vertices == 0) n_face_vertices = n_faces * (scheme == Scheme::Loop ? 3 : 4);
  const double faces = fine_faces(scheme, n_faces, n_face_vertices, levels);
  // Euler: about half as many vertices as faces for triangles, as many for quads.
  const double verts = static_cast<double>(n_vertices) + (scheme == Scheme::Loop ? faces / 2.0 : faces);
  const double bytes = static_cast<double>(tessellation_bytes(scheme, n_vertices, n_faces, n_face_vertices, levels)) +
                       kFairBytesPerVertex * verts;
  return bytes >= static_cast<double>(std::numeric_limits<std::size_t>::max())
             ? std::numeric_limits<std::size_t>::max()
             : static_cast<std::size_t>(bytes);
}

void check_refinement(const Topology& topology, const Rules& rules, int levels) {
  if (levels < 1 || levels > kMaxRefinementLevels)
    throw ParameterError("levels must be in 1.." + std::to_string(kMaxRefinementLevels) + ", got " +
                         std::to_string(levels));
  const Scheme scheme = rules.scheme;
  const std::size_t n = topology.n_vertices();
  const std::size_t m = topology.n_faces();
  const std::size_t corners = topology.face_indices().size();
  const double faces = fine_faces(scheme, m, corners, levels);
  const char* face_kind = scheme == Scheme::Loop ? " triangles" : " quads";
  char count[32];
  std::snprintf(count, sizeof count, "%.0f", faces);
  if (faces > static_cast<double>(std::numeric_limits<std::int32_t>::max()) / 4.0)
    throw ParameterError("levels = " + std::to_string(levels) + " would make " + count + face_kind + " from " +
                         std::to_string(m) + " faces, more than int32 indices hold");
  const std::size_t need = refinement_bytes(scheme, n, m, corners, levels);
  const std::size_t avail = available_memory_bytes();
  if (avail != 0 && need > avail)
    throw ParameterError("levels = " + std::to_string(levels) + " makes " + count + face_kind +
                         " and needs about " + human_bytes(static_cast<double>(need)) + ", but only " +
                         human_bytes(static_cast<double>(avail)) + " of memory is available: use fewer levels");
}

RefinedMesh refine_uniform(const Topology& topology, const Rules& rules, int levels, const double* vertices,
                           bool with_refinement) {
  check_refinement(topology, rules, levels);
  const Scheme scheme = rules.scheme;
  const std::size_t n = topology.n_vertices();

  detail::Refiner osd = detail::make_refiner(topology, scheme, rules.boundary, rules.tags);
  // The last level's edges (their sharpness) and vertex-face relations, read
  // only where creases or corners have sharpness to carry: without them the
  // fine mesh has no tags but holes (boundary edges and one-face corners are
  // sharp by the rules).
  const bool sharp_tags = !rules.tags.crease_sharpness.empty() || !rules.tags.corner_sharpness.empty();
  const detail::UniformRefinement uniform(osd, n, levels, sharp_tags);
  poll_interrupt();
  const Far::TopologyRefiner& refiner = uniform.refiner();
  const std::size_t n_osd = uniform.n_osd();
  const Far::TopologyLevel& last = uniform.last();
  const auto n_last = static_cast<std::size_t>(last.GetNumVertices());
  RefinedMesh out;
  out.n_vertices = uniform.n_fine_vertices();
  const auto fine_index = [&](int j) { return uniform.fine_index(j); };

  // Faces, and the coarse face of each (walking up the parents).
  const int n_fine_faces = last.GetNumFaces();
  out.mesh.face_size = scheme == Scheme::Loop ? 3 : 4;
  out.mesh.face_vertex_indices.reserve(static_cast<std::size_t>(n_fine_faces) * out.mesh.face_size);
  out.coarse_face.resize(static_cast<std::size_t>(n_fine_faces));
  for (int f = 0; f < n_fine_faces; ++f) {
    const auto fv = last.GetFaceVertices(f);
    if (fv.size() != out.mesh.face_size) throw std::logic_error("a refined face of unexpected size");
    for (const int v : fv) out.mesh.face_vertex_indices.push_back(fine_index(v));
    int parent = f;
    for (int l = levels; l >= 1; --l) parent = refiner.GetLevel(l).GetFaceParentFace(parent);
    out.coarse_face[static_cast<std::size_t>(f)] = parent;
    if (last.IsFaceHole(f)) out.tags.holes.push_back(f);
  }
  poll_interrupt();

  // Tags: Far's sharpness of the last level, where the fine mesh's own rules
  // would not give it (boundary edges are infinitely sharp; so is a one-face
  // corner under edge-and-corner).
  const bool corner_rule = rules.boundary == Boundary::EdgeAndCorner;
  const auto sharpness = [](float s) {
    return s >= static_cast<float>(kInfiniteSharpness) ? kInfiniteSharpness : static_cast<double>(s);
  };
  for (int e = 0; sharp_tags && e < last.GetNumEdges(); ++e) {
    const float s = last.GetEdgeSharpness(e);
    if (s <= 0.0f || last.IsEdgeBoundary(e)) continue;
    const auto ev = last.GetEdgeVertices(e);
    out.tags.crease_vertices.push_back(fine_index(ev[0]));
    out.tags.crease_vertices.push_back(fine_index(ev[1]));
    out.tags.crease_sharpness.push_back(sharpness(s));
  }
  for (int v = 0; sharp_tags && v < last.GetNumVertices(); ++v) {
    const float s = last.GetVertexSharpness(v);
    if (s <= 0.0f) continue;
    if (corner_rule && last.GetVertexFaces(v).size() == 1 && s >= static_cast<float>(kInfiniteSharpness)) continue;
    out.tags.corner_vertices.push_back(fine_index(v));
    out.tags.corner_sharpness.push_back(sharpness(s));
  }
  poll_interrupt();

  if (vertices) {
    // R V level by level (Far's PrimvarRefiner): the same weights as R's rows
    // without building them; unreferenced vertices keep their place.
    std::vector<detail::Point3> points;
    detail::gather_points(osd, vertices, points);
    uniform.interpolate(points);
    out.vertices.assign(vertices, vertices + 3 * std::min(n, out.n_vertices));
    out.vertices.resize(3 * out.n_vertices);
    for (std::size_t j = 0; j < n_last; ++j) {
      double* q = out.vertices.data() + 3 * static_cast<std::size_t>(fine_index(static_cast<int>(j)));
      q[0] = points[j].x;
      q[1] = points[j].y;
      q[2] = points[j].z;
    }
  }
  if (!with_refinement) return out;
  poll_interrupt();

  // R from Far's stencils of the last level, factorised down to the control
  // vertices, in double precision.
  using Factory = Far::StencilTableFactoryReal<double>;
  Factory::Options stencil_options;
  stencil_options.generateIntermediateLevels = false;
  stencil_options.factorizeIntermediateLevels = true;
  stencil_options.generateOffsets = true;
  stencil_options.maxLevel = static_cast<unsigned>(levels);
  const std::unique_ptr<const Far::StencilTableReal<double>> stencils(Factory::Create(refiner, stencil_options));
  poll_interrupt();
  if (!stencils || static_cast<std::size_t>(stencils->GetNumStencils()) != n_last)
    throw std::logic_error("Far's stencil table does not have one stencil per refined vertex");
  CsrMatrix& r = out.refinement;
  r.n_rows = out.n_vertices;
  r.n_cols = n;
  // Rows by fine index: the first n rows are the coarse vertices' children
  // (or, unreferenced, themselves), then Far's new vertices.
  std::vector<std::int32_t> slot(n, -1);  // coarse vertex -> Far's vertex j of the last level, or -1
  for (std::size_t j = 0; j < n_osd; ++j)
    slot[static_cast<std::size_t>(osd.from_osd[j])] = static_cast<std::int32_t>(j);
  r.indptr.reserve(r.n_rows + 1);
  r.indptr.push_back(0);
  const auto& sizes = stencils->GetSizes();
  const auto& offsets = stencils->GetOffsets();
  const auto& indices = stencils->GetControlIndices();
  const auto& weights = stencils->GetWeights();
  std::vector<std::pair<std::int32_t, double>> row;
  const auto append_stencil = [&](std::size_t j) {
    row.clear();
    for (int p = offsets[j]; p < offsets[j] + sizes[j]; ++p)
      if (weights[p] != 0.0) row.emplace_back(osd.from_osd[indices[p]], weights[p]);
    std::sort(row.begin(), row.end());
    for (std::size_t p = 0; p < row.size(); ++p) {
      if (p > 0 && row[p].first == row[p - 1].first) {  // Far may list a vertex twice: add up
        r.data.back() += row[p].second;
        continue;
      }
      r.indices.push_back(row[p].first);
      r.data.push_back(row[p].second);
    }
    r.indptr.push_back(static_cast<std::int32_t>(r.indices.size()));
  };
  for (std::size_t v = 0; v < n; ++v) {
    if (slot[v] < 0) {
      r.indices.push_back(static_cast<std::int32_t>(v));
      r.data.push_back(1.0);
      r.indptr.push_back(static_cast<std::int32_t>(r.indices.size()));
    } else {
      append_stencil(static_cast<std::size_t>(slot[v]));
    }
  }
  for (std::size_t j = n_osd; j < n_last; ++j) append_stencil(j);
  return out;
}

}  // namespace sorpia
