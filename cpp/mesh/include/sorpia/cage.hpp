#pragma once
/// @file cage.hpp
/// A light control mesh (a cage) made from a dense triangle mesh: OpenMesh's
/// Decimater down to a given number of vertices, and for Catmull-Clark the
/// decimated triangles paired into quads.

#include <cstddef>
#include <string>

#include "sorpia/mesh.hpp"
#include "sorpia/subdivision.hpp"

namespace sorpia {

/// The guards of decimate(): a collapse that breaks one is never made.
struct DecimateOptions {
  /// The cage's scheme: Loop gives the decimated triangles, Catmull-Clark
  /// the same triangles paired into quads across their edges.
  Scheme scheme = Scheme::Loop;
  /// OpenMesh's ModNormalFlippingT: no face's normal may turn by more than
  /// this in one collapse (degrees, in (0, 180]).
  double max_normal_deviation = 60.0;
  /// OpenMesh's ModAspectRatioT: a collapse may not leave a face with a
  /// longer edge-to-height ratio than this, unless it improves the worst
  /// face around it (at least 1).
  double max_aspect_ratio = 10.0;
  /// A boundary vertex is removed only where the boundary turns by at most
  /// this angle (degrees, in [0, 180]) between its two boundary edges, so that
  /// corners and the outline of an open mesh stay; 0 removes boundary
  /// vertices only where the boundary runs straight, 180 lets the quadric
  /// alone decide.
  double max_boundary_angle = 30.0;
};

/// The mesh decimated on OpenMesh's Decimater framework (BaseDecimaterT) with
/// the quadric error module (ModQuadricT, Garland and Heckbert's quadrics of
/// the faces' planes; a collapse moves a vertex onto its neighbour, so the
/// cage's vertices are input vertices), guarded by ModNormalFlippingT,
/// ModAspectRatioT and the boundary angle of `options`. Collapses are made
/// cheapest first, their costs kept up to date as DecimaterT keeps them;
/// OpenMesh's legality test and the guards judge the cheapest candidate when
/// it comes up (a refused one makes way for the next), not every candidate of
/// every vertex whose one-ring changed as DecimaterT does. A mesh of 200,000
/// vertices or more and over 8 times `n_vertices` is first clustered on a
/// grid to about 4 times `n_vertices` (Lindstrom's vertex clustering: each
/// cluster its vertex of least summed quadric, boundary vertices and their
/// neighbours kept, the clustered mesh kept manifold), and decimated from
/// there with the clusters' quadrics.
///
/// Loop: a triangle mesh of exactly `n_vertices` vertices. Catmull-Clark: the
/// same triangles (the same decimation, the same vertices) paired into quads
/// across their edges, greedily by a quad's quality (its worst corner's
/// departure from a right angle and the fold between its two triangles; no
/// reflex corner, no vertex left with two edges), then along augmenting
/// paths that pair two left-over triangles more; those that find no partner stay
/// triangles (face_vertex_counts of 4 and 3; Catmull-Clark takes them as
/// n-gons). Each quad (a, d, b, c) is the triangles (a, b, c) and (b, a, d).
///
/// Vertices no face references are left out (they count neither towards the
/// mesh's vertices nor towards `n_vertices`). The result's vertices are input
/// vertices, in the order OpenMesh's garbage collection leaves them.
/// @param mesh       triangles (all_triangles() or every count 3), manifold and consistently oriented
/// @param n_vertices the cage's vertices, at least 4 and at most the mesh's referenced vertices
/// @throw MeshError  a face that is not a triangle, an index out of range, a
///                   face OpenMesh's half-edge mesh cannot take (named), a
///                   mesh with fewer referenced vertices than `n_vertices`,
///                   or, without `stopped`, a decimation the guards stop
///                   before `n_vertices` (saying how far it got)
/// @param stopped    when given: a decimation the guards stop before
///                   `n_vertices` returns the mesh it reached (more vertices
///                   than asked) and says so here, in the words of that
///                   MeshError; cleared when the count is reached
/// @throw ParameterError n_vertices < 4 or an option out of range
Mesh decimate(const Mesh& mesh, std::size_t n_vertices, const DecimateOptions& options = {},
              std::string* stopped = nullptr);

/// Each triangle split into three quads by joining its centroid to its edge
/// midpoints: corner k of triangle (a, b, c) gives the quad
/// (t[k], mid(t[k], t[k+1]), centroid, mid(t[k-1], t[k])), counter-clockwise
/// as the triangle. The triangles' vertices keep their numbers; the edge
/// midpoints (one per edge, shared by its faces) and the centroids follow,
/// numbered in the order the faces reach them. A midpoint has valence 4 inside
/// (3 on the boundary), a centroid valence 3.
/// @param triangles a triangle mesh (all_triangles())
Mesh quads_from_triangles(const Mesh& triangles);

}  // namespace sorpia
