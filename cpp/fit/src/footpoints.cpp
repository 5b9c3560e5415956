#include "sorpia/footpoints.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/order.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/spatial.hpp"
#include "sorpia/detail/unit_normal.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/subface_grid.hpp"

namespace sorpia {

// ---- k-d tree ----------------------------------------------------------------

namespace {

constexpr std::uint32_t kLeafSize = 12;
// Points per task, at least, of refit's and set_slack's copies and leaves.
constexpr std::size_t kPointsPerFitTask = 65536;

// Squared distance from q to a box (0 inside).
inline double box_distance2(const float* lo, const float* hi, const double* q) {
  double d2 = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double e = q[c] < lo[c] ? lo[c] - q[c] : (q[c] > hi[c] ? q[c] - hi[c] : 0.0);
    d2 += e * e;
  }
  return d2;
}

// Pushes inner node nd's children on a depth-first search's stack, the
// nearer to q last, so that it is searched first.
template <class Node>
void push_children(const std::vector<Node>& nodes, const Node& nd, const double* q, std::vector<std::uint32_t>& stack) {
  const Node& a = nodes[nd.left];
  const Node& b = nodes[nd.left + 1];
  const bool a_first = box_distance2(a.lo, a.hi, q) <= box_distance2(b.lo, b.hi, q);
  stack.push_back(a_first ? nd.left + 1 : nd.left);
  stack.push_back(a_first ? nd.left : nd.left + 1);
}

}  // namespace

PointIndex::PointIndex(const double* points, std::size_t n) : n_(n) {
  if (n == 0) throw ParameterError("a point index needs at least one point");
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw ParameterError("a point index holds fewer than 2^32 - 1 points, got " + std::to_string(n));
  order_.resize(n);
  for (std::size_t i = 0; i < n; ++i) order_[i] = static_cast<std::int64_t>(i);
  points_.assign(points, points + 3 * n);
  nodes_.reserve(2 * (n / kLeafSize + 1) + 1);
  nodes_.push_back(Node{});
  // The top levels on this thread, down to one subtree per task; the
  // subtrees (disjoint ranges of order_) on the core's threads, each into
  // nodes of its own, appended after.
  const int tasks = detail::task_count(n, 65536);
  int depth = 0;
  while ((1 << depth) < tasks) ++depth;
  std::vector<std::array<std::uint32_t, 3>> subtrees;  // (node, begin, end)
  build(nodes_, 0, 0, static_cast<std::uint32_t>(n), depth, &subtrees);
  std::vector<std::vector<Node>> built(subtrees.size());
  detail::for_each_task(subtrees.size() > 1, static_cast<int>(subtrees.size()), [&](int t) {
    const auto& [node, begin, end] = subtrees[static_cast<std::size_t>(t)];
    std::vector<Node>& nodes = built[static_cast<std::size_t>(t)];
    nodes.reserve(2 * ((end - begin) / kLeafSize + 1) + 1);
    nodes.push_back(Node{});
    build(nodes, 0, begin, end, -1, nullptr);
  });
  for (std::size_t t = 0; t < subtrees.size(); ++t) {
    // Local node j >= 1 lands at offset + j - 1; its children stay a pair.
    const auto offset = static_cast<std::uint32_t>(nodes_.size());
    std::vector<Node>& nodes = built[t];
    for (Node& nd : nodes)
      if (nd.left != 0) nd.left += offset - 1;
    nodes_[subtrees[t][0]] = nodes[0];
    nodes_.insert(nodes_.end(), nodes.begin() + 1, nodes.end());
  }
  // Tree order for the points, so that a leaf's points lie together.
  std::vector<double> sorted(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) sorted[3 * i + c] = points[3 * order_[i] + c];
  points_.swap(sorted);
}

void PointIndex::set_box(Node& nd, const double* lo, const double* hi) {
  for (int c = 0; c < 3; ++c) {
    nd.lo[c] = std::nextafter(static_cast<float>(lo[c]), -std::numeric_limits<float>::infinity());
    nd.hi[c] = std::nextafter(static_cast<float>(hi[c]), std::numeric_limits<float>::infinity());
    if (static_cast<double>(nd.lo[c]) > lo[c]) nd.lo[c] = -std::numeric_limits<float>::infinity();
    if (static_cast<double>(nd.hi[c]) < hi[c]) nd.hi[c] = std::numeric_limits<float>::infinity();
  }
}

void PointIndex::refit(const double* points) {
  points_.resize(3 * n_);
  const int tasks = detail::task_count(n_, kPointsPerFitTask);
  detail::for_each_index(tasks > 1, tasks, n_, [&](std::size_t i) {
    for (int c = 0; c < 3; ++c) points_[3 * i + c] = points[3 * order_[i] + c];
  });
  point_slack_.clear();
  node_slack_.clear();
  // The leaves' boxes on the core's threads; then, as a node's children follow it in nodes_ (as set_slack takes
  // them), the inner nodes' from the last node back.
  const int node_tasks = detail::task_count(nodes_.size(), kPointsPerFitTask / kLeafSize);
  detail::for_each_index(node_tasks > 1, node_tasks, nodes_.size(), [&](std::size_t j) {
    Node& nd = nodes_[j];
    if (nd.left != 0) return;
    double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (std::uint32_t i = nd.begin; i < nd.end; ++i)
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], points_[3 * i + c]);
        hi[c] = std::max(hi[c], points_[3 * i + c]);
      }
    set_box(nd, lo, hi);
  });
  for (std::size_t j = nodes_.size(); j-- > 0;) {
    Node& nd = nodes_[j];
    if (nd.left == 0) continue;
    const Node &a = nodes_[nd.left], &b = nodes_[nd.left + 1];
    for (int c = 0; c < 3; ++c) {
      nd.lo[c] = std::min(a.lo[c], b.lo[c]);
      nd.hi[c] = std::max(a.hi[c], b.hi[c]);
    }
  }
}

void PointIndex::release_points() {
  std::vector<double>().swap(points_);
  std::vector<double>().swap(point_slack_);
  std::vector<float>().swap(node_slack_);
}

void PointIndex::build(std::vector<Node>& nodes, std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                       std::vector<std::array<std::uint32_t, 3>>* subtrees) {
  // points_ is still in input order here; order_[begin..end) are the node's points.
  if (depth == 0 && end - begin > kLeafSize) {
    subtrees->push_back({node, begin, end});
    return;
  }
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (std::uint32_t i = begin; i < end; ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = points_[3 * order_[i] + c];
      lo[c] = std::min(lo[c], x);
      hi[c] = std::max(hi[c], x);
    }
  Node& nd = nodes[node];
  set_box(nd, lo, hi);
  nd.begin = begin;
  nd.end = end;
  nd.left = 0;
  if (end - begin <= kLeafSize) return;
  int axis = 0;
  for (int c = 1; c < 3; ++c)
    if (hi[c] - lo[c] > hi[axis] - lo[axis]) axis = c;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::int64_t a, std::int64_t b) { return points_[3 * a + axis] < points_[3 * b + axis]; });
  const auto left = static_cast<std::uint32_t>(nodes.size());
  nodes[node].left = left;  // nodes may grow below: index, not reference
  nodes.push_back(Node{});
  nodes.push_back(Node{});
  build(nodes, left, begin, mid, depth - 1, subtrees);
  build(nodes, left + 1, mid, end, depth - 1, subtrees);
}

void PointIndex::nearest(const double* queries, std::size_t k, std::int64_t* index, double* distance) const {
  const std::vector<std::size_t> order = detail::spatial_order(queries, k);
  const int tasks = detail::task_count(k, 4096);
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    std::vector<std::uint32_t> stack;
    stack.reserve(64);
    const std::size_t first = k * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks);
    const std::size_t last = k * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(tasks);
    for (std::size_t j = first; j < last; ++j) {
      if (t == 0 && (j - first) % 65536 == 0) poll_interrupt();
      const std::size_t qi = order[j];
      const double* q = queries + 3 * qi;
      double best = std::numeric_limits<double>::infinity();
      std::uint32_t best_i = 0;
      stack.clear();
      stack.push_back(0);
      while (!stack.empty()) {
        const Node& nd = nodes_[stack.back()];
        stack.pop_back();
        if (box_distance2(nd.lo, nd.hi, q) >= best) continue;
        if (nd.left == 0) {
          for (std::uint32_t i = nd.begin; i < nd.end; ++i) {
            const double* p = &points_[3 * static_cast<std::size_t>(i)];
            const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
            const double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 < best) best = d2, best_i = i;
          }
          continue;
        }
        push_children(nodes_, nd, q, stack);
      }
      index[qi] = order_[best_i];
      distance[qi] = std::sqrt(best);
    }
  });
}

std::size_t PointIndex::least_ranked(const double* q, double bound, double slack, std::size_t k,
                                     const std::function<double(std::int64_t, double)>& rank, std::int64_t* index,
                                     double* value) const {
  if (k == 0) return 0;
  // The points taken so far, a max-heap on their rank of at most k; the
  // bound is the k-th one's once k are held.
  thread_local std::vector<std::pair<double, std::uint32_t>> heap;
  heap.clear();
  // A box at distance b holds no rank below b minus its points' slack.
  const auto box_out = [&](std::uint32_t node) {
    const double reach =
        bound + (node_slack_.empty() ? slack : std::min(slack, static_cast<double>(node_slack_[node])));
    return !(reach > 0.0) || box_distance2(nodes_[node].lo, nodes_[node].hi, q) >= reach * reach;
  };
  thread_local std::vector<std::uint32_t> stack;
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const std::uint32_t node = stack.back();
    const Node& nd = nodes_[node];
    stack.pop_back();
    if (box_out(node)) continue;
    if (nd.left == 0) {
      for (std::uint32_t i = nd.begin; i < nd.end; ++i) {
        const double* p = &points_[3 * static_cast<std::size_t>(i)];
        const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double within = bound + (point_slack_.empty() ? slack : std::min(slack, point_slack_[i]));
        if (!(within > 0.0 && d2 < within * within)) continue;
        const double d = std::sqrt(d2);
        if (!(d - slack < bound)) continue;
        const double r = rank(order_[i], d);
        if (!(r < bound)) continue;
        heap.emplace_back(r, i);
        std::push_heap(heap.begin(), heap.end());
        if (heap.size() > k) {
          std::pop_heap(heap.begin(), heap.end());
          heap.pop_back();
        }
        if (heap.size() == k) bound = heap.front().first;
      }
      continue;
    }
    push_children(nodes_, nd, q, stack);
  }
  std::sort_heap(heap.begin(), heap.end());
  for (std::size_t j = 0; j < heap.size(); ++j) {
    index[j] = order_[heap[j].second];
    value[j] = heap[j].first;
  }
  return heap.size();
}

void PointIndex::set_slack(const double* slack) {
  // A node's children follow it in nodes_: from the last node back, each
  // node's children are done before it.
  point_slack_.resize(n_);
  const int tasks = detail::task_count(n_, kPointsPerFitTask);
  detail::for_each_index(tasks > 1, tasks, n_, [&](std::size_t i) { point_slack_[i] = slack[order_[i]]; });
  // The leaves on the core's threads, then the inner nodes (as refit).
  node_slack_.resize(nodes_.size());
  const int node_tasks = detail::task_count(nodes_.size(), kPointsPerFitTask / kLeafSize);
  detail::for_each_index(node_tasks > 1, node_tasks, nodes_.size(), [&](std::size_t j) {
    const Node& nd = nodes_[j];
    if (nd.left != 0) return;
    double most = 0.0;
    for (std::uint32_t i = nd.begin; i < nd.end; ++i) most = std::max(most, point_slack_[i]);
    auto up = static_cast<float>(most);
    if (static_cast<double>(up) < most) up = std::nextafter(up, std::numeric_limits<float>::infinity());
    node_slack_[j] = up;
  });
  for (std::size_t j = nodes_.size(); j-- > 0;) {
    const Node& nd = nodes_[j];
    if (nd.left != 0) node_slack_[j] = std::max(node_slack_[nd.left], node_slack_[nd.left + 1]);
  }
}

// ---- charts of a face's domain ---------------------------------------------------

namespace {

// A face's domain in Bfr's parameterisation is one chart (a Loop triangle, a
// Catmull-Clark quad) or k square charts (the quad sub-faces of a
// Catmull-Clark k-gon, k != 4). Local coordinates (a, b): the triangle
// a, b >= 0, a + b <= 1 or the unit square; sub-face j's (a, b) = 2 ((u, v) -
// (x_j, y_j)), so that (0, 0) is corner j, (1, 0) the midpoint of edge j,
// (1, 1) the centre and (0, 1) the midpoint of edge j - 1 (surface.hpp).
enum class Kind : std::uint8_t { Triangle, Quad, Sub };

struct Domains {
  const Topology& topology;
  Scheme scheme;
  const std::vector<std::int32_t>& opposite;  // half-edge (face_offset(f) + e) -> half-edge across, or -1 (the topology's)
  std::vector<std::int32_t> half_edge_face;
  std::vector<std::uint8_t> hole;

  Domains(const Topology& t, Scheme s, const std::vector<std::int32_t>& holes)
      : topology(t), scheme(s), opposite(t.half_edge_twins()) {
    const std::size_t m = t.n_faces();
    hole.assign(m, 0);
    for (const std::int32_t f : holes) hole[static_cast<std::size_t>(f)] = 1;
    half_edge_face.assign(t.face_indices().size(), 0);
    for (std::size_t f = 0; f < m; ++f) {
      const std::int32_t o = t.face_offset(f), k = t.face_size(f);
      std::fill_n(half_edge_face.begin() + o, k, static_cast<std::int32_t>(f));
    }
  }

  Kind kind(std::int32_t f) const {
    if (scheme == Scheme::Loop) return Kind::Triangle;
    return topology.face_size(static_cast<std::size_t>(f)) == 4 ? Kind::Quad : Kind::Sub;
  }
  int columns(std::int32_t f) const { return subface_columns(topology.face_size(static_cast<std::size_t>(f))); }
  int charts(std::int32_t f) const { return kind(f) == Kind::Sub ? topology.face_size(static_cast<std::size_t>(f)) : 1; }

  // (u, v) of local (a, b) in chart c of face f, and back.
  void to_uv(std::int32_t f, int c, double a, double b, double* uv) const {
    if (kind(f) != Kind::Sub) {
      uv[0] = a, uv[1] = b;
      return;
    }
    double origin[2];
    subface_origin(columns(f), c, origin);
    uv[0] = origin[0] + 0.5 * a;
    uv[1] = origin[1] + 0.5 * b;
  }
  // The chart of (u, v) in face f (a point on a sub-face's edge: the sub-face
  // Bfr's evaluation takes it in) and its local coordinates.
  int from_uv(std::int32_t f, const double* uv, double* ab) const {
    if (kind(f) != Kind::Sub) {
      ab[0] = uv[0], ab[1] = uv[1];
      return 0;
    }
    const int w = columns(f), k = topology.face_size(static_cast<std::size_t>(f));
    const int tu = std::clamp(static_cast<int>(std::floor(uv[0] + 1e-12)), 0, w - 1);
    int tv = std::max(0, static_cast<int>(std::floor(uv[1] + 1e-12)));
    int c = tv * w + tu;
    if (c >= k) c = k - 1, tv = c / w;
    ab[0] = std::clamp(2.0 * (uv[0] - (c % w)), 0.0, 1.0);
    ab[1] = std::clamp(2.0 * (uv[1] - tv), 0.0, 1.0);
    return c;
  }

  // Local coordinates at parameter s along face f's edge e (corner e to e + 1)
  // and the chart they lie in.
  int on_edge(std::int32_t f, int e, double s, double* ab) const {
    switch (kind(f)) {
      case Kind::Triangle: {
        static constexpr double kA[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        const double* p = kA[e];
        const double* q = kA[(e + 1) % 3];
        ab[0] = p[0] + s * (q[0] - p[0]), ab[1] = p[1] + s * (q[1] - p[1]);
        return 0;
      }
      case Kind::Quad: {
        static constexpr double kA[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        const double* p = kA[e];
        const double* q = kA[(e + 1) % 4];
        ab[0] = p[0] + s * (q[0] - p[0]), ab[1] = p[1] + s * (q[1] - p[1]);
        return 0;
      }
      case Kind::Sub: {
        const int k = topology.face_size(static_cast<std::size_t>(f));
        if (s < 0.5) {
          ab[0] = 2.0 * s, ab[1] = 0.0;
          return e;
        }
        ab[0] = 0.0, ab[1] = 2.0 * (1.0 - s);
        return (e + 1) % k;
      }
    }
    return 0;
  }
};

// Where a step from local point p by d in chart c of face f ends: inside the
// chart, on a chart's edge across which the domain goes on (then in the next
// chart or face, at the same surface point), or slid along the domain's
// boundary. Returns true when the point moved.
bool move(const Domains& dom, std::int32_t& f, int& c, double* ab, const double* d) {
  const Kind kind = dom.kind(f);
  // From the chart: a point put on an edge (a hop's, a + b = 1 computed)
  // can lie a rounding outside it, where no side is crossed from and a step
  // would leave the domain unseen.
  const double a0 = std::clamp(ab[0], 0.0, 1.0);
  const double b0 = std::clamp(ab[1], 0.0, kind == Kind::Triangle ? 1.0 - a0 : 1.0);
  const double a1 = a0 + d[0], b1 = b0 + d[1];
  // Fraction t of the step at which each side is crossed (sides: 0 b = 0,
  // 1 a + b = 1 or a = 1, 2 a = 0 for a triangle / b = 1 for a square, 3 a = 0).
  double t_exit = 1.0;
  int side = -1;
  const auto cross = [&](double from, double to, int s) {  // crossing of a linear function from >= 0 to < 0
    if (to < 0.0 && from >= 0.0) {
      const double t = from / (from - to);
      if (t < t_exit) t_exit = t, side = s;
    }
  };
  if (kind == Kind::Triangle) {
    cross(b0, b1, 0);
    cross(1.0 - a0 - b0, 1.0 - a1 - b1, 1);
    cross(a0, a1, 2);
  } else {
    cross(b0, b1, 0);
    cross(1.0 - a0, 1.0 - a1, 1);
    cross(1.0 - b0, 1.0 - b1, 2);
    cross(a0, a1, 3);
  }
  if (side < 0) {
    if (a1 == a0 && b1 == b0) return false;
    ab[0] = a1, ab[1] = b1;
    return true;
  }
  double a = a0 + t_exit * d[0], b = b0 + t_exit * d[1];
  // On the side exactly.
  if (kind == Kind::Triangle) {
    if (side == 0) b = 0.0;
    if (side == 1) b = 1.0 - a;
    if (side == 2) a = 0.0;
    a = std::clamp(a, 0.0, 1.0), b = std::clamp(b, 0.0, 1.0 - a);
  } else {
    if (side == 0) b = 0.0;
    if (side == 1) a = 1.0;
    if (side == 2) b = 1.0;
    if (side == 3) a = 0.0;
    a = std::clamp(a, 0.0, 1.0), b = std::clamp(b, 0.0, 1.0);
  }
  // The face edge (and the parameter along it) that the side lies on, or
  // the next sub-face of the same face.
  int edge = -1;
  double s = 0.0;
  if (kind == Kind::Triangle) {
    edge = side;
    s = side == 0 ? a : (side == 1 ? b : 1.0 - b);
  } else if (kind == Kind::Quad) {
    edge = side;
    s = side == 0 ? a : side == 1 ? b : side == 2 ? 1.0 - a : 1.0 - b;
  } else {
    const int k = dom.topology.face_size(static_cast<std::size_t>(f));
    if (side == 1) {  // a = 1: into sub-face c + 1 at its side b = 1
      const double nb = b;
      c = (c + 1) % k;
      ab[0] = nb, ab[1] = 1.0;
      return true;
    }
    if (side == 2) {  // b = 1: into sub-face c - 1 at its side a = 1
      const double na = a;
      c = (c + k - 1) % k;
      ab[0] = 1.0, ab[1] = na;
      return true;
    }
    if (side == 0) edge = c, s = 0.5 * a;
    else edge = (c + k - 1) % k, s = 1.0 - 0.5 * b;
  }
  const std::int32_t h = dom.topology.face_offset(static_cast<std::size_t>(f)) + edge;
  const std::int32_t across = dom.opposite[static_cast<std::size_t>(h)];
  const std::int32_t g = across < 0 ? -1 : dom.half_edge_face[static_cast<std::size_t>(across)];
  if (g < 0 || dom.hole[static_cast<std::size_t>(g)]) {
    // A boundary: slide, the step's component along the side kept.
    double pa = a1, pb = b1;
    if (kind == Kind::Triangle) {
      pa = std::max(pa, 0.0), pb = std::max(pb, 0.0);
      if (pa + pb > 1.0) {
        const double e = 0.5 * (pa + pb - 1.0);
        pa -= e, pb -= e;
        pa = std::clamp(pa, 0.0, 1.0), pb = std::clamp(pb, 0.0, 1.0 - pa);
      }
    } else {
      pa = std::clamp(pa, 0.0, 1.0), pb = std::clamp(pb, 0.0, 1.0);
    }
    if (pa == a0 && pb == b0) return false;
    ab[0] = pa, ab[1] = pb;
    return true;
  }
  const int e_g = across - dom.topology.face_offset(static_cast<std::size_t>(g));
  f = g;
  c = dom.on_edge(g, e_g, std::clamp(1.0 - s, 0.0, 1.0), ab);
  return true;
}

// The grid of starting samples: for each face (not a hole), each chart, the
// local points (i / r, j / r) (i + j <= r in a triangle), drawn towards the
// chart's centre by a factor r / (r + 1) so that every sample lies inside
// its face: a point nearest to a sample starts in that sample's face (a
// sample on a corner, shared by every face there, would start it in any one
// of them, and the walk round the vertex can take a step per face).
void grid_samples(const Domains& dom, int r, std::vector<std::int32_t>& face_ids, std::vector<double>& uv) {
  const auto m = static_cast<std::int32_t>(dom.topology.n_faces());
  for (std::int32_t f = 0; f < m; ++f) {
    if (dom.hole[static_cast<std::size_t>(f)]) continue;
    const bool tri = dom.kind(f) == Kind::Triangle;
    for (int c = 0; c < dom.charts(f); ++c)
      for (int j = 0; j <= r; ++j)
        for (int i = 0; i <= (tri ? r - j : r); ++i) {
          const double centre = tri ? 1.0 / 3.0 : 0.5, shrink = static_cast<double>(r) / (r + 1);
          double p[2];
          dom.to_uv(f, c, centre + shrink * (static_cast<double>(i) / r - centre),
                    centre + shrink * (static_cast<double>(j) / r - centre), p);
          face_ids.push_back(f);
          uv.push_back(p[0]);
          uv.push_back(p[1]);
        }
  }
}

// The number of samples of face f in grid_samples(dom, r): none in a hole.
std::size_t face_samples(const Domains& dom, int r, std::int32_t f) {
  if (dom.hole[static_cast<std::size_t>(f)]) return 0;
  const auto side = static_cast<std::size_t>(r + 1);
  const std::size_t chart = dom.kind(f) == Kind::Triangle ? side * (side + 1) / 2 : side * side;
  return static_cast<std::size_t>(dom.charts(f)) * chart;
}

// Calls link(f, a, b) for each pair of neighbouring samples a, b of face f of
// grid_samples(dom, r) in one chart's grid (indices in its order, face f's
// from `offset`): along a row, a column, and for a triangle the third
// direction.
template <class Link>
void for_each_face_grid_link(const Domains& dom, int r, std::int32_t f, std::size_t offset, Link&& link) {
  if (dom.hole[static_cast<std::size_t>(f)]) return;
  const bool tri = dom.kind(f) == Kind::Triangle;
  for (int c = 0; c < dom.charts(f); ++c) {
    // Sample (i, j) of this chart: row j holds r + 1 samples (r + 1 - j in a triangle).
    const auto at = [&](int i, int j) {
      std::size_t o = offset;
      for (int jj = 0; jj < j; ++jj) o += static_cast<std::size_t>(tri ? r + 1 - jj : r + 1);
      return o + static_cast<std::size_t>(i);
    };
    for (int j = 0; j <= r; ++j) {
      const int row = tri ? r - j : r;  // the last i of row j
      for (int i = 0; i <= row; ++i) {
        if (i < row) link(f, at(i, j), at(i + 1, j));
        if (j < r && (!tri || i <= row - 1)) link(f, at(i, j), at(i, j + 1));
        if (tri && i > 0 && j < r) link(f, at(i, j), at(i - 1, j + 1));
      }
    }
    offset = at(0, r) + static_cast<std::size_t>(tri ? 1 : r + 1);
  }
}

// for_each_face_grid_link for every face, in order.
template <class Link>
void for_each_grid_link(const Domains& dom, int r, Link&& link) {
  const auto m = static_cast<std::int32_t>(dom.topology.n_faces());
  std::size_t offset = 0;
  for (std::int32_t f = 0; f < m; ++f) {
    for_each_face_grid_link(dom, r, f, offset, link);
    offset += face_samples(dom, r, f);
  }
}

double distance3(const double* p, const double* q) {
  return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
}

// For each sample of grid_samples(dom, r) (in its order), with limit points
// `positions`: the largest distance to its neighbours in its chart's grid
// (for_each_grid_link). Every point of the chart lies within about half a
// spacing of a sample in (u, v), so within this of one in space.
// A face's links join its own samples only: the faces on the core's threads.
std::vector<double> grid_reach(const Domains& dom, int r, const std::vector<double>& positions) {
  std::vector<double> reach(positions.size() / 3, 0.0);
  const std::size_t m = dom.topology.n_faces();
  std::vector<std::size_t> first(m + 1, 0);  // face f's samples from first[f]
  for (std::size_t f = 0; f < m; ++f) first[f + 1] = first[f] + face_samples(dom, r, static_cast<std::int32_t>(f));
  const int tasks = detail::task_count(m, 2048);
  detail::for_each_index(tasks > 1, tasks, m, [&](std::size_t f) {
    for_each_face_grid_link(dom, r, static_cast<std::int32_t>(f), first[f], [&](std::int32_t, std::size_t a, std::size_t b) {
      const double d = distance3(&positions[3 * a], &positions[3 * b]);
      reach[a] = std::max(reach[a], d);
      reach[b] = std::max(reach[b], d);
    });
  });
  return reach;
}

// The curves where the surface ends (the boundary, the edges of holes):
// for each face f outside the holes (in offsets[f] .. offsets[f + 1]) and
// each of its edges e with across[face_offset(f) + e] = -1, the limit
// points at 2 r + 1 evenly spaced parameters along the edge (points, 3
// each) and each one's largest distance to its neighbours along the edge
// (reach): every point of the curve lies within that of one of them, as
// every point of a face lies within grid_reach of one of its samples.
void boundary_samples(const Domains& dom, const LimitSurface& surface, int r, const std::vector<std::int32_t>& across,
                      std::vector<std::int32_t>& offsets, std::vector<double>& points, std::vector<double>& reach) {
  const std::size_t m = dom.topology.n_faces();
  const int count = 2 * r + 1;
  std::vector<std::int32_t> face_ids;
  std::vector<double> uv;
  offsets.assign(m + 1, 0);
  for (std::size_t f = 0; f < m; ++f) {
    offsets[f + 1] = offsets[f];
    if (dom.hole[f]) continue;
    const auto g = static_cast<std::int32_t>(f);
    for (std::int32_t e = 0; e < dom.topology.face_size(f); ++e) {
      if (across[static_cast<std::size_t>(dom.topology.face_offset(f) + e)] >= 0) continue;
      for (int i = 0; i < count; ++i) {
        double ab[2], p[2];
        const int c = dom.on_edge(g, e, static_cast<double>(i) / (count - 1), ab);
        dom.to_uv(g, c, ab[0], ab[1], p);
        face_ids.push_back(g);
        uv.push_back(p[0]);
        uv.push_back(p[1]);
      }
      offsets[f + 1] += count;
    }
  }
  points.resize(3 * face_ids.size());
  reach.assign(face_ids.size(), 0.0);
  if (face_ids.empty()) return;
  surface.evaluate(face_ids.data(), uv.data(), face_ids.size(), points.data(), nullptr, nullptr, nullptr);
  for (std::size_t j = 0; j < face_ids.size(); j += static_cast<std::size_t>(count))
    for (std::size_t i = j; i + 1 < j + static_cast<std::size_t>(count); ++i) {
      const double d = distance3(&points[3 * i], &points[3 * (i + 1)]);
      reach[i] = std::max(reach[i], d);
      reach[i + 1] = std::max(reach[i + 1], d);
    }
}

}  // namespace

namespace {
// A footpoint is final when its next step in (u, v) is below this (a face's
// domain has side 1): its distance is then exact to about this times the
// surface's size.
constexpr double kUvTolerance = 1e-11;
// A step below FootpointOptions::uv_tolerance ends a point's refinement when
// the decrease of the distance it predicts is below this fraction of the
// distance: the distance is then exact to about this relatively.
constexpr double kDistanceTolerance = 1e-6;
// Gauss-Newton steps at least of FootpointSearch::closer's refinements: its
// starts may lie a few grid cells from their minimum.
constexpr int kCloserSteps = 100;
// Gauss-Newton steps at least of FootpointSearch::closer's last refinement of
// each footpoint from itself: near a focal point of the surface (a point as
// far from it as its radius of curvature) Gauss-Newton converges slowly.
constexpr int kPolishSteps = 400;
// The rounding of a computed distance, in units of epsilon times the size of
// the surface point's coordinates (|p|_1 + distance).
constexpr double kRounding = 8.0;
// Points per task, at least, of refine's checks and lists of the points (a few loads and stores each).
constexpr std::size_t kPointsPerTask = 65536;
// Rows per task, at least, of FootpointSearch::closer's gathers and lists of a batch's rows.
constexpr std::size_t kRowsPerTask = 8192;

// Limit points known where the search starts (closest_points' grid samples,
// evaluated with their derivatives): point i starts at sample nearest[i],
// whose position and first derivatives are those of its (face, u, v), so
// that its first evaluation is already made (borrowed: a FootpointSearch's).
struct KnownStart {
  const std::int64_t* nearest = nullptr;
  const double *positions = nullptr, *du = nullptr, *dv = nullptr;  // per sample, (3) each
};

// One point's state in refine: the point, its current face, chart and
// local coordinates, and the best point so far (face, chart, local
// coordinates, position, derivatives, distance). Trust region: a step's
// largest (u, v) component is at most `radius`, which starts at one grid
// spacing, doubles after a step that lowers the distance and shrinks to a
// tenth of the failed step after one that does not.
struct Slot {
  double x[3];
  double ab[2], best_ab[2];
  double best_p[3], best_du[3], best_dv[3];
  double best_dist;
  double radius;
  std::size_t point;  // its index in the input
  std::int32_t face, chart, best_face, best_chart;
  int steps;           // evaluations made
  std::uint8_t fresh;  // the current point is not evaluated yet
  std::uint8_t again;  // to be taken on in the next round
  // The decrease of the distance that the Gauss-Newton model predicted for
  // the step taken last; -1 for a step the trust region cut.
  float predicted;
};

// Bfr's derivatives are approximate within the corner region of side 1/16 of
// a face's domain at an extraordinary vertex (surface.hpp: a Gregory patch),
// so that Gauss-Newton with them stops up to about 1e-5 of the face's size
// off the minimum there (distances 1e-9 of the diagonal too far). A point
// within this much of a chart's corner, in its local coordinates (twice the
// region: a sub-face of a k-gon is half the face's side), takes its
// derivatives from differences of Bfr's positions instead where refine is
// asked to be exact (FootpointSearch::closer).
constexpr double kCornerRegion = 1.0 / 8.0;
// The step of those differences in (u, v): their error is about this (the
// second derivative's term) plus epsilon over it (rounding) relative to the
// derivative.
constexpr double kDifferenceStep = 1e-7;

bool near_corner(const Domains& dom, std::int32_t f, const double* ab) {
  const Kind kind = dom.kind(f);
  const double m = kind == Kind::Sub ? 2.0 * kCornerRegion : kCornerRegion;
  const double a = ab[0], b = ab[1];
  if (kind == Kind::Triangle) {
    const double c = 1.0 - a - b;
    return (a < m && b < m) || (c < m && b < m) || (a < m && c < m);
  }
  return (a < m || a > 1.0 - m) && (b < m || b > 1.0 - m);
}

// refine_footpoints, optionally from known start points; `exact`: with
// `irregular` (per face, or null): Bfr's Surface::IsRegular() false, where
// the derivatives come from differences of positions near corners
// (kCornerRegion). The points' states
// are held in one array in face order, so that the points of the face being
// visited lie together in memory; it and the other arrays of the call are
// taken from `scratch` (null: arrays of the call's own).
void refine(const LimitSurface& surface, const Topology& topology, const double* points, std::size_t n,
            const FootpointOptions& options, Footpoints& fp, KnownStart* known,
            const std::vector<std::uint8_t>* irregular = nullptr, detail::Scratch* scratch = nullptr) {
  if (fp.face_ids.size() != n || fp.uv.size() != 2 * n)
    throw ParameterError("footpoints hold " + std::to_string(fp.face_ids.size()) + " faces and " +
                         std::to_string(fp.uv.size() / 2) + " parameters for " + std::to_string(n) + " points");
  const Domains dom(topology, surface.scheme(), surface.tags().holes);
  const auto m = static_cast<std::int32_t>(topology.n_faces());
  detail::check_each_index(n, kPointsPerTask, [&](std::size_t i) {
    if (fp.face_ids[i] < 0 || fp.face_ids[i] >= m)
      throw ParameterError("face_ids[" + std::to_string(i) + "] = " + std::to_string(fp.face_ids[i]) +
                           " is out of range [0, " + std::to_string(m) + ")");
  });
  if (!(options.uv_tolerance >= 0.0 && options.uv_tolerance < 1.0))
    throw ParameterError("uv_tolerance = " + std::to_string(options.uv_tolerance) + " must be in [0, 1)");
  detail::Scratch::Frame frame(scratch);
  // Each field set below, in parallel, where the slots are first written (so that their memory, where fresh, is
  // touched first by the tasks).
  Slot* const slots = frame.take<Slot>(n);
  // The points in the order of their starting faces (a counting sort): slot s holds point point_of[s]. Then, its
  // room reused, the slots pending (pending[0 .. n_pending)).
  std::size_t* const point_of = frame.take<std::size_t>(n);
  detail::order_by_key(fp.face_ids.data(), n, static_cast<std::size_t>(m), point_of);
  // The Gauss-Newton step at q's best point, in (u, v), within the trust
  // region: false when the point is final, else q's current point has moved
  // (fresh, possibly into another face).
  const auto step = [&](Slot& q) -> bool {
    if (q.steps > options.max_steps || q.best_dist == 0.0) return false;
    const double* x = q.x;
    const double* bp = q.best_p;
    const double* su = q.best_du;
    const double* sv = q.best_dv;
    const double br[3] = {x[0] - bp[0], x[1] - bp[1], x[2] - bp[2]};
    const double a11 = su[0] * su[0] + su[1] * su[1] + su[2] * su[2];
    const double a12 = su[0] * sv[0] + su[1] * sv[1] + su[2] * sv[2];
    const double a22 = sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2];
    const double g1 = su[0] * br[0] + su[1] * br[1] + su[2] * br[2];
    const double g2 = sv[0] * br[0] + sv[1] * br[1] + sv[2] * br[2];
    const double m11 = a11 * (1.0 + 1e-12) + 1e-300, m22 = a22 * (1.0 + 1e-12) + 1e-300;
    const double det = m11 * m22 - a12 * a12;
    if (!(det > 0.0) || !std::isfinite(det)) return false;
    double d[2] = {(m22 * g1 - a12 * g2) / det, (m11 * g2 - a12 * g1) / det};
    // Converged: a step below kUvTolerance in (u, v), or below the options'
    // uv_tolerance with a predicted decrease of the distance below
    // kDistanceTolerance of it (so that a point on the surface, whose
    // distance is all error, still converges to rounding). (Near
    // extraordinary vertices Bfr's derivatives are approximate, so the steps
    // there need not vanish: the trust region shrinks to the tolerance
    // instead.)
    const double len = std::max(std::abs(d[0]), std::abs(d[1]));
    if (!(len > kUvTolerance)) return false;
    if (len <= options.uv_tolerance && 0.5 * (g1 * d[0] + g2 * d[1]) <= kDistanceTolerance * q.best_dist * q.best_dist)
      return false;
    // The decrease of the distance that the Gauss-Newton model predicts
    // for the full step (g . d / 2 over the distance); -1 when the trust
    // region cuts the step.
    q.predicted = len > q.radius ? -1.0f : static_cast<float>(0.5 * (g1 * d[0] + g2 * d[1]) / q.best_dist);
    if (len > q.radius) d[0] *= q.radius / len, d[1] *= q.radius / len;
    q.radius = std::min(q.radius, len);  // a failure shrinks the step taken
    if (dom.kind(q.face) == Kind::Sub) d[0] *= 2.0, d[1] *= 2.0;  // local = 2 (u, v)
    std::int32_t f = q.face;
    int c = q.chart;
    if (!move(dom, f, c, q.ab, d)) return false;
    q.face = f;
    q.chart = c;
    q.fresh = 1;
    return true;
  };
  const double radius0 = 1.0 / std::max(1, options.grid > 0 ? options.grid : 4);
  const int tasks = detail::task_count(n, 16384);
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t s) {
    Slot& q = slots[s];
    const std::size_t i = q.point = point_of[s];
    std::copy_n(points + 3 * i, 3, q.x);
    q.face = q.best_face = fp.face_ids[i];
    q.chart = q.best_chart = dom.from_uv(q.face, &fp.uv[2 * i], q.ab);
    std::copy_n(q.ab, 2, q.best_ab);
    q.radius = radius0;
    q.again = 0;
    q.predicted = -1.0f;
    if (known == nullptr) {
      std::fill_n(q.best_p, 3, 0.0);
      std::fill_n(q.best_du, 3, 0.0);
      std::fill_n(q.best_dv, 3, 0.0);
      q.best_dist = std::numeric_limits<double>::infinity();
      q.steps = 0;
      q.fresh = 1;
      return;
    }
    // The first evaluation, made: as run() below takes it.
    const auto k = static_cast<std::size_t>(known->nearest[i]);
    const double* p = &known->positions[3 * k];
    const double r[3] = {q.x[0] - p[0], q.x[1] - p[1], q.x[2] - p[2]};
    q.best_dist = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    std::copy_n(p, 3, q.best_p);
    std::copy_n(&known->du[3 * k], 3, q.best_du);
    std::copy_n(&known->dv[3 * k], 3, q.best_dv);
    q.radius = std::min(2.0 * q.radius, 1.0);
    q.steps = 1;
    q.fresh = 0;
    // Its first step too: a point whose step crosses into another face is
    // then taken in that face in the first round.
    step(q);
  });
  // The inputs are in the slots now; their arrays are kept for the outputs (as are any of fp's other arrays of
  // the right size: written in place).
  // Each round visits the faces the pending points are in, and runs each
  // point's steps there (the face's patch prepared once) until the point is
  // done or crosses into another face, where the next round takes it on.
  const auto run = [&](Slot& q, std::int32_t f_visit, const LimitSurface::FaceEvaluation& evaluate) {
    const double* x = q.x;
    for (;;) {
      if (q.fresh) {
        if (q.steps > options.max_steps) return;
        ++q.steps;
        double uv[2], p[3], du[3], dv[3];
        dom.to_uv(f_visit, q.chart, q.ab[0], q.ab[1], uv);
        evaluate(uv, p, du, dv);
        if (irregular && (*irregular)[static_cast<std::size_t>(f_visit)] && near_corner(dom, f_visit, q.ab)) {
          // Forward differences, backward where the forward step would leave the chart.
          const bool tri = dom.kind(f_visit) == Kind::Triangle;
          const double h = dom.kind(f_visit) == Kind::Sub ? 0.5 * kDifferenceStep : kDifferenceStep;
          const double room_a = tri ? 1.0 - q.ab[0] - q.ab[1] : 1.0 - q.ab[0];
          const double room_b = tri ? room_a : 1.0 - q.ab[1];
          const double local = dom.kind(f_visit) == Kind::Sub ? 2.0 * h : h;
          const double hu = room_a > local ? h : -h, hv = room_b > local ? h : -h;
          double at[2] = {uv[0] + hu, uv[1]}, pu[3], pv[3], unused[6];
          evaluate(at, pu, unused, unused + 3);
          at[0] = uv[0], at[1] = uv[1] + hv;
          evaluate(at, pv, unused, unused + 3);
          for (int c = 0; c < 3; ++c) du[c] = (pu[c] - p[c]) / hu, dv[c] = (pv[c] - p[c]) / hv;
        }
        const double r[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
        const double dist = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        // A point across an edge (a hop) starts at the surface point it left:
        // as good as the best within rounding, and accepted so that the next
        // step is taken in the new face.
        const double scale = std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]) + q.best_dist;
        const bool hopped = (f_visit != q.best_face || q.chart != q.best_chart) && dist <= q.best_dist + 1e-12 * scale;
        if (dist < q.best_dist || hopped) {
          q.best_dist = dist;
          std::copy_n(p, 3, q.best_p);
          std::copy_n(du, 3, q.best_du);
          std::copy_n(dv, 3, q.best_dv);
          q.best_face = f_visit;
          q.best_chart = q.chart;
          std::copy_n(q.ab, 2, q.best_ab);
          q.radius = std::min(2.0 * q.radius, 1.0);
        } else {
          // No better: back to the best point, a smaller region.
          q.radius *= 0.1;
          q.face = q.best_face;
          q.chart = q.best_chart;
          std::copy_n(q.best_ab, 2, q.ab);
          if (q.radius < kUvTolerance) return;
          // A failed full Gauss-Newton step whose predicted decrease of the
          // distance is within the distance's rounding: a shorter step's
          // decrease would be rounding too, so the best point is final.
          if (q.predicted >= 0.0f && q.predicted <= kRounding * std::numeric_limits<double>::epsilon() * scale) return;
          if (q.best_face != f_visit) {  // the best is in another face: the next round steps from there
            q.fresh = 0;
            q.again = 1;
            return;
          }
        }
      }
      if (!step(q)) return;
      if (q.face != f_visit) {  // across an edge: the next round
        q.again = 1;
        return;
      }
    }
  };
  std::size_t* const pending = point_of;
  std::size_t* const staging = frame.take<std::size_t>(n);  // keep_in_order's
  std::size_t n_pending = detail::keep_in_order(
      n, kPointsPerTask, [&](std::size_t s) { return slots[s].fresh != 0; }, [](std::size_t s) { return s; }, staging,
      pending);
  std::int32_t* const pending_faces = frame.take<std::int32_t>(n);
  while (n_pending > 0) {
    const int gather_tasks = detail::task_count(n_pending, kPointsPerTask);
    detail::for_each_index(gather_tasks > 1, gather_tasks, n_pending,
                           [&](std::size_t j) { pending_faces[j] = slots[pending[j]].face; });
    surface.visit_faces(pending_faces, n_pending,
                        [&](std::int32_t f_visit, const std::size_t* first, const std::size_t* last,
                            const LimitSurface::FaceEvaluation& evaluate) {
                          for (const std::size_t* it = first; it != last; ++it)
                            run(slots[pending[*it]], f_visit, evaluate);
                        });
    n_pending = detail::keep_in_order(
        n_pending, kPointsPerTask,
        [&](std::size_t j) {
          Slot& q = slots[pending[j]];
          const bool again = q.again != 0;
          q.again = 0;
          return again;
        },
        [&](std::size_t j) { return pending[j]; }, staging, pending);
    poll_interrupt();
  }
  // Back in input order, at the best points.
  fp.face_ids.resize(n);
  fp.uv.resize(2 * n);
  fp.positions.resize(3 * n);
  fp.distances.resize(n);
  fp.normals.resize(3 * n);
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t s) {
    const Slot& q = slots[s];
    const std::size_t i = q.point;
    fp.face_ids[i] = q.best_face;
    dom.to_uv(q.best_face, q.best_chart, q.best_ab[0], q.best_ab[1], &fp.uv[2 * i]);
    std::copy_n(q.best_p, 3, &fp.positions[3 * i]);
    fp.distances[i] = q.best_dist;
    detail::unit_normal(q.best_du, q.best_dv, &fp.normals[3 * i]);
  });
}

}  // namespace

FootpointSearch::FootpointSearch(const LimitSurface& surface, const Topology& topology,
                                 const FootpointOptions& options, FootpointSearch* previous)
    : surface_(&surface), topology_(&topology), options_(options) {
  if (options.grid < 1 || options.grid > 64)
    throw ParameterError("grid must be in 1..64, got " + std::to_string(options.grid));
  const Domains dom(topology, surface.scheme(), surface.tags().holes);
  const bool reuse = previous != nullptr && previous->index_ && previous->topology_ == &topology &&
                     previous->options_.grid == options.grid;
  if (reuse) {
    sample_faces_ = std::move(previous->sample_faces_);
    sample_uv_ = std::move(previous->sample_uv_);
    irregular_ = std::move(previous->irregular_);
  } else {
    grid_samples(dom, options.grid, sample_faces_, sample_uv_);
  }
  if (sample_faces_.empty()) throw ParameterError("the surface has no face outside its holes");
  const std::size_t k = sample_faces_.size();
  positions_.resize(3 * k);
  du_.resize(3 * k);
  dv_.resize(3 * k);
  surface.evaluate(sample_faces_.data(), sample_uv_.data(), k, positions_.data(), du_.data(), dv_.data(), nullptr);
  reach_ = grid_reach(dom, options.grid, positions_);
  largest_reach_ = *std::max_element(reach_.begin(), reach_.end());
  if (reuse) {
    index_ = std::move(previous->index_);
    index_->refit(positions_.data());
  } else {
    index_ = std::make_unique<PointIndex>(positions_.data(), k);
  }
  index_->set_slack(reach_.data());  // closer's candidates: |x - s| - reach(s) < d
  if (previous != nullptr) previous->retire();
  if (reuse) return;
  // Bfr's regularity of each face (holes: regular, never searched).
  std::vector<std::int32_t> faces;
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(topology.n_faces()); ++f)
    if (!dom.hole[static_cast<std::size_t>(f)]) faces.push_back(f);
  const std::vector<std::uint8_t> regular = surface.control_points(faces.data(), faces.size()).regular;
  irregular_.assign(topology.n_faces(), 0);
  for (std::size_t i = 0; i < faces.size(); ++i) irregular_[static_cast<std::size_t>(faces[i])] = !regular[i];
}

void FootpointSearch::retire() {
  std::vector<double>().swap(positions_);
  std::vector<double>().swap(du_);
  std::vector<double>().swap(dv_);
  std::vector<double>().swap(reach_);
  if (index_) index_->release_points();
  certificate_.reset();
}

FootpointSearch::~FootpointSearch() = default;

namespace {
// closer's certificate (footpoints.hpp): the curvature bound per face is this
// times the samples' largest angle between normals over distance (the chord
// estimate misses curvature between samples).
constexpr double kCertifySafety = 4.0;
// The largest angle of the star's normals from the axis x - p (below a right
// angle: the star projects onto the plane across the axis without folding).
constexpr double kCertifyStarTilt = 1.3962634015954636;  // 80 degrees
// The largest angle of the normals near the footpoint (within sqrt(2) d of
// it) from the axis: the graph's slope there is at most 1.
constexpr double kCertifyTilt = 0.7853981633974483;  // 45 degrees
// The largest distance times curvature bound (convexity needs it below
// 1 / (4 2^1.5) = 0.177).
constexpr double kCertifyCurvature = 0.1;
// The star's rim lies farther than this times the distance from the
// footpoint (sqrt(2) times the distance, the lift of the disk, with room).
constexpr double kCertifyRim = 4.0;
}  // namespace

struct FootpointSearch::Certificate {
  // Per face: the faces outside holes sharing a vertex with it (its star,
  // sorted) and those outside the star sharing a vertex with a face of the
  // star (its rim); both empty where the face is never certified.
  std::vector<std::int32_t> star_offsets, star, rim_offsets, rim;
  std::vector<double> axis;       // per face (3): the unit axis of a cone holding its normals
  std::vector<double> half;       // per face: the cone's half-angle
  std::vector<double> cone_cos;   // per face: cos(kCertifyStarTilt - half), above 1 where half exceeds it
  std::vector<double> curvature;  // per face: the bound of its normal curvature
  std::vector<double> ball;       // per face (4): centre and radius of a ball holding its surface
  // Per face f: its near samples near[near_offsets[f] .. near_offsets[f + 1])
  // and its clearance, a lower bound of |p - s| - reach(s) over the points p
  // of the face and the samples s outside its star other than its near
  // samples (0 where the face is never certified). Where the clearance is
  // at least 2 d, no such sample passes the candidates' bound
  // |x - s| - reach(s) < d for a point x at distance d from a footpoint p in
  // the face, since |x - s| >= |p - s| - d: the near samples are the only
  // candidates outside the star, and need no query.
  std::vector<std::int32_t> near_offsets;
  std::vector<std::int64_t> near;
  std::vector<double> clearance;
  std::vector<std::size_t> samples;  // per face + 1: its grid samples are [samples[f], samples[f + 1])
  // Per half-edge (Topology::face_offset(f) + e): the face across it, -1
  // where the surface ends there (the boundary, a hole).
  std::vector<std::int32_t> across, face_offsets;  // face_offsets: per face + 1, Topology::face_offset
  // Per face f: samples edge_points[3 j..] and edge_reach[j], j in
  // [edge_offsets[f], edge_offsets[f + 1]), of the curves where the surface
  // ends along f's edges (boundary_samples): each such curve lies within
  // edge_reach[j] of one of its samples j.
  std::vector<std::int32_t> edge_offsets;
  std::vector<double> edge_points, edge_reach;
  // Per face f, its star at once (shortcuts of the tests on each face of
  // the star, below): star_axis (3) and star_cos, a cone holding the cones
  // of the star's faces (angle(star_axis, axis[g]) + half[g] <= H for each
  // g, star_cos = cos(kCertifyStarTilt - H), above 1 where H exceeds it,
  // so that z within kCertifyStarTilt - H of star_axis passes every face's
  // test); star_curvature, the largest curvature bound of the star;
  // star_ends, whether the surface ends along an edge of the star; and
  // rim_clear, a lower bound of |o - s| - reach(s) over the samples s of
  // the rim (o: f's ball's centre), so that a point p has no point of the
  // rim within rim_clear - |p - o| of it.
  std::vector<double> star_axis, star_cos, star_curvature, rim_clear;
  std::vector<std::uint8_t> star_ends;

  bool in_star(std::int32_t f, std::int32_t g) const {
    const auto first = star.begin() + star_offsets[static_cast<std::size_t>(f)];
    const auto last = star.begin() + star_offsets[static_cast<std::size_t>(f) + 1];
    return std::binary_search(first, last, g);
  }

  // Whether point x, at distance d > 0 from its footpoint p in face f (unit
  // normal n there, or null), is certified (footpoints.hpp,
  // FootpointSearch::closer).
  bool certifies(std::int32_t f, const double* x, const double* p, const double* n, double d,
                 const double* positions, const double* reach) const {
    const auto fs = static_cast<std::size_t>(f);
    if (!(d > 0.0) || star_offsets[fs] == star_offsets[fs + 1]) return false;
    const double z[3] = {(x[0] - p[0]) / d, (x[1] - p[1]) / d, (x[2] - p[2]) / d};
    // The normals' side of the axis, and the angle of p's normal from it
    // (without a normal: the cone of p's face bounds it).
    const double* a = &axis[3 * fs];
    const double* along = n != nullptr ? n : a;
    const double c_p = along[0] * z[0] + along[1] * z[1] + along[2] * z[2];
    const double sign = c_p < 0.0 ? -1.0 : 1.0;
    const double tilt = std::acos(std::min(std::abs(c_p), 1.0)) + (n != nullptr ? 0.0 : half[fs]);
    // Whether face g's surface (within reach(s) of its samples s) lies
    // farther than kCertifyRim d from p: its ball first, then where that is
    // too near, the samples.
    const double rim_d = kCertifyRim * d;
    const auto far = [&](std::size_t g) {
      const double* o = &ball[4 * g];
      if (distance3(p, o) - o[3] > rim_d) return true;
      for (std::size_t s = samples[g]; s < samples[g + 1]; ++s) {
        const double* q = &positions[3 * s];
        const double e = reach[s] + rim_d;
        if (!((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]) > e * e))
          return false;
      }
      return true;
    };
    // Face g's normals within the cone round z, and the curves where the
    // surface ends along its edges farther than kCertifyRim d from p.
    const auto holds = [&](std::size_t g) {
      const double* b = &axis[3 * g];
      if (!(sign * (b[0] * z[0] + b[1] * z[1] + b[2] * z[2]) >= cone_cos[g])) return false;
      for (std::int32_t j = edge_offsets[g]; j < edge_offsets[g + 1]; ++j)
        if (!(distance3(p, &edge_points[3 * static_cast<std::size_t>(j)]) - edge_reach[static_cast<std::size_t>(j)] >
              rim_d))
          return false;
      return true;
    };
    const auto bounded = [&](double kappa) {
      return d * kappa <= kCertifyCurvature && tilt + 1.4142135623730951 * d * kappa <= kCertifyTilt;
    };
    // N: the whole star where each of its faces holds and none ends (a
    // star without ends is joined to f round f's vertices), else its faces
    // not far from p (linked[k] for star[k]), joined to f across their edges.
    const std::int32_t first = star_offsets[fs], size = star_offsets[fs + 1] - first;
    const double* sa = &star_axis[3 * fs];
    bool whole = !star_ends[fs];
    double kappa = star_curvature[fs];
    if (whole && !(sign * (sa[0] * z[0] + sa[1] * z[1] + sa[2] * z[2]) >= star_cos[fs]))
      for (std::int32_t k = 0; k < size && whole; ++k)
        whole = holds(static_cast<std::size_t>(star[static_cast<std::size_t>(first + k)]));
    if (!whole || !bounded(kappa)) {
      thread_local std::vector<std::uint8_t> linked;  // per star face: 1 near p, 2 joined to f
      thread_local std::vector<std::int32_t> stack;
      linked.assign(static_cast<std::size_t>(size), 0);
      kappa = 0.0;
      std::int32_t listed = 0;
      for (std::int32_t k = 0; k < size; ++k) {
        const auto g = static_cast<std::size_t>(star[static_cast<std::size_t>(first + k)]);
        if (g != fs && far(g)) continue;
        if (!holds(g)) return false;
        kappa = std::max(kappa, curvature[g]);
        linked[static_cast<std::size_t>(k)] = 1;
        ++listed;
      }
      if (!bounded(kappa)) return false;
      // Joined to f (2 on those reached, f's first).
      const auto index_of = [&](std::int32_t g) {
        const auto from = star.begin() + first, to = star.begin() + first + size;
        const auto it = std::lower_bound(from, to, g);
        return it != to && *it == g ? static_cast<std::int32_t>(it - from) : -1;
      };
      linked[static_cast<std::size_t>(index_of(f))] = 2;
      stack.assign(1, f);
      std::int32_t joined = 1;
      while (!stack.empty() && joined < listed) {
        const auto g = static_cast<std::size_t>(stack.back());
        stack.pop_back();
        for (std::int32_t h = face_offsets[g]; h < face_offsets[g + 1]; ++h) {
          const std::int32_t next = across[static_cast<std::size_t>(h)];
          const std::int32_t k = next < 0 ? -1 : index_of(next);
          if (k < 0 || linked[static_cast<std::size_t>(k)] != 1) continue;
          linked[static_cast<std::size_t>(k)] = 2;
          ++joined;
          stack.push_back(next);
        }
      }
      if (joined < listed) return false;
    }
    // The rim's surface lies farther than kCertifyRim d from p.
    if (rim_clear[fs] - distance3(p, &ball[4 * fs]) > rim_d) return true;
    for (std::int32_t k = rim_offsets[fs]; k < rim_offsets[fs + 1]; ++k)
      if (!far(static_cast<std::size_t>(rim[static_cast<std::size_t>(k)]))) return false;
    return true;
  }
};

const FootpointSearch::Certificate& FootpointSearch::certificate() const {
  std::call_once(certificate_once_, [&] {
    auto cert = std::make_unique<Certificate>();
    const Topology& t = *topology_;
    const Tags& tags = surface_->tags();
    const Domains dom(t, surface_->scheme(), tags.holes);
    const std::size_t m = t.n_faces(), nv = t.n_vertices();
    const std::vector<std::int32_t>& corners = t.face_indices();
    // The samples of each face (grid_samples gives them face after face).
    std::vector<std::size_t> first(m + 1, 0);
    for (const std::int32_t f : sample_faces_) ++first[static_cast<std::size_t>(f) + 1];
    for (std::size_t f = 0; f < m; ++f) first[f + 1] += first[f];
    const std::size_t k = sample_faces_.size();
    std::vector<double> normal(3 * k);
    for (std::size_t s = 0; s < k; ++s) detail::unit_normal(&du_[3 * s], &dv_[3 * s], &normal[3 * s]);
    // Curvature: the largest angle between neighbouring samples' normals over
    // their distance; and the largest spacing.
    std::vector<double> bend(m, 0.0), spacing(m, 0.0);
    for_each_grid_link(dom, options_.grid, [&](std::int32_t f, std::size_t a, std::size_t b) {
      const double* na = &normal[3 * a];
      const double* nb = &normal[3 * b];
      const double c = na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2];
      const double len = distance3(&positions_[3 * a], &positions_[3 * b]);
      const auto fs = static_cast<std::size_t>(f);
      bend[fs] = std::max(bend[fs], len > 0.0 ? std::acos(std::clamp(c, -1.0, 1.0)) / len
                                              : std::numeric_limits<double>::infinity());
      spacing[fs] = std::max(spacing[fs], len);
    });
    cert->axis.assign(3 * m, 0.0);
    cert->half.assign(m, std::numeric_limits<double>::infinity());
    cert->cone_cos.assign(m, 2.0);
    cert->curvature.assign(m, std::numeric_limits<double>::infinity());
    cert->ball.assign(4 * m, 0.0);
    for (std::size_t f = 0; f < m; ++f) {
      if (first[f] == first[f + 1]) continue;  // a hole
      double* a = &cert->axis[3 * f];
      double* o = &cert->ball[4 * f];
      bool zero = false;
      for (std::size_t s = first[f]; s < first[f + 1]; ++s)
        for (int c = 0; c < 3; ++c) {
          a[c] += normal[3 * s + c];
          o[c] += positions_[3 * s + c] / static_cast<double>(first[f + 1] - first[f]);
          zero = zero || (normal[3 * s] == 0.0 && normal[3 * s + 1] == 0.0 && normal[3 * s + 2] == 0.0);
        }
      const double len = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      double half = 0.0;
      for (std::size_t s = first[f]; s < first[f + 1]; ++s) {
        const double* n = &normal[3 * s];
        const double c = len > 0.0 ? (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / len : -1.0;
        half = std::max(half, std::acos(std::clamp(c, -1.0, 1.0)));
        o[3] = std::max(o[3], distance3(&positions_[3 * s], o) + reach_[s]);
      }
      for (int c = 0; c < 3; ++c) a[c] = len > 0.0 ? a[c] / len : 0.0;
      cert->curvature[f] = kCertifySafety * bend[f];
      // A point of the face lies within about spacing / sqrt(3) of a sample,
      // where its normal is within that distance times the curvature bound.
      if (!zero && len > 0.0) cert->half[f] = half + 0.6 * cert->curvature[f] * spacing[f];
      cert->cone_cos[f] = cert->half[f] <= kCertifyStarTilt ? std::cos(kCertifyStarTilt - cert->half[f]) : 2.0;
    }
    // Vertices where the surface is smooth (up to the boundary or a hole
    // where it ends there): on no crease and no corner of any sharpness.
    std::vector<std::int32_t> vf_offsets(nv + 1, 0), vf;
    for (const std::int32_t v : corners) ++vf_offsets[static_cast<std::size_t>(v) + 1];
    for (std::size_t v = 0; v < nv; ++v) vf_offsets[v + 1] += vf_offsets[v];
    vf.resize(corners.size());
    {
      std::vector<std::int32_t> fill(vf_offsets.begin(), vf_offsets.end() - 1);
      for (std::size_t f = 0; f < m; ++f)
        for (std::int32_t c = 0; c < t.face_size(f); ++c)
          vf[static_cast<std::size_t>(fill[static_cast<std::size_t>(corners[static_cast<std::size_t>(t.face_offset(f) + c)])]++)] =
              static_cast<std::int32_t>(f);
    }
    std::vector<std::uint8_t> smooth(nv, 1);
    for (std::size_t v = 0; v < nv; ++v) smooth[v] = !t.is_unreferenced(v);
    for (std::size_t c = 0; c < tags.n_creases(); ++c)
      if (tags.crease_sharpness[c] > 0.0)
        smooth[static_cast<std::size_t>(tags.crease_vertices[2 * c])] =
            smooth[static_cast<std::size_t>(tags.crease_vertices[2 * c + 1])] = 0;
    for (std::size_t c = 0; c < tags.n_corners(); ++c)
      if (tags.corner_sharpness[c] > 0.0) smooth[static_cast<std::size_t>(tags.corner_vertices[c])] = 0;
    // Across each half-edge the face there, -1 where the surface ends (the
    // boundary, a hole); and the curves where it ends, sampled along each
    // such edge of a face that is not a hole.
    cert->face_offsets = t.face_offsets();
    cert->across.assign(corners.size(), -1);
    for (std::size_t h = 0; h < corners.size(); ++h) {
      const std::int32_t o = dom.opposite[h];
      const std::int32_t g = o < 0 ? -1 : dom.half_edge_face[static_cast<std::size_t>(o)];
      if (g >= 0 && !dom.hole[static_cast<std::size_t>(g)]) cert->across[h] = g;
    }
    boundary_samples(dom, *surface_, options_.grid, cert->across, cert->edge_offsets, cert->edge_points,
                     cert->edge_reach);
    // Each face's star (sorted) and rim (left empty where the face is not
    // certified): the faces at its vertices, then those at its star's
    // vertices, each listed once (mark[g] = f + 1 once listed in f's star,
    // -(f + 1) in its rim), for a range of faces per task.
    const int tasks = detail::task_count(m, 4096);
    struct Lists {
      std::vector<std::int32_t> star_sizes, star, rim_sizes, rim;
    };
    std::vector<Lists> lists(static_cast<std::size_t>(tasks));
    detail::for_each_range(tasks > 1, tasks, m, [&](int task, std::size_t from, std::size_t to) {
      Lists& out = lists[static_cast<std::size_t>(task)];
      std::vector<std::int64_t> mark(m, 0);
      // Appends the faces at g's vertices (not holes) not marked `in` or
      // `out_mark`, marking them `in`; false where a vertex is not smooth.
      const auto faces_at = [&](std::size_t g, std::int64_t in, std::int64_t out_mark, std::vector<std::int32_t>& list) {
        bool ok = true;
        for (std::int32_t c = 0; c < t.face_size(g); ++c) {
          const auto v = static_cast<std::size_t>(corners[static_cast<std::size_t>(t.face_offset(g) + c)]);
          ok = ok && smooth[v];
          for (std::int32_t k = vf_offsets[v]; k < vf_offsets[v + 1]; ++k) {
            const auto h = static_cast<std::size_t>(vf[static_cast<std::size_t>(k)]);
            if (dom.hole[h] || mark[h] == in || mark[h] == out_mark) continue;
            mark[h] = in;
            list.push_back(static_cast<std::int32_t>(h));
          }
        }
        return ok;
      };
      for (std::size_t f = from; f < to; ++f) {
        const std::size_t star_at = out.star.size(), rim_at = out.rim.size();
        const auto in = static_cast<std::int64_t>(f) + 1;
        bool ok = first[f] != first[f + 1] && faces_at(f, in, in, out.star);
        for (std::size_t k = star_at; ok && k < out.star.size(); ++k) {
          const auto g = static_cast<std::size_t>(out.star[k]);
          ok = std::isfinite(cert->half[g]) && faces_at(g, -in, in, out.rim);
        }
        if (!ok) {
          out.star.resize(star_at);
          out.rim.resize(rim_at);
        }
        std::sort(out.star.begin() + static_cast<std::ptrdiff_t>(star_at), out.star.end());
        out.star_sizes.push_back(static_cast<std::int32_t>(out.star.size() - star_at));
        out.rim_sizes.push_back(static_cast<std::int32_t>(out.rim.size() - rim_at));
      }
    });
    const auto flatten = [&](std::vector<std::int32_t> Lists::*sizes, std::vector<std::int32_t> Lists::*list,
                             std::vector<std::int32_t>& offsets, std::vector<std::int32_t>& flat) {
      offsets.assign(1, 0);
      for (Lists& l : lists) {
        for (const std::int32_t k : l.*sizes) offsets.push_back(offsets.back() + k);
        flat.insert(flat.end(), (l.*list).begin(), (l.*list).end());
        std::vector<std::int32_t>().swap(l.*list);
      }
    };
    flatten(&Lists::star_sizes, &Lists::star, cert->star_offsets, cert->star);
    flatten(&Lists::rim_sizes, &Lists::rim, cert->rim_offsets, cert->rim);
    cert->samples = std::move(first);
    // Each star at once (Certificate::star_axis ..., rim_clear).
    cert->star_axis.assign(3 * m, 0.0);
    cert->star_cos.assign(m, 2.0);
    cert->star_curvature.assign(m, 0.0);
    cert->star_ends.assign(m, 1);
    cert->rim_clear.assign(m, -std::numeric_limits<double>::infinity());
    detail::for_each_index(tasks > 1, tasks, m, [&](std::size_t f) {
      const std::int32_t from = cert->star_offsets[f], to = cert->star_offsets[f + 1];
      if (from == to) return;
      double* a = &cert->star_axis[3 * f];
      bool ends = false;
      double kappa = 0.0;
      for (std::int32_t k = from; k < to; ++k) {
        const auto g = static_cast<std::size_t>(cert->star[static_cast<std::size_t>(k)]);
        for (int c = 0; c < 3; ++c) a[c] += cert->axis[3 * g + c];
        ends = ends || cert->edge_offsets[g] != cert->edge_offsets[g + 1];
        kappa = std::max(kappa, cert->curvature[g]);
      }
      const double len = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      double wide = len > 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
      for (int c = 0; c < 3; ++c) a[c] = len > 0.0 ? a[c] / len : 0.0;
      for (std::int32_t k = from; k < to && len > 0.0; ++k) {
        const auto g = static_cast<std::size_t>(cert->star[static_cast<std::size_t>(k)]);
        const double* b = &cert->axis[3 * g];
        wide = std::max(wide, std::acos(std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0)) + cert->half[g]);
      }
      // (A rounding's margin: the shortcut never passes where a face's own test would not.)
      wide += 1e-12;
      cert->star_cos[f] = wide <= kCertifyStarTilt ? std::cos(kCertifyStarTilt - wide) : 2.0;
      cert->star_curvature[f] = kappa;
      cert->star_ends[f] = ends;
      const double* o = &cert->ball[4 * f];
      double clear = std::numeric_limits<double>::infinity();
      for (std::int32_t k = cert->rim_offsets[f]; k < cert->rim_offsets[f + 1]; ++k) {
        const auto g = static_cast<std::size_t>(cert->rim[static_cast<std::size_t>(k)]);
        const double* og = &cert->ball[4 * g];
        if (!(distance3(o, og) - og[3] < clear)) continue;  // its samples s: |o - s| - reach(s) >= |o - og| - r_g
        for (std::size_t t = cert->samples[g]; t < cert->samples[g + 1]; ++t)
          clear = std::min(clear, distance3(o, &positions_[3 * t]) - reach_[t]);
      }
      cert->rim_clear[f] = clear;
    });
    // Each face's clearance and near samples: a point p of the face lies
    // within reach(t) of one of its samples t, so that a sample s outside
    // the star has |p - s| - reach(s) >= |t - s| - reach(t) - reach(s) for
    // some t. The samples s whose least such bound over t is below
    // kClearance r (r the face's ball's radius) are its near samples; the
    // clearance bounds it below for the others. The balls (o, r) hold their
    // face's samples widened by their reach (|o - t| + reach(t) <= r), so
    // that the samples of a face g have the bound at least
    // |o_f - o_g| - r_f - r_g: a query over the balls' centres finds the
    // faces g outside the star below (1 + kClearance) r_f of it, and of
    // their samples those with |o_f - s| - reach(s) - r_f below the
    // clearance are compared with each sample t.
    constexpr double kClearance = 0.1;
    constexpr std::size_t kClearanceFaces = 64;
    std::vector<std::int32_t> ball_face;
    std::vector<double> centre, radius;
    for (std::size_t f = 0; f < m; ++f)
      if (cert->samples[f] != cert->samples[f + 1]) {
        ball_face.push_back(static_cast<std::int32_t>(f));
        centre.insert(centre.end(), &cert->ball[4 * f], &cert->ball[4 * f] + 3);
        radius.push_back(cert->ball[4 * f + 3]);
      }
    PointIndex balls(centre.data(), ball_face.size());
    balls.set_slack(radius.data());
    const double largest_radius = *std::max_element(radius.begin(), radius.end());
    cert->clearance.assign(m, 0.0);
    std::vector<std::vector<std::int64_t>> near_lists(m);
    detail::for_each_index(tasks > 1, tasks, m, [&](std::size_t f) {
      if (cert->star_offsets[f] == cert->star_offsets[f + 1]) return;
      const double* o = &cert->ball[4 * f];
      const double r = o[3];
      const auto g = static_cast<std::int32_t>(f);
      const auto rank = [&](std::int64_t b, double dist) {
        const std::int32_t h = ball_face[static_cast<std::size_t>(b)];
        return cert->in_star(g, h) ? std::numeric_limits<double>::infinity()
                                   : dist - radius[static_cast<std::size_t>(b)];
      };
      std::int64_t near[kClearanceFaces];
      double least[kClearanceFaces];
      const std::size_t found =
          balls.least_ranked(o, (1.0 + kClearance) * r, largest_radius, kClearanceFaces, rank, near, least);
      const double clear = found == kClearanceFaces ? std::min(least[found - 1] - r, kClearance * r) : kClearance * r;
      if (!(clear > 0.0)) return;
      std::vector<std::int64_t>& list = near_lists[f];
      const std::vector<std::size_t>& first = cert->samples;
      for (std::size_t j = 0; j < found && least[j] - r < clear; ++j) {
        const auto h = static_cast<std::size_t>(ball_face[static_cast<std::size_t>(near[j])]);
        for (std::size_t s = first[h]; s < first[h + 1]; ++s) {
          if (!(distance3(o, &positions_[3 * s]) - reach_[s] - r < clear)) continue;
          for (std::size_t t = first[f]; t < first[f + 1]; ++t)
            if (distance3(&positions_[3 * t], &positions_[3 * s]) - reach_[t] - reach_[s] < clear) {
              list.push_back(static_cast<std::int64_t>(s));
              break;
            }
        }
      }
      cert->clearance[f] = clear;
    });
    cert->near_offsets.assign(m + 1, 0);
    for (std::size_t f = 0; f < m; ++f)
      cert->near_offsets[f + 1] = cert->near_offsets[f] + static_cast<std::int32_t>(near_lists[f].size());
    cert->near.reserve(static_cast<std::size_t>(cert->near_offsets[m]));
    for (const auto& list : near_lists) cert->near.insert(cert->near.end(), list.begin(), list.end());
    certificate_ = std::move(cert);
  });
  return *certificate_;
}

Footpoints FootpointSearch::find(const double* points, std::size_t n, detail::Scratch* scratch) const {
  Footpoints fp;
  fp.face_ids.resize(n);
  fp.uv.resize(2 * n);
  detail::Scratch::Frame frame(scratch);
  std::int64_t* const nearest = frame.take<std::int64_t>(n);
  index_->nearest(points, n, nearest, frame.take<double>(n));
  const int tasks = detail::task_count(n, kPointsPerTask);
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t i) {
    const auto s = static_cast<std::size_t>(nearest[i]);
    fp.face_ids[i] = sample_faces_[s];
    fp.uv[2 * i] = sample_uv_[2 * s];
    fp.uv[2 * i + 1] = sample_uv_[2 * s + 1];
  });
  KnownStart known{nearest, positions_.data(), du_.data(), dv_.data()};
  refine(*surface_, *topology_, points, n, options_, fp, &known, nullptr, &frame.scratch());
  return fp;
}

std::size_t FootpointSearch::closer(const double* points, std::size_t n, Footpoints& fp, bool found,
                                    std::size_t* certified, std::size_t* listed) const {
  if (certified != nullptr) *certified = 0;
  if (listed != nullptr) *listed = 0;
  if (fp.face_ids.size() != n || fp.uv.size() != 2 * n || fp.distances.size() != n)
    throw ParameterError("footpoints hold " + std::to_string(fp.face_ids.size()) + " faces, " +
                         std::to_string(fp.uv.size() / 2) + " parameters and " + std::to_string(fp.distances.size()) +
                         " distances for " + std::to_string(n) + " points");
  const auto m = static_cast<std::int32_t>(topology_->n_faces());
  detail::check_each_index(n, kPointsPerTask, [&](std::size_t i) {
    if (fp.face_ids[i] < 0 || fp.face_ids[i] >= m)
      throw ParameterError("face_ids[" + std::to_string(i) + "] = " + std::to_string(fp.face_ids[i]) +
                           " is out of range [0, " + std::to_string(m) + ")");
  });
  const auto starts = static_cast<std::size_t>(std::max(options_.starts, 0));
  if (n == 0 || starts == 0) return 0;
  const bool has_positions = fp.positions.size() == 3 * n, has_normals = fp.normals.size() == 3 * n;
  const Certificate* cert = options_.certify ? &certificate() : nullptr;
  FootpointOptions options = options_;
  options.max_steps = std::max(options.max_steps, kCloserSteps);
  std::size_t moved = 0;
  // In batches of points, so that the starts' states stay within a bounded
  // memory.
  constexpr std::size_t kBatch = 65536;
  std::vector<std::int64_t> candidate(kBatch * (starts + 1));
  std::vector<double> candidate_rank(kBatch * starts);
  std::vector<std::size_t> count(kBatch);
  std::vector<std::int64_t> nearest_sample(kBatch);
  std::vector<double> nearest_distance(kBatch);
  FootpointOptions polishing = options_;
  polishing.max_steps = std::max(options_.max_steps, kPolishSteps);
  // Replaces point i's footpoint by row r of `from` where that is closer.
  const auto take = [&](std::size_t i, const Footpoints& from, std::size_t r) {
    if (!(from.distances[r] < fp.distances[i])) return false;
    fp.face_ids[i] = from.face_ids[r];
    fp.uv[2 * i] = from.uv[2 * r];
    fp.uv[2 * i + 1] = from.uv[2 * r + 1];
    fp.distances[i] = from.distances[r];
    if (has_positions) std::copy_n(&from.positions[3 * r], 3, &fp.positions[3 * i]);
    if (has_normals) std::copy_n(&from.normals[3 * r], 3, &fp.normals[3 * i]);
    return true;
  };
  // Refines the footpoints of points first + rows[r] from themselves, to
  // the minimum (find and refine stop after max_steps, the starts after
  // kCloserSteps, and near corners with Bfr's derivatives: a step or two
  // where one is there already), each taken where closer; `again` holds the
  // results (row r: its point's footpoint, or where not taken, the point
  // the refinement ended at).
  const auto polish = [&](std::size_t first, const std::vector<std::size_t>& rows, Footpoints& again,
                          std::vector<std::uint8_t>& changed) {
    const std::size_t k = rows.size();
    if (k == 0) return;
    std::vector<double> y(3 * k);
    again.face_ids.resize(k);
    again.uv.resize(2 * k);
    const int tasks = detail::task_count(k, kRowsPerTask);
    detail::for_each_index(tasks > 1, tasks, k, [&](std::size_t r) {
      const std::size_t i = first + rows[r];
      std::copy_n(points + 3 * i, 3, &y[3 * r]);
      again.face_ids[r] = fp.face_ids[i];
      std::copy_n(&fp.uv[2 * i], 2, &again.uv[2 * r]);
    });
    refine(*surface_, *topology_, y.data(), k, polishing, again, nullptr, &irregular_);
    detail::for_each_index(tasks > 1, tasks, k, [&](std::size_t r) {
      if (take(first + rows[r], again, r)) changed[rows[r]] = 1;
    });
  };
  std::vector<std::uint8_t> changed(kBatch), skipped(kBatch), started(kBatch);
  for (std::size_t first = 0; first < n; first += kBatch) {
    poll_interrupt();
    const std::size_t b = std::min(kBatch, n - first);
    const int tasks = detail::task_count(b, 4096);
    // Each footpoint off its point refined from itself first: the
    // certificate's p (and its normal) is then the polished footpoint, as
    // that refinement evaluated it (-1 in polished_row where it ended
    // elsewhere at no smaller distance, a hop across an edge: not
    // certified).
    std::fill_n(changed.begin(), b, std::uint8_t{0});
    // The rows j of the batch with keep(j), in order.
    std::vector<std::size_t> staging(b);
    const auto rows_where = [&](auto keep) {
      std::vector<std::size_t> out(b);
      out.resize(detail::keep_in_order(b, kRowsPerTask, keep, [](std::size_t j) { return j; }, staging.data(),
                                       out.data()));
      return out;
    };
    std::vector<std::size_t> again_row = rows_where([&](std::size_t j) { return fp.distances[first + j] > 0.0; });
    Footpoints polished;
    polish(first, again_row, polished, changed);
    std::vector<std::int64_t> polished_row(b, -1);
    const int again_tasks = detail::task_count(again_row.size(), kRowsPerTask);
    detail::for_each_index(again_tasks > 1, again_tasks, again_row.size(), [&](std::size_t r) {
      const std::size_t i = first + again_row[r];
      if (fp.face_ids[i] == polished.face_ids[r] && fp.uv[2 * i] == polished.uv[2 * r] &&
          fp.uv[2 * i + 1] == polished.uv[2 * r + 1])
        polished_row[again_row[r]] = static_cast<std::int64_t>(r);
    });
    // In the points' spatial order, so that the queries find the tree's
    // nodes and the faces' certificates in cache.
    const std::vector<std::size_t> order = detail::spatial_order(points + 3 * first, b);
    // The nearest sample: find's start (left out where the footpoints are
    // find's) and the reach that `near` scales; for near = 0, only for the
    // points that take candidates from a query (below), and where the
    // footpoints are find's, only for those the certificate leaves with
    // every start.
    const bool all_nearest = options_.near > 0.0;
    if (all_nearest) index_->nearest(points + 3 * first, b, nearest_sample.data(), nearest_distance.data());
    // Re-searched: a point not within a fraction of its nearest sample's
    // reach of its footpoint (every point off the surface for near = 0).
    const auto off = [&](std::size_t j) {
      const double d = fp.distances[first + j];
      return d > 0.0 &&
             (options_.near > 0.0 ? d > options_.near * reach_[static_cast<std::size_t>(nearest_sample[j])] : true);
    };
    std::fill_n(skipped.begin(), b, std::uint8_t{0});
    if (cert != nullptr)
      detail::for_each_index(tasks > 1, tasks, b, [&](std::size_t o) {
        const std::size_t j = order[o], i = first + j;
        const auto r = static_cast<std::size_t>(polished_row[j]);
        skipped[j] = off(j) && polished_row[j] >= 0 &&
                     cert->certifies(fp.face_ids[i], points + 3 * i, &polished.positions[3 * r],
                                     &polished.normals[3 * r], fp.distances[i], positions_.data(), reach_.data());
      });
    // A certified point whose face's clearance is at least 2 d: its
    // candidates are its face's near samples that pass the bound (its
    // nearest sample, in the star or outside it, holds no closer point
    // than those: see the contract).
    const auto listed_by_clearance = [&](std::size_t j) {
      return skipped[j] && cert->clearance[static_cast<std::size_t>(fp.face_ids[first + j])] >= 2.0 * fp.distances[first + j];
    };
    if (!all_nearest) {
      // The rows that take candidates from a query, in the points' spatial order.
      std::vector<std::size_t> rest(b);
      rest.resize(detail::keep_in_order(
          b, kRowsPerTask,
          [&](std::size_t o) {
            const std::size_t j = order[o];
            if (off(j) && !listed_by_clearance(j) && !(found && skipped[j])) return true;
            nearest_sample[j] = -1;
            return false;
          },
          [&](std::size_t o) { return order[o]; }, staging.data(), rest.data()));
      std::vector<double> y(3 * rest.size()), unused(rest.size());
      std::vector<std::int64_t> near(rest.size());
      const int rest_tasks = detail::task_count(rest.size(), kRowsPerTask);
      detail::for_each_index(rest_tasks > 1, rest_tasks, rest.size(),
                             [&](std::size_t r) { std::copy_n(points + 3 * (first + rest[r]), 3, &y[3 * r]); });
      if (!rest.empty()) index_->nearest(y.data(), rest.size(), near.data(), unused.data());
      detail::for_each_index(rest_tasks > 1, rest_tasks, rest.size(),
                             [&](std::size_t r) { nearest_sample[rest[r]] = near[r]; });
    }
    detail::for_each_index(tasks > 1, tasks, b, [&](std::size_t o) {
      const std::size_t j = order[o];
      const std::size_t i = first + j;
      const double* x = points + 3 * i;
      const double d = fp.distances[i];
      // The nearest sample, as find starts (its footpoint may be another
      // than the one given), and for a point re-searched, the samples whose
      // cells may hold a point closer than d: |x - s| - reach(s) < d, the
      // least of that lower bound first; none of the star of the
      // footpoint's face where the certificate holds.
      std::int64_t* c = &candidate[j * (starts + 1)];
      c[0] = nearest_sample[j];
      const std::int32_t f = fp.face_ids[i];
      const bool skip = skipped[j] != 0;
      const bool nearest_too =
          c[0] >= 0 && d > 0.0 && !found && !(skip && cert->in_star(f, sample_faces_[static_cast<std::size_t>(c[0])]));
      count[j] = nearest_too ? 1 : 0;
      if (!off(j)) return;
      double* value = &candidate_rank[j * starts];
      std::size_t m = 0;
      if (listed_by_clearance(j)) {
        // The near samples below the bound, least first (as the query
        // would take them).
        const auto fs = static_cast<std::size_t>(f);
        for (auto k = static_cast<std::size_t>(cert->near_offsets[fs]); k < static_cast<std::size_t>(cert->near_offsets[fs + 1]); ++k) {
          const std::int64_t s = cert->near[k];
          const double r = distance3(x, &positions_[3 * static_cast<std::size_t>(s)]) - reach_[static_cast<std::size_t>(s)];
          if (!(r < d) || (m == starts && !(r < value[m - 1]))) continue;
          std::int64_t* taken = c + 1;
          std::size_t at = m < starts ? m++ : m - 1;
          for (; at > 0 && r < value[at - 1]; --at) value[at] = value[at - 1], taken[at] = taken[at - 1];
          value[at] = r;
          taken[at] = s;
        }
      } else {
        const auto rank = [&](std::int64_t s, double dist) {
          return s == c[0] || (skip && cert->in_star(f, sample_faces_[static_cast<std::size_t>(s)]))
                     ? std::numeric_limits<double>::infinity()
                     : dist - reach_[static_cast<std::size_t>(s)];
        };
        m = index_->least_ranked(x, d, largest_reach_, starts, rank, c + 1, value);
      }
      if (!nearest_too) std::copy_n(c + 1, m, c);
      count[j] += m;
    });
    if (certified != nullptr)
      for (std::size_t j = 0; j < b; ++j) *certified += skipped[j];
    if (listed != nullptr)
      for (std::size_t j = 0; j < b; ++j) *listed += off(j) && listed_by_clearance(j);
    // The starts, one row each: the point repeated, refined from its sample.
    std::vector<std::size_t> row(b + 1, 0);
    for (std::size_t j = 0; j < b; ++j) row[j + 1] = row[j] + count[j];
    const std::size_t rows = row[b];
    std::fill_n(started.begin(), b, std::uint8_t{0});
    if (rows > 0) {
      std::vector<double> x(3 * rows);
      std::vector<std::int64_t> nearest(rows);
      Footpoints trial;
      trial.face_ids.resize(rows);
      trial.uv.resize(2 * rows);
      detail::for_each_index(tasks > 1, tasks, b, [&](std::size_t j) {
        for (std::size_t c = 0; c < count[j]; ++c) {
          const std::size_t r = row[j] + c;
          const auto s = static_cast<std::size_t>(candidate[j * (starts + 1) + c]);
          std::copy_n(points + 3 * (first + j), 3, &x[3 * r]);
          nearest[r] = static_cast<std::int64_t>(s);
          trial.face_ids[r] = sample_faces_[s];
          trial.uv[2 * r] = sample_uv_[2 * s];
          trial.uv[2 * r + 1] = sample_uv_[2 * s + 1];
        }
      });
      KnownStart known{nearest.data(), positions_.data(), du_.data(), dv_.data()};
      refine(*surface_, *topology_, x.data(), rows, options, trial, &known, &irregular_);
      // The closest of each point's results, where closer than its footpoint
      // (the first of equals).
      detail::for_each_index(tasks > 1, tasks, b, [&](std::size_t j) {
        if (count[j] == 0) return;
        std::size_t best = row[j];
        for (std::size_t r = row[j] + 1; r < row[j + 1]; ++r)
          if (trial.distances[r] < trial.distances[best]) best = r;
        if (take(first + j, trial, best)) changed[j] = started[j] = 1;
      });
    }
    // The footpoints a start moved refined again from themselves.
    again_row = rows_where([&](std::size_t j) { return started[j] != 0; });
    Footpoints again;
    polish(first, again_row, again, changed);
    for (std::size_t j = 0; j < b; ++j) moved += changed[j];
  }
  return moved;
}

Footpoints closest_points(const LimitSurface& surface, const Topology& topology, const double* points, std::size_t n,
                          const FootpointOptions& options) {
  return FootpointSearch(surface, topology, options).find(points, n);
}

void refine_footpoints(const LimitSurface& surface, const Topology& topology, const double* points, std::size_t n,
                       const FootpointOptions& options, Footpoints& fp, detail::Scratch* scratch) {
  refine(surface, topology, points, n, options, fp, nullptr, nullptr, scratch);
}

}  // namespace sorpia
