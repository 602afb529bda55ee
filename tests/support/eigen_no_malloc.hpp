#pragma once
// Forbids Eigen's heap allocations for its lifetime, where the build arms
// Eigen's check (EIGEN_RUNTIME_NO_MALLOC: RTFUSE_EIGEN_NO_MALLOC_CHECK, on
// whenever the tests are built). The one place that names Eigen's switch, so
// a test compiles in every configuration: a bare call fails to compile where
// the check is not armed, which is how a default build once broke.
#include <Eigen/Core>

namespace rtfuse::test {

class EigenMallocForbidden {
 public:
  EigenMallocForbidden() {
#ifdef EIGEN_RUNTIME_NO_MALLOC
    Eigen::internal::set_is_malloc_allowed(false);
#endif
  }
  ~EigenMallocForbidden() {
#ifdef EIGEN_RUNTIME_NO_MALLOC
    Eigen::internal::set_is_malloc_allowed(true);
#endif
  }
  EigenMallocForbidden(const EigenMallocForbidden&) = delete;
  EigenMallocForbidden& operator=(const EigenMallocForbidden&) = delete;
};

}  // namespace rtfuse::test
