#pragma once
/// @file surface.hpp
/// The Loop limit surface of a control mesh (OpenSubdiv): evaluation at any
/// (face, u, v) through Bfr, and uniform tessellation with every output vertex
/// at its exact limit position.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "sorpia/memory.hpp"  // available_memory_bytes, which tessellate checks
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// Bytes a uniform tessellation to `level` needs at its peak (OpenSubdiv's
/// refined topology of every level, the refined positions, the output
/// arrays), estimated from the counts: each level multiplies faces by 4 and
/// vertices by about 4.
/// @param n_vertices  control vertices
/// @param n_faces     control triangles
/// @param level       refinement level, 0..15
std::size_t tessellation_bytes(std::size_t n_vertices, std::size_t n_faces, int level);

/// The Loop limit surface of one mesh topology: build once, query many.
///
/// Holds the topology and the OpenSubdiv structures (a Far::TopologyRefiner
/// for the Bfr surface factory, and the uniformly refined refiner of the last
/// tessellation level asked for); set_vertices() changes the control vertices
/// without rebuilding them, as the PIA loop changes positions, never topology.
///
/// Threads: evaluate() and get_vertices() may run concurrently (one shared
/// Bfr factory with a thread-safe cache, the core's thread pool inside
/// evaluate(): at most one thread per 64 distinct faces queried); set_vertices() and tessellate() take
/// exclusive access.
///
/// Parameterisation of face f = (a, b, c) (Bfr's triangle parameterisation):
/// (u, v) = (0, 0) is vertex a, (1, 0) is b, (0, 1) is c; points with u >= 0,
/// v >= 0, u + v <= 1 lie on the face's limit patch.
class LoopSurface {
 public:
  /// @param topology  mesh connectivity (copied)
  /// @param vertices  row-major (n_vertices, 3) control vertices (copied)
  /// @param boundary  boundary interpolation rule
  /// @throws MeshError when OpenSubdiv refuses the topology
  LoopSurface(const Topology& topology, const double* vertices, Boundary boundary);
  ~LoopSurface();
  LoopSurface(LoopSurface&&) noexcept;
  LoopSurface& operator=(LoopSurface&&) noexcept;
  LoopSurface(const LoopSurface&) = delete;
  LoopSurface& operator=(const LoopSurface&) = delete;

  std::size_t n_vertices() const;
  std::size_t n_faces() const;
  Boundary boundary() const;

  /// Replace the control vertices (same topology).
  /// @param vertices  row-major (n_vertices, 3)
  void set_vertices(const double* vertices);
  /// Row-major (n_vertices, 3) control vertices, copied into `out`.
  void get_vertices(double* out) const;

  /// Limit positions (and optionally first derivatives and unit normals) at k
  /// points (face_ids[i], uv[2i], uv[2i+1]), evaluated by Bfr::Surface<double>.
  /// Exact at face corners (the limit position B V of the corner vertex) under
  /// both boundary rules, and wherever the patch is regular (box spline).
  /// Within the corner triangle of side 1/16 at an extraordinary vertex Bfr
  /// uses a Gregory triangle: positions approximate the limit surface there
  /// and OpenSubdiv's derivatives approximate the positions' derivatives
  /// (normals within a few hundredths of a radian of finite differences;
  /// tests/test_surface.py holds them to 0.05 rad).
  /// @param face_ids  k face indices, each in [0, n_faces)
  /// @param uv        row-major (k, 2) parameters, u >= 0, v >= 0, u + v <= 1
  /// @param k         number of points
  /// @param positions row-major (k, 3), written
  /// @param du, dv    row-major (k, 3) dP/du and dP/dv, written unless null
  /// @param normals   row-major (k, 3) (dP/du x dP/dv) / |dP/du x dP/dv|, zero
  ///                  where the cross product vanishes; written unless null
  /// @throws ParameterError for a face index or (u, v) out of range
  void evaluate(const std::int32_t* face_ids, const double* uv, std::size_t k, double* positions, double* du,
                double* dv, double* normals) const;

  /// Uniform refinement to `level` (4^level triangles per control triangle)
  /// with every vertex moved to its limit position
  /// (Far::PrimvarRefinerReal<double>: Interpolate level by level, then Limit).
  ///
  /// Vertex i < n_vertices() descends from control vertex i and sits at its
  /// limit position B V (unreferenced control vertices stay where they are);
  /// the triangles of control face f are rows [f 4^level, (f+1) 4^level) of
  /// the output faces, with f's orientation.
  /// @param level  0..15
  /// @throws ParameterError when the level is out of range or the estimated
  ///         memory (tessellation_bytes) exceeds the memory available
  TriMesh tessellate(int level);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sorpia
