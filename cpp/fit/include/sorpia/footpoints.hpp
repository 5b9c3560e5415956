#pragma once
/// @file footpoints.hpp
/// Closest points of a limit surface to data points (footpoints), as
/// (face, u, v) in OpenSubdiv Bfr's parameterisation (surface.hpp), and a
/// k-d tree for nearest-point queries: the geometric half of approximation
/// (sorpia.approximate).

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "sorpia/detail/scratch.hpp"
#include "sorpia/surface.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// A static k-d tree over points in 3D (copied): nearest-neighbour queries,
/// exact (Euclidean), run on the core's threads.
class PointIndex {
 public:
  /// @param points  row-major (n, 3), finite
  /// @param n       number of points, at least 1
  /// @throws ParameterError when n is 0
  PointIndex(const double* points, std::size_t n);
  std::size_t size() const { return n_; }
  /// For each of k queries the index of its nearest point (the lowest index
  /// among ties is not promised) and the distance to it.
  /// @param queries   row-major (k, 3)
  /// @param index     k entries, written
  /// @param distance  k entries, written (Euclidean, not squared)
  void nearest(const double* queries, std::size_t k, std::int64_t* index, double* distance) const;
  /// The at most `k` points of least rank(index, distance to q) below
  /// `bound`, for one query q (rank called on the calling thread), least
  /// first: their indices and ranks written to index and value (k entries
  /// each). rank(i, d) must be at least d - slack, and at least d minus
  /// point i's slack where set_slack gave them (so that a part of the tree
  /// farther than bound plus its points' largest slack is skipped); +inf
  /// rejects a point.
  /// @return how many were written
  std::size_t least_ranked(const double* q, double bound, double slack, std::size_t k,
                           const std::function<double(std::int64_t, double)>& rank, std::int64_t* index,
                           double* value) const;
  /// Slack of each point (n entries, input order, finite and not negative):
  /// least_ranked then skips a part of the tree by the largest slack of its
  /// points rather than by its `slack` argument.
  void set_slack(const double* slack);
  /// The same points moved (n, row-major, input order): the tree's
  /// partition is kept and its boxes fitted to them (queries stay exact;
  /// they visit more of the tree the farther the points moved across it).
  /// Slack is cleared (set_slack again).
  void refit(const double* points);
  /// Frees the points and their slack, keeping the partition for refit
  /// only: no query before refit.
  void release_points();

 private:
  struct Node {
    float lo[3], hi[3];      // bounding box of the node's points (rounded outward)
    std::uint32_t begin, end;  // range in order_
    std::uint32_t left;        // child index, 0 for a leaf (the right child is left + 1)
  };
  /// Node `node` of `nodes` over order_[begin, end) and its subtree; at
  /// `depth` 0 (counting down; -1: never) an inner node is only listed in
  /// `subtrees` as (node, begin, end), to be built later.
  /// nd's box: [lo, hi] rounded outward to float.
  static void set_box(Node& nd, const double* lo, const double* hi);
  void build(std::vector<Node>& nodes, std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
             std::vector<std::array<std::uint32_t, 3>>* subtrees);
  std::size_t n_ = 0;
  std::vector<double> points_;       // (n, 3) in tree order
  std::vector<std::int64_t> order_;  // tree position -> input index
  std::vector<Node> nodes_;
  std::vector<double> point_slack_;  // per point in tree order, set_slack's; empty without it
  std::vector<float> node_slack_;    // per node, its points' largest slack (rounded up); empty without set_slack
};

/// Footpoints of data points on a limit surface: for point i the face
/// face_ids[i], its parameters (uv[2i], uv[2i+1]), the surface point
/// positions[3i..], the distance |point - surface point| and the normal.
struct Footpoints {
  std::vector<std::int32_t> face_ids;
  std::vector<double> uv;
  std::vector<double> positions;
  std::vector<double> distances;
  /// Unit normals du x dv / |du x dv| at the footpoints (zero where the
  /// tangents are parallel), as LimitSurface::evaluate gives them.
  std::vector<double> normals;
};

/// Options of the footpoint search.
struct FootpointOptions {
  /// Samples per side of each face's domain (each quad sub-face of a
  /// Catmull-Clark k-gon counts as one) whose nearest one starts the search.
  int grid = 4;
  /// Gauss-Newton steps on (u, v) at most, per point.
  int max_steps = 20;
  /// Starts per point at most of FootpointSearch::closer's re-search from
  /// the samples near a closer point (0: none).
  int starts = 8;
  /// FootpointSearch::closer re-searches from those samples only the points
  /// whose distance exceeds `near` times the reach of their nearest grid
  /// sample (0: every point off the surface). A point nearer is refined from
  /// that sample alone (as find); a closer point it misses lies on a fold of
  /// the surface within about that distance, finer than the grid. 0 (the
  /// default) is the exhaustive search, which tests/test_footpoints.py holds
  /// to the brute-force closest points within 1e-9 of the diagonal (about 6
  /// times find's instructions without the certificate below; 0.1 far fewer,
  /// leaving points on folds).
  double near = 0.0;
  /// FootpointSearch::closer leaves out the starts in the faces round a
  /// footpoint where a bound on the surface's curvature there shows that
  /// none of them can hold a closer point (the certificate described at
  /// closer). false: every point takes every start (the exhaustive rule, the
  /// reference the certificate is tested against).
  bool certify = true;
  /// A point's refinement stops where its next Gauss-Newton step is below
  /// this in (u, v) (a face's domain has side 1; in [0, 1)) and the decrease
  /// of the distance it predicts is below 1e-6 of the distance (a point on
  /// the surface goes on), and always below 1e-11. The default leaves a
  /// footpoint at its minimum to about rounding; a looser one leaves it off
  /// by up to about this (ApproximationChunk::refine's iterations), its
  /// distance exact to about 1e-6 relatively.
  double uv_tolerance = 1e-11;
};

/// The closest point of the limit surface to each of n points: start at the
/// nearest of a grid of limit points with known (face, u, v) (a k-d tree over
/// the grid), then refine_footpoints (from the grid sample's position and
/// derivatives, evaluated with the grid).
/// @param surface   the limit surface (its current control vertices)
/// @param topology  the surface's topology (faces and their sizes)
/// @param points    row-major (n, 3), finite
/// @throws ParameterError when the surface has no face outside holes
Footpoints closest_points(const LimitSurface& surface, const Topology& topology, const double* points,
                          std::size_t n, const FootpointOptions& options);

/// closest_points' search start on one state of a surface, built once and
/// queried for any number of point sets (an approximation's chunks): the
/// grid samples (face, u, v), their limit points and first derivatives, and
/// a k-d tree over them. find(points) is closest_points(surface, topology,
/// points, options), bit for bit. The surface and topology are borrowed:
/// they must outlive it and the surface's control vertices must not change
/// while it is used.
class FootpointSearch {
 public:
  /// @param previous  a search on an earlier state of the same surface
  ///                  (its topology, the same grid) or null: its samples'
  ///                  (face, u, v), the faces' regularity and its k-d
  ///                  tree's partition are taken over (its tree refitted:
  ///                  PointIndex::refit), so that only the samples are
  ///                  evaluated again; it is left empty, only to be
  ///                  destroyed. The queries' results are those of a
  ///                  search without it (but for which of equally near
  ///                  samples a query finds).
  /// @throws ParameterError for a grid out of 1..64, or no face outside holes
  FootpointSearch(const LimitSurface& surface, const Topology& topology, const FootpointOptions& options,
                  FootpointSearch* previous = nullptr);
  /// Frees all but what a later search takes over as its `previous`: no
  /// query after it.
  void retire();
  ~FootpointSearch();
  FootpointSearch(const FootpointSearch&) = delete;
  FootpointSearch& operator=(const FootpointSearch&) = delete;
  /// Its transient arrays are taken from `scratch` where given (a caller
  /// that repeats it lends one: detail/scratch.hpp).
  Footpoints find(const double* points, std::size_t n, detail::Scratch* scratch = nullptr) const;

  /// Re-searches footpoints that may be local minima of the distance
  /// (refine_footpoints' results, and find's: its start is the nearest
  /// sample, whose basin need not hold the closest point), so that each
  /// becomes the closest point of the surface; returns how many moved.
  /// Each footpoint off its point is first refined from itself (at least
  /// 400 steps: near a focal point Gauss-Newton converges slowly), and the
  /// rest takes that footpoint and its distance d.
  /// Every point of the surface lies within reach(s) of a grid sample s of
  /// its face (the largest distance from s to its neighbours in the grid),
  /// so a surface point closer to x than its footpoint (distance d) lies
  /// within reach(s) of a sample s with |x - s| - reach(s) < d: those are
  /// the candidate starts. The point's nearest sample (find's start) and up
  /// to options.starts candidates, least |x - s| - reach(s) first (for a
  /// point farther than options.near times its nearest sample's reach),
  /// are refined (refine_footpoints from the sample, at least 100 steps),
  /// the closest result replaces the footpoint where it is closer, and is
  /// then refined from itself as the footpoints were. These refinements take
  /// their derivatives near the corners of irregular faces
  /// (Bfr::Surface::IsRegular() false) from differences of positions (Bfr's
  /// are approximate there, surface.hpp), so that they reach the minimum to
  /// rounding.
  /// Cost: a k-d tree query per point not certified (or certified with a
  /// clearance below 2 d) and a refinement per start. With
  /// near = 0 a point has about 5 to 8 starts (its footpoint's own grid
  /// cell and its neighbours pass the bound too) unless certified; with
  /// near = 0.1 about 1.05 starts on a fit's footpoints.
  ///
  /// Certificate (options.certify): the samples of the faces of the star
  /// of the footpoint's face f (the faces outside holes sharing a vertex
  /// with f) are left out of the starts where no point of the star can be
  /// closer to x than the footpoint p (distance d) other than in p's own
  /// basin, which the refinement of p from itself reaches (p: the footpoint
  /// that refinement returned; a point whose refinement hopped to another
  /// point at no smaller distance is not certified). A point of the surface
  /// closer to x than d lies within 2 d of p. N is the whole star
  /// where the surface does not end in it and the tests below hold for all
  /// of it, else its near part: its faces whose surface comes within 4 d of
  /// p (f's always); the samples s of the other faces have
  /// |x - s| - reach(s) > 3 d, outside the candidates' bound in any case. In
  /// the frame whose axis z is (x - p) / d:
  /// - every normal of N lies within 80 degrees of z, so that N projects
  ///   onto the plane across z without folding, and each face of N is
  ///   joined to f across edges between faces of N (a whole star without
  ///   ends is, round each vertex of f): N is one piece of
  ///   surface without folds (a sheet that comes back near p through a fold
  ///   outside N, out of the cone's sight, is joined to f only through faces
  ///   outside N, unless N winds round z), taken to be one sheet over that
  ///   plane (it does not wind round z);
  /// - with kappa a bound of N's normal curvature, p's normal lies within
  ///   45 degrees minus sqrt(2) d kappa of z, and N's edges lie farther than
  ///   4 d from p: those it shares with the star's other faces (by N's
  ///   definition), with the rim (the faces outside the star sharing a
  ///   vertex with it, all farther than 4 d) and the curves where the
  ///   surface ends (the boundary and the edges of holes, each within the
  ///   reach of its samples at 2 grid + 1 points along the edge): N over the
  ///   disk |y| <= d round p is a graph z = h(y), h(0) = 0, of slope at most 1
  ///   (a radial path of length r lifts to one of length at most sqrt(2) r,
  ///   which stays in N short of its edges, and along which the normal turns
  ///   by at most sqrt(2) d kappa) and |Hess h| <= 2^1.5 kappa;
  /// - d kappa <= 0.1: the squared distance to x over that disk,
  ///   |y|^2 + (h(y) - d)^2, has a Hessian of at least
  ///   2 (1 - 2 d 2^1.5 kappa) > 0, so it is convex there, and the disk
  ///   holds every point of N within d of x: the points of the star closer
  ///   than d form one basin, p's.
  /// The argument uses the surface inside N alone, which is smooth up to
  /// the curves where it ends: OpenSubdiv's boundary rules are a crease's
  /// from one side, with no second sheet across it, the faces round a hole
  /// are those of the surface without the hole, and a one-face corner
  /// (valence 2, kept sharp by "edge-and-corner") is a corner of the curve,
  /// which lies farther than 4 d from p like the rest of it; no point of
  /// the curve is then within d of x, where a closest point need not be a
  /// stationary point of the distance inside the surface.
  /// The bounds come from the grid samples of each face: kappa is 4 times
  /// the largest angle between neighbouring samples' normals over their
  /// distance, the cone of normals is the samples' widened by kappa times
  /// 0.6 of the largest spacing, and the face lies within reach(s) of its
  /// samples s (as the candidates' bound takes it). A face is never
  /// certified where a vertex of its star lies on a crease or corner of any
  /// sharpness (where the surface is not smooth: across a concave crease a
  /// closer point lies in the star). The
  /// samples outside the star keep the candidates' bound; a point not
  /// certified takes every start. Per face f, with its ball (o, r) holding
  /// its samples t widened by reach(t), the samples s outside the star
  /// with min over t of |t - s| - reach(t) - reach(s) below 0.1 r are its
  /// near samples, and the clearance bounds that below for the others
  /// (every point of f lies within reach(t) of a sample t of f); a
  /// certified point with clearance at least 2 d takes as starts only the
  /// near samples that pass the candidates' bound (|x - s| >= |p - s| - d
  /// keeps the others out), without a k-d tree query, and not its nearest
  /// sample: outside the near samples that one's cells hold no point
  /// closer than d, and a closer point anywhere lies in such a cell.
  /// Each point's result depends on that point alone; no distance
  /// increases.
  /// @param points      row-major (n, 3), finite
  /// @param footpoints  face_ids, uv and distances of n points on this
  ///                    search's surface (as find or refine_footpoints give
  ///                    them), or with a distance of +inf, (face, u, v) that
  ///                    are only a start (e.g. the footpoints of a previous
  ///                    state of the surface): the refinement from itself
  ///                    then takes it to its local minimum first, as
  ///                    refine_footpoints would, to full precision;
  ///                    positions and normals, where they hold 3n entries,
  ///                    are kept up to date
  /// @param found       the footpoints are this search's find(points) (then
  ///                    the nearest sample is not refined again)
  /// @param certified   where not null, set to how many points the
  ///                    certificate let leave out their star's samples
  /// @param listed      where not null, set to how many of those took their
  ///                    candidates from their face's near samples (clearance
  ///                    at least 2 d), without a query
  /// @throws ParameterError when the sizes disagree with n or a face is out
  ///                        of range
  std::size_t closer(const double* points, std::size_t n, Footpoints& footpoints, bool found = false,
                     std::size_t* certified = nullptr, std::size_t* listed = nullptr) const;

 private:
  const LimitSurface* surface_;
  const Topology* topology_;
  FootpointOptions options_;
  std::vector<std::int32_t> sample_faces_;
  std::vector<double> sample_uv_, positions_, du_, dv_;
  std::vector<std::uint8_t> irregular_;  // per face: Bfr's Surface::IsRegular() false (closer)
  std::vector<double> reach_;  // per sample: the distance to its farthest neighbour in its chart's grid (closer)
  double largest_reach_ = 0.0;
  std::unique_ptr<PointIndex> index_;
  // closer's certificate: per face its star, rim, cone of normals,
  // curvature bound and ball (footpoints.cpp), built on closer's first call.
  struct Certificate;
  const Certificate& certificate() const;
  mutable std::once_flag certificate_once_;
  mutable std::unique_ptr<const Certificate> certificate_;
};

/// Moves footpoints (face_ids, uv: the input state, e.g. those of the
/// previous control vertices) to local minima of the distance to their
/// points: Gauss-Newton steps on (u, v) with Bfr's first derivatives in a
/// trust region (one grid spacing at the start), a step never increasing
/// the distance. A point is final when its next step is below 1e-11 in
/// (u, v), or when a full (uncut) step failed although the model predicted a
/// decrease of the distance no larger than the distance's rounding. Each
/// point's result depends on that point alone (not on the others or
/// their order). A face index out of range is refused (ParameterError,
/// naming it). A step that
/// leaves the face's domain stops on its edge and, where a face lies across
/// that edge (not a hole), continues in that face from the same surface point
/// ("hops"); on a boundary edge it slides along the edge. Fills positions,
/// distances and normals. Its transient arrays are taken from `scratch`
/// where given (a caller that repeats it lends one: detail/scratch.hpp).
void refine_footpoints(const LimitSurface& surface, const Topology& topology, const double* points, std::size_t n,
                       const FootpointOptions& options, Footpoints& footpoints, detail::Scratch* scratch = nullptr);

}  // namespace sorpia
