#include "sorpia/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "openmesh_types.hpp"
#include "sorpia/cage.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {
namespace {
constexpr double kPi = 3.14159265358979323846;

void check(bool ok, const std::string& what) {
  if (!ok) throw ParameterError(what);
}
}  // namespace

Mesh icosphere(int level) {
  check(level >= 0 && level <= 10, "icosphere level must be in 0..10, got " + std::to_string(level));
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  m.vertices = {-1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t,
                0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t, 0, -1, -t, 0, 1};
  m.face_vertex_indices = {0, 11, 5, 0, 5,  1,  0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
             4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3, 4,  2,  3, 2, 6, 3,
             6, 8,  3, 8,  9,  4,  9, 5, 2, 4, 11, 6,  2, 10, 8, 6,  7, 9, 8, 1};
  auto normalise = [&](std::size_t v) {
    double* p = &m.vertices[3 * v];
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int k = 0; k < 3; ++k) p[k] /= r;
  };
  for (std::size_t v = 0; v < 12; ++v) normalise(v);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const int v = static_cast<int>(m.n_vertices());
      for (int k = 0; k < 3; ++k) m.vertices.push_back(0.5 * (m.vertices[3 * a + k] + m.vertices[3 * b + k]));
      normalise(v);
      mid.emplace(key, v);
      return v;
    };
    std::vector<std::int32_t> faces;
    faces.reserve(4 * m.face_vertex_indices.size());
    for (std::size_t f = 0; f < m.n_faces(); ++f) {
      const std::int32_t* t = m.face_vertex_indices.data() + 3 * f;
      const int a = t[0], b = t[1], c = t[2];
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      faces.insert(faces.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.face_vertex_indices.swap(faces);
  }
  return m;
}

Mesh torus(int nu, int nv) {
  check(nu >= 3 && nv >= 3, "torus needs at least 3 x 3 vertices, got " + std::to_string(nu) + " x " +
                                std::to_string(nv));
  Mesh m;
  m.vertices.reserve(3 * static_cast<std::size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.insert(m.vertices.end(),
                        {(1 + 0.4 * std::cos(v)) * std::cos(u), (1 + 0.4 * std::cos(v)) * std::sin(u), 0.4 * std::sin(v)});
    }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  m.face_vertex_indices.reserve(6 * static_cast<std::size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.face_vertex_indices.insert(m.face_vertex_indices.end(), {a, b, c, a, c, d});
    }
  return m;
}

Mesh grid(int nu, int nv) {
  check(nu >= 2 && nv >= 2, "grid needs at least 2 x 2 vertices, got " + std::to_string(nu) + " x " +
                                std::to_string(nv));
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double x = static_cast<double>(i) / (nu - 1), y = static_cast<double>(j) / (nv - 1);
      m.vertices.insert(m.vertices.end(), {x, y, 0.1 * std::sin(2 * kPi * x) * std::cos(2 * kPi * y)});
    }
  for (int i = 0; i + 1 < nu; ++i)
    for (int j = 0; j + 1 < nv; ++j) {
      const int a = i * nv + j, b = (i + 1) * nv + j, c = (i + 1) * nv + j + 1, d = i * nv + j + 1;
      m.face_vertex_indices.insert(m.face_vertex_indices.end(), {a, b, c, a, c, d});
    }
  return m;
}

Mesh pole(int n) {
  check(n >= 3, "pole valence must be at least 3, got " + std::to_string(n));
  Mesh m;
  m.vertices = {0, 0, 0.3};
  for (int r = 1; r <= 2; ++r)
    for (int k = 0; k < n; ++k) {
      const double a = 2 * kPi * (k + 0.5 * (r - 1)) / n;
      m.vertices.insert(m.vertices.end(), {r * std::cos(a), r * std::sin(a), 0.3 / (1 + r * r)});
    }
  auto ring = [&](int r, int k) { return 1 + (r - 1) * n + (k % n); };
  std::vector<std::int32_t>& idx = m.face_vertex_indices;
  for (int k = 0; k < n; ++k) idx.insert(idx.end(), {0, ring(1, k), ring(1, k + 1)});
  for (int k = 0; k < n; ++k) {
    idx.insert(idx.end(), {ring(1, k), ring(2, k), ring(1, k + 1)});
    idx.insert(idx.end(), {ring(1, k + 1), ring(2, k), ring(2, k + 1)});
  }
  return m;
}

Mesh irregular(int n_vertices, std::uint32_t seed) {
  check(n_vertices >= 16, "irregular needs at least 16 vertices, got " + std::to_string(n_vertices));
  const int nv = std::max(4, static_cast<int>(std::sqrt(n_vertices / 2.5)));
  const int nu = std::max(4, n_vertices / nv);
  Mesh m = torus(nu, nv);

  detail::silence_openmesh();
  detail::OMesh mesh;
  std::vector<detail::OMesh::VertexHandle> vh;
  for (std::size_t v = 0; v < m.n_vertices(); ++v)
    vh.push_back(mesh.add_vertex(detail::OMesh::Point(m.vertices[3 * v], m.vertices[3 * v + 1], m.vertices[3 * v + 2])));
  for (std::size_t f = 0; f < m.n_faces(); ++f)
    mesh.add_face(vh[m.face_vertex_indices[3 * f]], vh[m.face_vertex_indices[3 * f + 1]],
                  vh[m.face_vertex_indices[3 * f + 2]]);

  // Flip about a third of the edges at random, keeping every valence in 3..12.
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(mesh.n_edges()) - 1);
  const std::size_t flips = mesh.n_edges() / 3;
  for (std::size_t k = 0; k < flips; ++k) {
    const auto eh = mesh.edge_handle(pick(rng));
    if (!mesh.is_flip_ok(eh)) continue;
    const auto h0 = mesh.halfedge_handle(eh, 0), h1 = mesh.halfedge_handle(eh, 1);
    const auto a = mesh.to_vertex_handle(h0), b = mesh.to_vertex_handle(h1);
    const auto c = mesh.to_vertex_handle(mesh.next_halfedge_handle(h0));
    const auto d = mesh.to_vertex_handle(mesh.next_halfedge_handle(h1));
    if (mesh.valence(a) <= 3 || mesh.valence(b) <= 3 || mesh.valence(c) >= 12 || mesh.valence(d) >= 12) continue;
    mesh.flip(eh);
  }
  m.face_vertex_indices.clear();
  for (const auto fh : mesh.faces())
    for (const auto v : mesh.fv_range(fh)) m.face_vertex_indices.push_back(v.idx());
  return m;
}

namespace {
// The quads (a, b, c, d) of the vertex grid of torus(nu, nv) (wrapped) or
// grid(nu, nv) (not), counter-clockwise as their triangles (a, b, c), (a, c, d).
Mesh quads_of(Mesh tri) {
  Mesh m;
  m.vertices = std::move(tri.vertices);
  for (std::size_t f = 0; f < tri.n_faces(); f += 2) {
    const std::int32_t* t = tri.face_vertex_indices.data() + 3 * f;
    m.face_vertex_indices.insert(m.face_vertex_indices.end(), {t[0], t[1], t[2], t[5]});
    m.face_vertex_counts.push_back(4);
  }
  return m;
}
}  // namespace

Mesh quad_torus(int nu, int nv) { return quads_of(torus(nu, nv)); }

Mesh quad_grid(int nu, int nv) { return quads_of(grid(nu, nv)); }

Mesh quad_irregular(int n_vertices, std::uint32_t seed) {
  check(n_vertices >= 96, "quad_irregular needs at least 96 vertices, got " + std::to_string(n_vertices));
  Mesh m = quads_from_triangles(irregular(n_vertices / 6, seed));
  // Number the vertices in the order the faces first reach them, as a mesh
  // exported from a modeller would be: the triangle mesh's own vertices
  // otherwise all come before the points added between them.
  std::vector<std::int32_t> renumber(m.n_vertices(), -1);
  std::int32_t next = 0;
  for (std::int32_t& v : m.face_vertex_indices) {
    if (renumber[v] < 0) renumber[v] = next++;
    v = renumber[v];
  }
  std::vector<double> moved(m.vertices.size());
  for (std::size_t v = 0; v < renumber.size(); ++v)
    std::copy_n(&m.vertices[3 * v], 3, &moved[3 * static_cast<std::size_t>(renumber[v])]);
  m.vertices.swap(moved);
  return m;
}

Mesh polygon_torus(int nu, int nv, std::uint32_t seed) {
  check(nu >= 4 && nv >= 4, "polygon_torus needs at least 4 x 4 vertices, got " + std::to_string(nu) + " x " +
                                std::to_string(nv));
  Mesh m;
  m.vertices = torus(nu, nv).vertices;
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  std::vector<std::uint8_t> used(static_cast<std::size_t>(nu) * nv, 0), joined(used.size(), 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const auto face = [&](std::initializer_list<std::int32_t> vs) {
    m.face_vertex_counts.push_back(static_cast<std::int32_t>(vs.size()));
    m.face_vertex_indices.insert(m.face_vertex_indices.end(), vs);
  };
  // A quad is joined only with its neighbour i + 1 < nu (never across the
  // wrap), which no earlier quad has used.
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      if (used[i * nv + j]) continue;
      used[i * nv + j] = 1;
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      const double r = u01(rng);
      // Two joins stacked in one column would leave the vertex between them
      // with two edges, an interior vertex of valence 2 (whose limit masks
      // make B indefinite): a join needs its column's neighbours unjoined.
      const bool right_free = i + 1 < nu && !used[(i + 1) * nv + j] && !joined[i * nv + (j + nv - 1) % nv] &&
                              !joined[i * nv + (j + 1) % nv];
      if (r < 0.10) {
        face({a, b, c});
        face({a, c, d});
      } else if (r < 0.24 && right_free) {
        used[(i + 1) * nv + j] = 1;
        joined[i * nv + j] = 1;
        const int e = id(i + 2, j), f = id(i + 2, j + 1);
        if (r < 0.17) {  // the neighbour's half (b, f, c) joined: a pentagon and a triangle
          face({a, b, f, c, d});
          face({b, e, f});
        } else {  // the whole neighbour (b, e, f, c): a hexagon
          face({a, b, e, f, c, d});
        }
      } else {
        face({a, b, c, d});
      }
    }
  return m;
}

}  // namespace sorpia
