#pragma once
/// @file subdivision.hpp
/// The subdivision rules a limit surface is defined by, as OpenSubdiv names
/// them: the scheme (Sdc::SchemeType), the boundary interpolation
/// (Sdc::Options::VtxBoundaryInterpolation) and the sharpness tags of the
/// topology (Far::TopologyDescriptor's creases, corners and holes).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sorpia {

/// The subdivision scheme (Sdc::SchemeType).
enum class Scheme {
  Loop,          ///< SCHEME_LOOP: triangles only
  CatmullClark,  ///< SCHEME_CATMARK: any polygons
};

/// "loop", "catmull-clark". @throw ParameterError on another name
Scheme parse_scheme(const std::string& name);
const char* scheme_name(Scheme scheme);

/// How the limit surface treats the mesh boundary (OpenSubdiv's
/// Sdc::Options::VtxBoundaryInterpolation).
enum class Boundary {
  EdgeOnly,       ///< VTX_BOUNDARY_EDGE_ONLY: boundary curves are smooth, a one-face corner gets (1/6, 2/3, 1/6)
  EdgeAndCorner,  ///< VTX_BOUNDARY_EDGE_AND_CORNER: as EdgeOnly, but one-face corners are kept (weight 1)
};

/// "edge-only", "edge-and-corner". @throw ParameterError on another name
Boundary parse_boundary(const std::string& name);
const char* boundary_name(Boundary boundary);

/// Sharpness at or above this is infinitely sharp (Sdc::Crease::SHARPNESS_INFINITE).
constexpr double kInfiniteSharpness = 10.0;

/// OpenSubdiv's sharpness tags: creases (edges), corners (vertices) and holes
/// (faces), as Far::TopologyDescriptor takes them. Sharpness is a
/// non-negative number; kInfiniteSharpness and above (and +inf) is infinitely
/// sharp, 0 is smooth, anything between is semi-sharp (it decays by one per
/// subdivision level).
struct Tags {
  std::vector<std::int32_t> crease_vertices;  ///< (k, 2) row-major: the two ends of each crease edge
  std::vector<double> crease_sharpness;       ///< (k,)
  std::vector<std::int32_t> corner_vertices;  ///< (c,)
  std::vector<double> corner_sharpness;       ///< (c,)
  std::vector<std::int32_t> holes;            ///< face indices

  std::size_t n_creases() const { return crease_sharpness.size(); }
  std::size_t n_corners() const { return corner_sharpness.size(); }
  /// No tag at all (zero sharpness entries count as tags until dropped).
  bool empty() const { return crease_sharpness.empty() && corner_sharpness.empty() && holes.empty(); }
  /// The largest finite sharpness below kInfiniteSharpness (0 when none):
  /// the number of levels after which every semi-sharp feature has decayed
  /// is its ceiling.
  double max_semi_sharpness() const;
};

/// The rules a limit surface is defined by: the scheme, the boundary
/// interpolation and the sharpness tags. What every function that builds B,
/// its rows or the surface takes, as one value.
struct Rules {
  Scheme scheme = Scheme::Loop;
  Boundary boundary = Boundary::EdgeAndCorner;
  Tags tags;
};

/// Checks what can be checked without the topology: array sizes, vertex and
/// face indices in range, a crease's two ends distinct, sharpness not NaN and
/// not negative. Messages name the tag ("creases[3] = [4, 4]: ...").
/// Whether a crease is an edge of the mesh is checked against the topology.
/// @throw MeshError
void check_tags(const Tags& tags, std::size_t n_vertices, std::size_t n_faces);

}  // namespace sorpia
