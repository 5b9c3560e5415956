// The names of the subdivision rules and the checks of the sharpness tags
// that need no topology.
#include "sorpia/subdivision.hpp"

#include <cmath>
#include <string>

#include "sorpia/detail/repr.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

Scheme parse_scheme(const std::string& name) {
  for (Scheme s : {Scheme::Loop, Scheme::CatmullClark})
    if (name == scheme_name(s)) return s;
  throw ParameterError("unknown scheme '" + name + "': use one of 'loop', 'catmull-clark'");
}

const char* scheme_name(Scheme scheme) { return scheme == Scheme::Loop ? "loop" : "catmull-clark"; }

Boundary parse_boundary(const std::string& name) {
  for (Boundary b : {Boundary::EdgeAndCorner, Boundary::EdgeOnly})
    if (name == boundary_name(b)) return b;
  throw ParameterError("unknown boundary '" + name + "': use one of 'edge-and-corner', 'edge-only'");
}

const char* boundary_name(Boundary boundary) {
  return boundary == Boundary::EdgeOnly ? "edge-only" : "edge-and-corner";
}

double Tags::max_semi_sharpness() const {
  double out = 0.0;
  for (const auto* list : {&crease_sharpness, &corner_sharpness})
    for (double s : *list)
      if (s < kInfiniteSharpness && s > out) out = s;
  return out;
}

namespace {

std::string index_list(const std::int32_t* p, std::size_t k) {
  std::string s = "[";
  for (std::size_t j = 0; j < k; ++j) s += (j ? ", " : "") + std::to_string(p[j]);
  return s + "]";
}

void check_sharpness(const std::vector<double>& sharpness, const char* name) {
  for (std::size_t i = 0; i < sharpness.size(); ++i)
    if (std::isnan(sharpness[i]) || sharpness[i] < 0.0)
      throw MeshError(std::string(name) + " sharpness[" + std::to_string(i) + "] = " + detail::repr(sharpness[i]) +
                      ": a sharpness is a number >= 0 (inf or >= " + detail::repr(kInfiniteSharpness) +
                      ": infinitely sharp)");
}

void check_indices(const std::int32_t* p, std::size_t n_rows, std::size_t width, std::size_t bound,
                   const char* name, const char* what) {
  for (std::size_t i = 0; i < n_rows; ++i)
    for (std::size_t j = 0; j < width; ++j) {
      const std::int32_t v = p[i * width + j];
      if (v < 0 || static_cast<std::size_t>(v) >= bound)
        throw MeshError(std::string(name) + "[" + std::to_string(i) + "] = " + index_list(p + i * width, width) +
                        " has " + what + " index " + std::to_string(v) + " out of range [0, " +
                        std::to_string(bound) + ")");
    }
}

}  // namespace

void check_tags(const Tags& tags, std::size_t n_vertices, std::size_t n_faces) {
  if (tags.crease_vertices.size() != 2 * tags.crease_sharpness.size())
    throw MeshError("creases: " + std::to_string(tags.crease_vertices.size() / 2) + " edges but " +
                    std::to_string(tags.crease_sharpness.size()) + " sharpness values");
  if (tags.corner_vertices.size() != tags.corner_sharpness.size())
    throw MeshError("corners: " + std::to_string(tags.corner_vertices.size()) + " vertices but " +
                    std::to_string(tags.corner_sharpness.size()) + " sharpness values");
  check_indices(tags.crease_vertices.data(), tags.n_creases(), 2, n_vertices, "creases", "vertex");
  for (std::size_t i = 0; i < tags.n_creases(); ++i)
    if (tags.crease_vertices[2 * i] == tags.crease_vertices[2 * i + 1])
      throw MeshError("creases[" + std::to_string(i) + "] = " + index_list(&tags.crease_vertices[2 * i], 2) +
                      ": a crease edge joins two distinct vertices");
  check_indices(tags.corner_vertices.data(), tags.n_corners(), 1, n_vertices, "corners", "vertex");
  check_indices(tags.holes.data(), tags.holes.size(), 1, n_faces, "holes", "face");
  check_sharpness(tags.crease_sharpness, "creases");
  check_sharpness(tags.corner_sharpness, "corners");
}

}  // namespace sorpia
