#pragma once
// The two OpenMP run-time calls the core makes, in a form that also builds
// without OpenMP (CMake option SORPIA_OPENMP=OFF, or no OpenMP found): the
// `#pragma omp` lines are then ignored, every parallel region runs on the
// calling thread alone, and these report one thread. Not a public header.
#ifdef _OPENMP
#include <omp.h>
#endif

namespace sorpia {
namespace detail {

// Whether parallel regions really run on several threads.
constexpr bool kOpenMP =
#ifdef _OPENMP
    true;
#else
    false;
#endif

// The number of the calling thread in the current parallel region (0 outside one).
inline int thread_number() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

// The threads a parallel region would get by default.
inline int default_thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

}  // namespace detail
}  // namespace sorpia
