#pragma once
/// @file reference.hpp
/// Reference builds of the limit matrix B from OpenSubdiv's own Far::Limit(),
/// for the tests only (the library sorpia_reference, built with
/// SORPIA_BUILD_TESTS, and the test-only module sorpia._reference): the
/// independent computation the production build (sorpia::limit_operator,
/// from Sdc's limit masks and local refinement) is checked against.

#include "sorpia/limit.hpp"

namespace sorpia {

/// Reference, for tests: B recorded from OpenSubdiv's
/// Far::PrimvarRefinerReal<double>::Limit on an unrefined Loop
/// Far::TopologyRefiner (the explicit zero weights OpenSubdiv gives interior
/// neighbours of boundary vertices dropped; identity rows for unreferenced
/// vertices). limit_matrix must equal it to rounding. It builds a refiner,
/// which costs several times limit_matrix.
CsrMatrix reference_limit_matrix(const Topology& topology, Boundary boundary);

/// Reference, for tests: B of the whole mesh with its sharpness tags, from
/// one Far::TopologyRefiner of the whole mesh refined uniformly until every
/// semi-sharp tag has decayed (ceil of the largest finite sharpness, after
/// repeated tags are resolved as OpenSubdiv resolves them: the last counts),
/// and for Catmull-Clark at least once when a face is not a quad (Limit() on
/// an unrefined level would treat an n-gon as a quad),
/// PrimvarRefinerReal<double>::Interpolate level by level and Limit() on the
/// last level, composed back to the control vertices (identity rows for
/// unreferenced vertices). limit_matrix(topology, rules) must equal it to
/// rounding. Its cost grows as 4^levels.
/// @throw MeshError naming the first crease that is not an edge of the mesh
CsrMatrix reference_limit_matrix(const Topology& topology, const Rules& rules);

/// Reference, for tests: B V evaluated by Far::PrimvarRefinerReal<double>::Limit (Loop).
void reference_limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out);

}  // namespace sorpia
