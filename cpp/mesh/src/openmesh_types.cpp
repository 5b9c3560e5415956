#include "openmesh_types.hpp"

#include <OpenMesh/Core/System/omstream.hh>

#include <mutex>

namespace sorpia::detail {

void silence_openmesh() {
  static std::once_flag once;
  std::call_once(once, [] {
    omlog().disable();
    omout().disable();
    omerr().disable();
  });
}

}  // namespace sorpia::detail
