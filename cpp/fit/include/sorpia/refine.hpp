#pragma once
/// @file refine.hpp
/// Uniform refinement of a control mesh by OpenSubdiv's Far: the finer
/// control mesh (faces and sharpness tags as Far's refinement carries them)
/// and the refinement matrix R that maps the coarse control vertices to the
/// fine ones, so that the limit surface of R V on the fine mesh is the limit
/// surface of V on the coarse mesh.

#include <cstddef>
#include <cstdint>

#include "sorpia/limit.hpp"
#include "sorpia/mesh.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// A control mesh refined `levels` times.
struct RefinedMesh {
  /// The faces of the finest level (no vertices), every face of
  /// Far::TopologyLevel L in its order, holes included (they are in
  /// `tags.holes`). Loop: triangles (face_size 3, no counts); Catmull-Clark:
  /// quads (face_size 4, no counts).
  Mesh mesh;
  /// Vertex i < n (the coarse count) is the child of coarse vertex i (its
  /// descendant through every level); the vertices Far adds follow in Far's
  /// order. An unreferenced coarse vertex stays unreferenced.
  std::size_t n_vertices = 0;
  /// The tags of the finest level: edge and vertex sharpness as Far's
  /// refinement decayed them (TopologyLevel::GetEdgeSharpness,
  /// GetVertexSharpness; infinitely sharp stays kInfiniteSharpness), boundary
  /// edges and one-face corners under edge-and-corner left out (the rules
  /// make them sharp anyway), and the faces whose coarse ancestor is a hole.
  Tags tags;
  /// R, (n_vertices, n) (empty unless asked for): row i the weights of the coarse control vertices in
  /// fine vertex i (Far::StencilTableFactoryReal<double>, factorised over the
  /// levels); an unreferenced vertex's row is 1 on itself.
  CsrMatrix refinement;
  /// (n_vertices, 3) row-major: R V for the coarse vertices V given to
  /// refine_uniform (Far's PrimvarRefiner, level by level), else empty.
  std::vector<double> vertices;
  /// For each fine face, the coarse face it lies in.
  std::vector<std::int32_t> coarse_face;
};

/// Bytes refine_uniform and a fair solve on its result need at their peak,
/// estimated from the counts (the refiner's levels, R, the fine mesh's limit
/// rows, a fairness matrix of the fine mesh and the solver's vectors).
/// Arguments as sorpia::tessellation_bytes.
std::size_t refinement_bytes(Scheme scheme, std::size_t n_vertices, std::size_t n_faces, std::size_t n_face_vertices,
                             int levels);

/// The largest number of levels refine_uniform accepts (R's stencils are
/// factorised by Far, whose StencilTableFactory takes at most 10 levels).
constexpr int kMaxRefinementLevels = 10;

/// Whether refine_uniform takes these levels, without refining: the checks
/// it makes before any work.
/// @throws ParameterError for levels out of range, a fine mesh beyond int32
///         indices, or more memory than available (refinement_bytes)
void check_refinement(const Topology& topology, const Rules& rules, int levels);

/// The control mesh refined `levels` times uniformly by Far under `rules`.
/// @param topology  coarse connectivity
/// @param rules     scheme, boundary rule, tags (checked as for B)
/// @param levels    1..kMaxRefinementLevels
/// @param vertices  nullptr, or (n, 3) row-major coarse vertices V: then
///                  RefinedMesh::vertices is R V (without R when
///                  with_refinement is false: a start needs R V, not R)
/// @param with_refinement  build R (RefinedMesh::refinement)
/// @throws ParameterError for levels out of range, a fine mesh beyond int32
///         indices, or more memory than available (check_refinement), before
///         any work; MeshError when OpenSubdiv refuses the mesh or a tag
RefinedMesh refine_uniform(const Topology& topology, const Rules& rules, int levels, const double* vertices = nullptr,
                           bool with_refinement = true);

}  // namespace sorpia
