#pragma once
// OpenMesh types used inside the core (never in a public header).
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace sorpia::detail {

// Double-precision points: TriMesh_ArrayKernelT<> stores Vec3f, which would
// round every coordinate to float32.
struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;
using OPolyMesh = OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits>;

// OpenMesh logs to stdout/stderr on every read, write and failed add_face;
// sorpia reports errors itself.
void silence_openmesh();

}  // namespace sorpia::detail
