#pragma once
/// @file surface.hpp
/// The limit surface of a control mesh under Loop or Catmull-Clark
/// subdivision, with OpenSubdiv's sharpness tags (OpenSubdiv Bfr and Far):
/// evaluation at any (face, u, v), and uniform tessellation with every output
/// vertex at its exact limit position.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "sorpia/detail/scratch.hpp"
#include "sorpia/limit.hpp"   // CsrMatrix
#include "sorpia/memory.hpp"  // available_memory_bytes, which tessellate checks
#include "sorpia/mesh.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// Bytes a uniform tessellation to `level` needs at its peak (OpenSubdiv's
/// refined topology of every level, the refined positions, the output
/// arrays), estimated from the counts.
/// @param scheme          Loop (each level splits a triangle into 4) or
///                        Catmull-Clark (the first level splits a k-gon into
///                        k quads, each later level a quad into 4)
/// @param n_vertices      control vertices
/// @param n_faces         control faces
/// @param n_face_vertices the faces' vertex counts summed (their corners);
///                        0 when every face has the scheme's regular size
///                        (3 for Loop, 4 for Catmull-Clark)
/// @param level           refinement level, 0..15
std::size_t tessellation_bytes(Scheme scheme, std::size_t n_vertices, std::size_t n_faces,
                               std::size_t n_face_vertices, int level);

/// Rows of the limit surface at k points: each a (k, n_vertices) sparse
/// matrix over the control vertices, so that position * V is the limit
/// position at the points and du * V, dv * V, duu * V, duv * V, dvv * V its
/// derivatives in the faces' parameters (LimitSurface::rows). Matrices not
/// asked for are empty (0 rows).
struct SurfaceRows {
  CsrMatrix position, du, dv, duu, duv, dvv;
};

/// One block of the position rows of points (LimitSurface::position_blocks):
/// `count` points sharing `width` columns (sorted, distinct), their rows
/// dense, (count, width) row-major.
struct PositionBlock {
  std::size_t index = 0;                  ///< the block's number, 0 .. blocks - 1
  const std::int32_t* columns = nullptr;  ///< width control vertices
  std::size_t width = 0;
  const std::size_t* points = nullptr;    ///< the points' indices among the k, increasing
  std::size_t count = 0;
  const double* rows = nullptr;           ///< (count, width): point points[j]'s weight of columns[c] at [j * width + c]
};

/// The control points of k faces (LimitSurface::control_points): face i's
/// are indices[offsets[i] .. offsets[i + 1]).
struct FaceControlPoints {
  std::vector<std::int64_t> offsets;
  std::vector<std::int32_t> indices;
  std::vector<std::uint8_t> regular;  // Bfr's Surface::IsRegular() per face
};

/// The limit surface of one mesh topology under one subdivision scheme,
/// boundary rule and set of sharpness tags: build once, query many.
///
/// Holds the topology and the OpenSubdiv structures (a Far::TopologyRefiner
/// carrying the tags, the Bfr surface factory built on it, and the uniformly
/// refined refiner of the last tessellation level asked for); set_vertices()
/// changes the control vertices without rebuilding them, as the PIA loop
/// changes positions, never topology.
///
/// Each face's Bfr::Surface is built on the face's first use and kept; its
/// patch points (Bfr::Surface::PreparePatchPoints, the control vertices
/// combined into the points Bfr evaluates the face from) are prepared on the
/// face's first evaluation after each set_vertices() and kept until the
/// next, so that evaluate(), visit_faces() and tessellate() prepare a face
/// once per state of the control vertices however often they evaluate it;
/// rows() and control_points() use the kept surfaces (their stencils need no
/// patch points). Results are those of a fresh Bfr::Surface at the current
/// vertices, bit for bit. Memory: a few hundred bytes per face, more at
/// irregular faces (bench/footpoints_speed.py measures it).
///
/// Threads: evaluate() and get_vertices() may run concurrently (one shared
/// Bfr factory with a thread-safe cache, a face's surface and patch points
/// built by the first thread that needs them under a lock per face, the
/// core's thread pool inside evaluate(): at most one thread per 64 distinct
/// faces queried); set_vertices() and tessellate() take exclusive access.
/// Long calls poll sorpia::poll_interrupt().
///
/// Parameterisation of a face (Bfr::Parameterization, chosen by the scheme
/// and the face's size k):
/// - a triangle (a, b, c) under Loop: (u, v) = (0, 0) is a, (1, 0) is b,
///   (0, 1) is c; the face is u >= 0, v >= 0, u + v <= 1;
/// - a quad (a, b, c, d) under Catmull-Clark: the unit square, (0, 0) is a,
///   (1, 0) is b, (1, 1) is c, (0, 1) is d;
/// - any other k-gon under Catmull-Clark (a triangle included): its limit
///   surface is made of k quad sub-faces, one at each corner (the quads of its
///   first subdivision). Sub-face j is the square [x_j, x_j + 1/2] x [y_j,
///   y_j + 1/2] with (x_j, y_j) = (j mod w, j div w), w = 2 for k < 5, 3 for
///   k = 5..9, 1 + floor(sqrt(k - 1)) from k = 10: (x_j, y_j) is corner j,
///   (x_j + 1/2, y_j) the midpoint of edge j (corner j to j + 1),
///   (x_j, y_j + 1/2) the midpoint of edge j - 1, and (x_j + 1/2, y_j + 1/2)
///   the face's centre (the same point in every sub-face).
class LimitSurface {
 public:
  /// @param topology  mesh connectivity (copied)
  /// @param vertices  row-major (n_vertices, 3) control vertices (copied)
  /// @param scheme    subdivision scheme
  /// @param boundary  boundary interpolation rule
  /// @param tags      creases, corners and holes (checked by check_tags)
  /// @throws MeshError when OpenSubdiv refuses the topology or a tag
  LimitSurface(const Topology& topology, const double* vertices, Scheme scheme, Boundary boundary,
               const Tags& tags = Tags{});
  ~LimitSurface();
  LimitSurface(LimitSurface&&) noexcept;
  LimitSurface& operator=(LimitSurface&&) noexcept;
  LimitSurface(const LimitSurface&) = delete;
  LimitSurface& operator=(const LimitSurface&) = delete;

  std::size_t n_vertices() const;
  std::size_t n_faces() const;
  Scheme scheme() const;
  Boundary boundary() const;
  const Tags& tags() const;
  /// The mesh connectivity the surface was built on.
  const Topology& topology() const;

  /// Replace the control vertices (same topology).
  /// @param vertices  row-major (n_vertices, 3)
  void set_vertices(const double* vertices);
  /// Row-major (n_vertices, 3) control vertices, copied into `out`.
  void get_vertices(double* out) const;

  /// Limit positions (and optionally first derivatives and unit normals) at k
  /// points (face_ids[i], uv[2i], uv[2i+1]), evaluated by Bfr::Surface<double>
  /// in the face's parameterisation (see the class comment).
  /// Exact at face corners (the limit position B V of the corner vertex) under
  /// both boundary rules, and wherever the patch is regular (box spline). At
  /// a dart's corner and at an interior vertex of two faces (Catmull-Clark)
  /// the point is B V's (the limit of refinement; Bfr's own corner at a dart
  /// is Far's Limit() after its local refinements, 10 on a mesh with darts,
  /// which the points next to that corner start from: docs/surfaces.md).
  /// With OpenSubdiv before 3.6.1 a face at a dart of two faces is refused
  /// (MeshError): Bfr writes out of bounds building its surface (OpenSubdiv's
  /// pull request 1336); and a face with a corner at an interior vertex of
  /// two faces is built by a Bfr factory without a cache, alone, since Bfr
  /// before 3.6.1 shares such a face's patch with faces of the same topology
  /// whose vertices repeat differently, wrongly for them (its pull request
  /// 1353). Every other face shares its patch through the cache.
  /// Within the corner region of side 1/16 at an extraordinary vertex Bfr
  /// uses a Gregory patch: positions approximate the limit surface there
  /// and OpenSubdiv's derivatives approximate the positions' derivatives
  /// (normals within a few hundredths of a radian of finite differences;
  /// tests/test_surface.py holds them to 0.05 rad). Semi-sharp features are
  /// resolved by Bfr's local refinement up to level 10, as deep as
  /// OpenSubdiv refines (sharpness 10 is infinite).
  /// @param face_ids  k face indices, each in [0, n_faces) and not a hole
  /// @param uv        row-major (k, 2) parameters in the face's domain
  /// @param k         number of points
  /// @param positions row-major (k, 3), written
  /// @param du, dv    row-major (k, 3) dP/du and dP/dv, written unless null
  /// @param normals   row-major (k, 3) (dP/du x dP/dv) / |dP/du x dP/dv|, zero
  ///                  where the cross product vanishes; written unless null
  /// @throws ParameterError for a face index, a hole or (u, v) out of range
  void evaluate(const std::int32_t* face_ids, const double* uv, std::size_t k, double* positions, double* du,
                double* dv, double* normals) const;

  /// Rows of the limit surface at k points (face_ids[i], uv[2i], uv[2i+1]),
  /// checked as evaluate() checks them: the weights of the control vertices
  /// in the point and its derivatives, from Bfr's stencils
  /// (Bfr::Surface::EvaluateStencil over the face's control points), so that
  /// rows.position * V equals evaluate()'s positions at the current vertices
  /// V to rounding, and likewise du, dv; at a dart's corner and at an
  /// interior vertex of two faces (Catmull-Clark) the position row is the
  /// vertex's row of B, as in evaluate(). Row i holds the control points of
  /// face_ids[i]'s surface (its one-ring neighbourhood, and more near
  /// semi-sharp features), columns sorted and distinct. The rows do not
  /// depend on the vertices: they are what fitting (fair interpolation,
  /// approximation) composes into its linear systems. OpenSubdiv's second
  /// derivatives on the rotated middle sub-patches of irregular Loop faces
  /// have the wrong sign (through 3.6.0); rows() corrects them.
  /// @param derivatives  0: position; 1: also du, dv; 2: also duu, duv, dvv
  /// @throws ParameterError as evaluate(), or for derivatives outside 0..2
  SurfaceRows rows(const std::int32_t* face_ids, const double* uv, std::size_t k, int derivatives = 0) const;
  /// rows(face_ids, uv, k, 0).position's rows, the same values, a block of
  /// points at a time, for a caller that uses them where they are made (the
  /// normal equations of approximation) instead of storing them all: the
  /// points of one face share its control points, so a face's points are
  /// one block, in the faces' increasing order; a point whose row is B's
  /// (at a dart's corner, see rows()) is a block of its own, after the
  /// faces' in the points' order. start(offsets, columns) is called first
  /// with every block's columns (block b's are columns[offsets[b] ..
  /// offsets[b + 1]), sorted and distinct; none for a face whose points all
  /// have B's rows), then visit(block) once per block, on the core's
  /// threads (concurrently for different blocks; the block's arrays are the
  /// thread's until visit returns; a face whose points all have B's rows is
  /// a block of 0 points). visit must not start tasks of the core's pool
  /// (detail::run_tasks is not reentrant). The points' checked parameters
  /// are taken from `scratch` (in a frame of its own).
  /// @throws ParameterError as evaluate()
  void position_blocks(
      const std::int32_t* face_ids, const double* uv, std::size_t k, detail::Scratch& scratch,
      const std::function<void(std::vector<std::int64_t>&& offsets, std::vector<std::int32_t>&& columns)>& start,
      const std::function<void(const PositionBlock&)>& visit) const;

  /// The control points of faces' surfaces in Bfr's order
  /// (Bfr::Surface::GetControlPointIndices, as mesh vertex indices; a vertex
  /// may appear more than once where a face meets itself), with Bfr's
  /// Surface::IsRegular(): what lets a caller reuse a quantity computed over
  /// one face's control points for another face of the same local topology.
  /// @param face_ids  k face indices, each in [0, n_faces) and not a hole
  /// @throws ParameterError for a face index out of range or a hole
  FaceControlPoints control_points(const std::int32_t* face_ids, std::size_t k) const;

  /// Uniform refinement to `level` with every vertex moved to its limit
  /// position (Far::PrimvarRefinerReal<double>: Interpolate level by level,
  /// then Limit on the last level; with semi-sharp tags the refinement goes
  /// on until every sharpness has decayed, and the last level's descendants
  /// of the level's vertices give their limit positions).
  ///
  /// Loop: 4^level triangles per control triangle. Catmull-Clark: level 0 is
  /// the control polygons; from level 1 a k-gon gives k 4^(level-1) quads.
  /// Vertex i < n_vertices() descends from control vertex i and sits at its
  /// limit position B V (unreferenced control vertices stay where they are);
  /// the vertices of level l are the first vertices of every level after it,
  /// in the same order. The faces refined from control face f come in one
  /// block of rows, after those of the faces before it, with f's
  /// orientation; faces of holes are left out.
  /// @param level  0..15
  /// @throws ParameterError when the level is out of range or the estimated
  ///         memory (tessellation_bytes) exceeds the memory available
  Mesh tessellate(int level);

  /// Evaluation of one face's surface at any parameter in its domain, with
  /// both first derivatives: (uv[2], position[3], du[3], dv[3]). Bfr's own
  /// evaluation (no exact corner from B, see evaluate()).
  using FaceEvaluation = std::function<void(const double*, double*, double*, double*)>;
  /// Visits the distinct faces of k entries face_ids[0..k), each on one of
  /// the core's threads with its surface built and its patch points prepared
  /// (once per state of the control vertices, see the class comment):
  /// visit(face, first, last, evaluate), where [first, last) are the
  /// indices i of the entries with face_ids[i] == face. For work that
  /// evaluates one face many times (Newton steps on footpoints) without
  /// rebuilding its patch at each step. The calls run concurrently on
  /// different faces; an exception from one is rethrown here.
  /// @throws ParameterError for a face index out of range or a hole;
  ///         MeshError as evaluate()
  void visit_faces(const std::int32_t* face_ids, std::size_t k,
                   const std::function<void(std::int32_t, const std::size_t*, const std::size_t*,
                                            const FaceEvaluation&)>& visit) const;

 private:
  // The parameters of k points after evaluate()'s checks (pulled onto the
  // domain where a rounding error outside), written to params (2k).
  void checked_params(const std::int32_t* face_ids, const double* uv, std::size_t k, double* params) const;
  // evaluate()'s checks of the faces alone (checked_params makes them too).
  void check_faces(const std::int32_t* face_ids, std::size_t k) const;
  // Where make_rows writes matrix d: the row offsets (handed to `store`) and room for their entries.
  struct RowsTarget {
    const std::int32_t* indptr;
    std::int32_t* indices;
    double* data;
  };
  using RowsStore = std::function<RowsTarget(int d, std::vector<std::int32_t>&& indptr)>;
  // rows()' matrices, each stored where store(d, its row offsets) says; the transient arrays taken from
  // `scratch`, in the frame open on it (store may take from it too).
  void make_rows(const std::int32_t* face_ids, const double* uv, std::size_t k, int derivatives,
                 detail::Scratch& scratch, const RowsStore& store) const;
  // For each point at the corner of a vertex whose position comes from B
  // (Impl::exact), its row in the exact rows, else -1; empty when none.
  std::vector<std::int32_t> exact_corners(const std::int32_t* face_ids, const double* params, std::size_t k) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sorpia
