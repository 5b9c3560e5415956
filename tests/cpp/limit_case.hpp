#pragma once
// A test mesh with its limit matrix B (OpenSubdiv's Far Limit(),
// edge-and-corner boundary) and B in the solvers' compact form.
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace sorpia_test {

struct LimitCase {
  const char* name;
  sorpia::TriMesh mesh;
  sorpia::CsrMatrix b;
  sorpia::LimitOperator op;
};

inline LimitCase limit_case(const sorpia::TriMesh& m, const char* name = "") {
  const sorpia::Topology topo(m.faces.data(), m.n_faces(), m.n_vertices());
  LimitCase c{name, m, sorpia::limit_matrix(topo, sorpia::Boundary::EdgeAndCorner), {}};
  c.op = sorpia::limit_operator(c.b);
  return c;
}

}  // namespace sorpia_test
