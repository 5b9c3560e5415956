#pragma once
/// @file point_chunks.hpp
/// Approximation's data as chunks of points (docs/approximation.md, "Large
/// data"): the unit of work of sorpia::approximate's one driver. A chunk
/// holds its points, their weights and their footpoints (the current ones,
/// the best iterate's and a fresh search's) and computes, for the surface's
/// current control vertices, its footpoints and its share of the normal
/// equations; the driver adds the chunks' sums in a fixed order (the chunks'
/// order) and solves the cage's system once per iteration.
///
/// PointChunks is the driver's view of all chunks (a backend): in memory
/// (InMemoryChunks: an array cut into chunks), streamed from a file
/// (FileChunks: binary PLY or .npy read per chunk, footpoint state spilled
/// to a temporary file), or any other, e.g. a Python subclass whose chunks
/// live on a Dask cluster (bindings: a trampoline). Footpoints do not
/// depend on how the points are cut (each point's search and re-projection
/// depend on that point alone); the sums do, by rounding only.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sorpia/footpoints.hpp"
#include "sorpia/normal_matrix.hpp"
#include "sorpia/robust.hpp"
#include "sorpia/surface.hpp"

namespace sorpia {

/// Distances of points to their footpoints, summed (a chunk's, or all
/// chunks' added in order by add()).
struct DistanceSums {
  double squares = 0.0;      ///< sum w_i d_i^2 (a chunk's by pairwise summation; w_i 1 without weights)
  double max = 0.0;          ///< the largest d_i of a point of weight > 0
  std::size_t count = 0;     ///< points
  std::size_t changed = 0;   ///< footpoints replaced (keep_fresh_in_best), else 0
};
/// total += chunk: squares and counts added, max the larger.
void add(DistanceSums& total, const DistanceSums& chunk);

/// A chunk's share of the normal equations (its rows A at its footpoints,
/// weights W): A^T W A and A^T W P.
struct NormalSums {
  NormalMatrix matrix;        ///< A^T W A, 1 value per entry (W scalar) or 6 (the tangent blend); n 0: none yet
  std::vector<double> rhs;    ///< A^T W P, (n, 3) row-major
  double rows_seconds = 0.0;  ///< wall seconds of forming the rows, each face's share of A^T W A and A^T W P
                              ///< added in as it is made (timings' "rows"), of the chunks added
  double rows_cpu = 0.0;      ///< and the process's CPU seconds
};
/// total += chunk: the matrices' patterns merged row by row (sorted columns),
/// values of a shared entry added (total's first); rhs added.
/// @throws ParameterError for matrices of different sizes or blocks
void add(NormalSums& total, NormalSums&& chunk);

/// What the driver needs of the points before any footpoint: their count,
/// bounding box and largest magnitude (checked finite).
struct PointExtent {
  std::size_t count = 0;     ///< points
  std::size_t weighted = 0;  ///< points of weight > 0 (all, without weights)
  double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {0.0, 0.0, 0.0};  ///< the box of the points of weight > 0
  double largest = 0.0;      ///< the largest |coordinate| of any point
};
void add(PointExtent& total, const PointExtent& chunk);

/// The first and second moments of d = (p - center) / diagonal: sum d and
/// sum d d^T (row-major 3x3), over count points.
struct PointMoments {
  std::size_t count = 0;
  double sum[3] = {0.0, 0.0, 0.0};
  double sum2[9] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
};
void add(PointMoments& total, const PointMoments& chunk);

/// One chunk: points (k, 3), weights (k or none) and footpoint states. Its
/// methods are the per-chunk work of the driver's calls of the same names
/// (PointChunks), given the surface (and search) of the current control
/// vertices. `first` is the index of its first point among all (for
/// messages naming a point).
///
/// The chunk holds its points in spatial order (detail::spatial_order, a
/// Morton curve over their box), not as given: the points of a face then lie
/// together in memory, which every pass over the points by face (the
/// footpoints' rounds, the rows' blocks) reads in order instead of
/// scattered. Its footpoint states are in that order too (a backend that
/// stores them, FileChunks, gets the same order back from the same points);
/// best_footpoints(), the sample's choice and the messages naming a point
/// are in the order as given. Each point's footpoint is the same in either
/// order (its search is its own); the sums over the points differ by
/// rounding only.
class ApproximationChunk {
 public:
  ApproximationChunk() = default;
  /// Copies the points and weights (weights may be null).
  ApproximationChunk(const double* points, std::size_t k, const double* weights, std::size_t first);
  std::size_t size() const { return k_; }
  std::size_t first() const { return first_; }
  /// The points (k, 3) in the chunk's order (spatial, see the class comment).
  const std::vector<double>& points() const { return points_; }
  /// Where point i of the chunk's order is among the points as given (0 .. k - 1).
  std::size_t given(std::size_t i) const { return order_.empty() ? i : order_[i]; }
  /// Whether point i counts (weight > 0): a point of weight 0 is no data; it
  /// is left out of the box, the moments, the largest distance and the
  /// sample, as it is out of every sum.
  bool counts(std::size_t i) const { return weights_.empty() || weights_[i] > 0; }

  /// @throws MeshError naming a point not finite; ParameterError naming a
  ///         weight not finite or negative
  PointExtent extent() const;
  /// The points times 2^-e (exact: the driver's scaling of data beyond 2^+-200).
  void scale(int e);
  PointMoments moments(const double center[3], double diagonal) const;
  /// The largest distance of (p - mean) / diagonal from the line along the unit `axis`.
  double line_offset(const double mean[3], const double axis[3], double diagonal) const;

  /// Current footpoints := search.find(points) (closest_points).
  /// search, refine and normal_sums take their transient arrays from `scratch` where given (LocalChunks lends
  /// its one to each chunk's call: detail/scratch.hpp), else arrays of the call's own.
  DistanceSums search(const FootpointSearch& search, detail::Scratch* scratch = nullptr);
  /// Current footpoints re-projected from where they are (refine_footpoints, grid unused, to a uv_tolerance of
  /// 1e-5: the iterations' footpoints, the distances exact to about 1e-6 relatively).
  DistanceSums refine(const LimitSurface& surface, const FootpointOptions& options, detail::Scratch* scratch = nullptr);
  /// The best iterate's footpoints := the current ones.
  void keep_best();
  /// Fresh footpoints := the current ones (of the search's surface: searched
  /// or refined on it) made closest by search.closer, every start that may
  /// lie near a closer point tried; returns the sums of the current
  /// distances with each replaced by the fresh one where that is closer by
  /// more than `closer` (what keep_fresh would make them).
  DistanceSums search_fresh(const FootpointSearch& search, double closer);
  /// Current and fresh footpoints := the current ones, of the previous
  /// control vertices, re-projected onto the search's surface and made
  /// closest in one call of search.closer (the distances given as +inf: its
  /// refinement of each footpoint from itself is the re-projection, to
  /// full precision); returns their sums. refine then search_fresh in one,
  /// each footpoint refined once (the approximation's last iteration).
  DistanceSums refine_fresh(const FootpointSearch& search);
  /// Current footpoints := the fresh ones where closer by more than `closer`.
  void keep_fresh(double closer);
  /// The best iterate's footpoints := the fresh ones where closer (at all);
  /// returns the best's sums, `changed` the footpoints replaced.
  DistanceSums keep_fresh_in_best();
  /// A^T W A and A^T W P at the current footpoints: the rows a face's
  /// points at a time (LimitSurface::position_blocks), each block's share
  /// formed as it is made (NormalBlocks), W the weights (tangential 1) or
  /// the blend towards the normals (blend_weights).
  /// With `robust` (not null): each point's weight times robust_factors of
  /// its current distance at `scale` (the robust fit's update).
  NormalSums normal_sums(const LimitSurface& surface, double tangential, const RobustOptions* robust = nullptr,
                         double scale = 0.0, detail::Scratch* scratch = nullptr) const;
  /// The current distances' histogram (weighted), in bins of `unit`.
  DistanceHistogram distance_histogram(double unit) const;
  /// The robust sums of the current distances (sorpia::robust_sums).
  RobustSums robust_sums(const RobustOptions& robust, double scale) const;
  /// The best iterate's footpoints: face_ids, uv, distances.
  Footpoints best_footpoints() const;

  /// The footpoint states as arrays (face ids, uv, distances, normals; the
  /// best's without normals), for a backend that stores them elsewhere
  /// between calls (FileChunks).
  struct State {
    std::vector<std::int32_t> face_ids;
    std::vector<double> uv, distances, normals;
  };
  State current, best, fresh;
  /// Points (and weights) replaced, e.g. read again from a file: k unchanged.
  void set_points(std::vector<double> points, std::vector<double> weights);
  /// A chunk of this one's points (and weights) that are in the fixed sample
  /// of about sample_points of all k (point_sample_mask: each point's choice
  /// its own, the same for any chunking), without footpoint states: the
  /// coarse iterations' chunk (PointChunks::set_sample).
  ApproximationChunk sampled(std::size_t k, std::size_t sample_points) const;

 private:
  friend class FileChunks;
  DistanceSums sums(const std::vector<double>& distances, detail::Scratch* scratch = nullptr) const;
  // Puts the points (and weights) in spatial order, order_ the way back; none for points not all finite (extent()
  // names the first, as given) or more than 2^32 - 1.
  void arrange();
  std::size_t k_ = 0, first_ = 0;
  std::vector<double> points_, weights_;  // weights_ empty: all 1
  std::vector<std::uint32_t> order_;      // point i's position as given; empty: as given
  // The normal matrix's pattern of the last normal_sums (NormalBlocks' `kept`: the same while the faces holding
  // the points do), read and replaced atomically (std::atomic_load, std::atomic_store).
  mutable std::shared_ptr<const NormalPattern> normal_pattern_;
};

/// The driver's view of all chunks (a backend). The driver calls, in order:
/// size, extent, scale (only when e != 0), moments, line_offset; set_sample
/// around the coarse iterations (only with them); then per surface state
/// set_control_vertices, and search (iteration 0, and after the coarse
/// iterations), refine
/// (after each update but the last), refine_fresh (after the last update),
/// normal_sums (before each update), keep_best (when the RMS is the lowest
/// so far), search_fresh / keep_fresh (before stopping),
/// keep_fresh_in_best and best_footpoints (at the end); sample once, for
/// the surface-to-data report. Every sum is the chunks' added in their
/// fixed order (add()).
class PointChunks {
 public:
  virtual ~PointChunks() = default;
  virtual std::size_t size() = 0;
  virtual PointExtent extent() = 0;
  virtual void scale(int e) = 0;
  virtual PointMoments moments(const double center[3], double diagonal) = 0;
  virtual double line_offset(const double mean[3], const double axis[3], double diagonal) = 0;
  /// The surface's control vertices (n, 3) for the calls that follow (the
  /// driver's surface holds them already).
  virtual void set_control_vertices(const double* vertices, std::size_t n) = 0;
  virtual DistanceSums search(const FootpointOptions& options) = 0;
  virtual DistanceSums refine(const FootpointOptions& options) = 0;
  virtual void keep_best() = 0;
  virtual DistanceSums search_fresh(const FootpointOptions& options, double closer) = 0;
  virtual void keep_fresh(double closer) = 0;
  virtual DistanceSums keep_fresh_in_best() = 0;
  virtual NormalSums normal_sums(double tangential) = 0;
  /// The fresh footpoints of the current control vertices from the current
  /// footpoints of the previous ones, and their sums (the closest points'
  /// distances): ApproximationChunk::refine_fresh per chunk, which refines
  /// each footpoint once. This default, for a backend without it, calls
  /// refine then search_fresh (closer 0), each footpoint refined twice: the
  /// same distances to rounding, its current footpoints the refined ones.
  virtual DistanceSums refine_fresh(const FootpointOptions& options);
  /// The robust fit's calls (sorpia/robust.hpp), on the current footpoints:
  /// their distances' histogram (all chunks' merged), robust_sums (the
  /// criterion's sum w rho(d), the points within and beyond the cut) at a
  /// scale, and normal_sums with each weight times the robust factor at a
  /// scale. A backend without them cannot fit robustly: these defaults
  /// throw ParameterError saying so (robust = "none" runs without them).
  virtual DistanceHistogram distance_histogram(double unit);
  virtual RobustSums robust_sums(const RobustOptions& robust, double scale);
  virtual NormalSums robust_normal_sums(double tangential, const RobustOptions& robust, double scale);
  /// The coarse iterations' points (ApproximationOptions::coarse_iterations):
  /// with sample_points > 0, every call from search to robust_normal_sums
  /// works, until the next set_sample, on the chunks' points in the fixed
  /// sample of about sample_points of all (ApproximationChunk::sampled), with
  /// footpoint states of their own; with 0, on all points again, with their
  /// states as before. A backend without it cannot run coarse iterations:
  /// this default throws ParameterError saying so.
  virtual void set_sample(std::size_t sample_points);
  /// Points for the surface-to-data distances (row-major (s, 3)): all of
  /// them when they fit, else a fixed sample.
  virtual std::vector<double> sample() = 0;
  /// The best iterate's footpoints of all points in order (face_ids, uv,
  /// distances), or empty ones where they are not kept (FileChunks).
  virtual Footpoints best_footpoints() = 0;
};

/// Chunks that run on the driver's own surface (shared by reference), one
/// after the other, each on the core's threads; the footpoint search is
/// built once per surface state. What a backend stores between calls is
/// its business: load(c) gives chunk c ready for a call, store(c) takes it
/// back (in memory: the chunk itself; from a file: read and spilled).
class LocalChunks : public PointChunks {
 public:
  explicit LocalChunks(LimitSurface& surface) : surface_(surface) {}
  std::size_t size() override;
  PointExtent extent() override;
  void scale(int e) override;
  PointMoments moments(const double center[3], double diagonal) override;
  double line_offset(const double mean[3], const double axis[3], double diagonal) override;
  void set_control_vertices(const double* vertices, std::size_t n) override;
  DistanceSums search(const FootpointOptions& options) override;
  DistanceSums refine(const FootpointOptions& options) override;
  void keep_best() override;
  DistanceSums search_fresh(const FootpointOptions& options, double closer) override;
  DistanceSums refine_fresh(const FootpointOptions& options) override;
  void keep_fresh(double closer) override;
  DistanceSums keep_fresh_in_best() override;
  NormalSums normal_sums(double tangential) override;
  DistanceHistogram distance_histogram(double unit) override;
  RobustSums robust_sums(const RobustOptions& robust, double scale) override;
  NormalSums robust_normal_sums(double tangential, const RobustOptions& robust, double scale) override;
  /// The sample's chunks are held in memory (about sample_points points).
  void set_sample(std::size_t sample_points) override;
  std::vector<double> sample() override;
  Footpoints best_footpoints() override;

  /// What a chunk needs for a call: its points, and which footpoint states.
  enum Needs : unsigned { kPoints = 1, kCurrent = 2, kBest = 4, kFresh = 8 };

 protected:
  virtual std::size_t n_chunks() const = 0;
  virtual std::size_t total_points() const = 0;
  /// Chunk c with what `needs` names loaded (the rest may be empty).
  virtual ApproximationChunk& load(std::size_t c, unsigned needs) = 0;
  /// Chunk c back after a call that changed the states `changed` names.
  virtual void store(std::size_t c, unsigned changed) = 0;
  int scale_ = 0;

 private:
  const FootpointSearch& footpoint_search(const FootpointOptions& options);
  // normal_sums of every chunk added in order; with `robust`, the robust fit's (robust_normal_sums).
  NormalSums chunks_normal_sums(double tangential, const RobustOptions* robust, double scale);
  // Chunk c for a footpoint call: the sample's (set_sample), else load(c, needs); put(c, changed) gives it back.
  ApproximationChunk& chunk(std::size_t c, unsigned needs) { return sampled_.empty() ? load(c, needs) : sampled_[c]; }
  void put(std::size_t c, unsigned changed) {
    if (sampled_.empty()) store(c, changed);
  }
  std::vector<ApproximationChunk> sampled_;  // the coarse iterations' chunks, empty when working on all points
  // The chunks' calls' transient arrays (search, refine, normal_sums), one chunk's call at a time: the memory of a
  // chunk's largest call, kept across the iterations; given back before the calls that take none (search_fresh,
  // best_footpoints) so that it adds to no other peak.
  detail::Scratch scratch_;
  LimitSurface& surface_;
  std::unique_ptr<FootpointSearch> search_;
  // The last search, retired (FootpointSearch::retire) when the control vertices changed: the next search takes
  // over its grid and tree partition.
  std::unique_ptr<FootpointSearch> retired_;
  void retire_search();
  FootpointOptions search_options_{};
};

/// An in-memory array of points cut into chunks of `chunk_points` (the last
/// one shorter). The points and weights are copied into the chunks.
class InMemoryChunks : public LocalChunks {
 public:
  /// @param weights  k weights or null
  /// @throws ParameterError for chunk_points 0
  InMemoryChunks(LimitSurface& surface, const double* points, std::size_t k, const double* weights,
                 std::size_t chunk_points);

 protected:
  std::size_t n_chunks() const override { return chunks_.size(); }
  std::size_t total_points() const override { return k_; }
  ApproximationChunk& load(std::size_t c, unsigned) override { return chunks_[c]; }
  void store(std::size_t, unsigned) override {}

 private:
  std::size_t k_;
  std::vector<ApproximationChunk> chunks_;
};

/// Where a file's points lie: k records of `stride` bytes from `offset`,
/// coordinate c at x_offset[c] in each, float64 or float32 (little-endian).
struct PointFileLayout {
  std::size_t k = 0, offset = 0, stride = 0, x_offset[3] = {0, 0, 0};
  bool float64 = false;
};
/// The layout of a binary little-endian PLY's vertices or of a .npy (k, 3)
/// array of float32 or float64 in C order (FileChunks' files), from its header.
/// @throws FileError naming the file and what it is not
PointFileLayout point_file_layout(const std::string& path);
/// Points first .. first + count of such a file as float64, row-major
/// (count, 3): a chunk read where it is used (a Dask worker).
/// @throws FileError; ParameterError for a range beyond the file's points
std::vector<double> read_point_file(const std::string& path, std::size_t first, std::size_t count);
/// Which of points first .. first + count of k are in FileChunks' fixed
/// sample of about `sample_points` (all of them when k <= sample_points):
/// each point's choice is its own, the same for any chunking.
std::vector<char> point_sample_mask(std::size_t first, std::size_t count, std::size_t k, std::size_t sample_points);

/// Points read from a file a chunk at a time (every call reads its chunk
/// again), their footpoint states spilled to a temporary file between calls:
/// memory set by the chunk and the cage, not the points. Binary
/// little-endian PLY (the vertex element's x, y, z as float or double;
/// other properties skipped, other elements after it ignored) or .npy
/// (float32 or float64, shape (k, 3), C order). Weights are all 1.
class FileChunks : public LocalChunks {
 public:
  /// @param spill_directory  where the temporary file goes (removed on destruction)
  /// @param sample_points    the most points sample() returns (a fixed
  ///                         sample, the same for any chunk size, when there are more)
  /// @throws FileError for a file that cannot be read or is not such a file
  FileChunks(LimitSurface& surface, const std::string& path, std::size_t chunk_points,
             const std::string& spill_directory, std::size_t sample_points);
  ~FileChunks() override;
  FileChunks(const FileChunks&) = delete;
  FileChunks& operator=(const FileChunks&) = delete;
  void scale(int e) override { scale_ = e; }  // applied as each chunk is read
  std::vector<double> sample() override;
  Footpoints best_footpoints() override { return {}; }

 protected:
  std::size_t n_chunks() const override { return (k_ + chunk_points_ - 1) / chunk_points_; }
  std::size_t total_points() const override { return k_; }
  ApproximationChunk& load(std::size_t c, unsigned needs) override;
  void store(std::size_t c, unsigned changed) override;

 private:
  std::vector<double> read_points(std::size_t first, std::size_t count) const;
  std::string path_, spill_path_;
  int fd_ = -1, spill_fd_ = -1;
  std::size_t k_ = 0, chunk_points_ = 0, sample_points_ = 0;
  PointFileLayout layout_;
  ApproximationChunk chunk_;  // the loaded one
};

}  // namespace sorpia
