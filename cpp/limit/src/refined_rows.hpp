#pragma once
// Rows of the limit matrix B computed by OpenSubdiv's own refinement and
// Limit(), vertex by vertex, on a local mesh (internal).
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::detail {

// The sharpness tags as OpenSubdiv applies them: a crease or a corner given
// twice counts with its last sharpness (Far::TopologyDescriptor assigns them
// in order), a zero sharpness is no tag, sharpness is float (Far's type), at
// most Sdc::Crease::SHARPNESS_INFINITE.
struct VertexTags {
  // Per tagged vertex: its crease edges (the other end, sharpness > 0).
  std::vector<std::int32_t> crease_offsets;  // n_vertices + 1
  std::vector<std::int32_t> crease_other;
  std::vector<float> crease_sharpness;
  std::vector<float> corner;       // n_vertices: vertex sharpness (0: none)
  std::vector<std::uint8_t> hole;  // n_faces

  // The number of refinement levels after which every semi-sharp tag at v
  // has decayed: ceil of the largest finite sharpness among v's creases and
  // its corner (0 when none).
  int levels(std::int32_t v) const;
  bool infinite(float s) const { return s >= kInfiniteSharpness; }
  // The number of v's creases that are infinitely sharp.
  int infinite_creases(std::int32_t v) const;
  // Whether v is a dart once its semi-sharp tags have decayed: an interior
  // vertex with exactly one infinitely sharp edge and no infinitely sharp
  // corner. Sdc gives a dart the smooth limit mask, which is not the limit of
  // its refinement (the sharp edge's children are midpoints, not smooth edge
  // points), so Far's Limit() of a dart depends on the level it is taken at
  // and converges as the level grows: refined_limit_rows takes its limit.
  bool dart(const Topology& topology, std::int32_t v) const {
    return !topology.is_boundary(v) && !infinite(corner[v]) && infinite_creases(v) == 1;
  }
  // Whether Far's Limit() of v after L levels changes with L (so that no
  // finite level gives v's limit and refined_limit_rows takes the limit as L
  // grows): a dart, and under Catmull-Clark an interior vertex of two faces
  // that is smooth once its semi-sharp tags have decayed, to which Sdc gives
  // the corner mask (Far's Limit() after L levels is v's point at level L,
  // which moves as L grows). Every other vertex's mask, once its semi-sharp
  // tags have decayed (and, under Catmull-Clark, its faces are quads), is the
  // dominant left eigenvector of its own subdivision matrix: the same at
  // every level. (Under Loop, Sdc's smooth mask at an interior vertex of two
  // triangles is its subdivision matrix's eigenvector too: Loop has no
  // corner-mask exception.)
  bool level_dependent(const Topology& topology, Scheme scheme, std::int32_t v) const {
    if (dart(topology, v)) return true;
    return scheme == Scheme::CatmullClark && !topology.is_boundary(v) && topology.valence(v) == 2 &&
           !infinite(corner[v]) && infinite_creases(v) == 0;
  }
};

// The level each row of B is taken at (B is OpenSubdiv's Limit() after
// L = the largest of these levels, except at the vertices whose Limit()
// changes with the level, VertexTags::level_dependent): for each vertex
// tags.levels(v), at least 1 under Catmull-Clark next to a face that is not a
// quad (Sdc's limit masks assume quads); 0 for an unreferenced vertex. Every
// other row is the same at any deeper level (tests: every row against the
// whole mesh refined to L). A level-dependent vertex's level is where
// refined_limit_rows starts its limit from.
std::vector<int> row_levels(const Topology& topology, Scheme scheme, const VertexTags& tags);

// Groups `tags` by vertex. Every crease must be an edge of `topology`, and a
// face must be left that is not a hole (check_surface_left).
// @throw MeshError naming the first crease that is not an edge, or for holes only
VertexTags vertex_tags(const Topology& topology, const Tags& tags);

// Rows of B (limit positions of the control vertices) for `vertices`, from
// OpenSubdiv itself: for each vertex v = vertices[k], a Far::TopologyRefiner
// on the faces incident to v with v's tags (its creases, its corner, the holes
// among those faces), refined uniformly one level at a time, the weights
// carried by PrimvarRefinerReal<double>::Interpolate, for levels[k] levels
// (at least tags.levels(v), where v's semi-sharp tags have decayed), then
// Limit() on the last level. After each level the local mesh is
// replaced by the faces incident to v's child, with their decayed sharpness.
// A vertex whose Limit() changes with the level (VertexTags::level_dependent:
// darts, Catmull-Clark's smooth interior vertices of two faces) instead gets
// the limit as the level grows: after max(levels[k], 1) levels one more level
// maps the local mesh's vertices to the same configuration one level down
// (the local subdivision matrix S, the same at every later level), and the
// row is S's dominant left eigenvector (eigenvalue 1, weights summing to 1)
// composed back; Far's Limit() after L levels tends to it as rho^L, rho the
// largest modulus of S's other eigenvalues (darts: about 1/3 at valence 6 and
// 0.6 at 12; two faces of quads: 1/4).
//
// Exact because of locality (Sdc's CREASE_UNIFORM rules): v's child depends
// on v's faces only, and its one-ring on the children of those faces, so v's
// limit depends only on v's faces, v's corner sharpness and its edges'
// sharpness; the edges and vertices of the local mesh that are not incident
// to v only turn into boundaries whose rules reach none of v's descendants.
// Tests compare every row with a refinement of the whole mesh.
//
// Returns a CSR matrix with one row per entry of `vertices` (in that order),
// n_vertices columns, the diagonal included, columns sorted, exact zeros
// dropped. An unreferenced vertex gets its identity row.
// Appends the entries of a row (columns `cols`, weights `w`) to `b`, sorted,
// exact zeros dropped (OpenSubdiv's masks list interior neighbours of crease
// vertices with weight 0).
void append_row(CsrMatrix& b, const std::vector<std::int32_t>& cols, const std::vector<double>& w);

CsrMatrix refined_limit_rows(const Topology& topology, Scheme scheme, Boundary boundary, const VertexTags& tags,
                             const std::vector<std::int32_t>& vertices, const std::vector<int>& levels);

}  // namespace sorpia::detail
