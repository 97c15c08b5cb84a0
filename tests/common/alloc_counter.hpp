// Counts every heap allocation of the process while armed (malloc, calloc, realloc, aligned
// variants; operator new and Eigen both go through them). Link alloc_counter.cpp into a test
// executable to interpose the allocator. Eigen's own EIGEN_RUNTIME_NO_MALLOC guard is an
// eigen_assert, compiled out in Release builds, so this counter is what the tests rely on.
#pragma once

#include <cstddef>

namespace lexdyn::test {

void allocCounterArm();
/// Disarms and returns the number of allocations since allocCounterArm().
std::size_t allocCounterDisarm();

/// RAII: counts allocations in its scope.
class AllocationScope {
 public:
  AllocationScope() { allocCounterArm(); }
  std::size_t finish() {
    done_ = true;
    return allocCounterDisarm();
  }
  ~AllocationScope() {
    if (!done_) allocCounterDisarm();
  }

 private:
  bool done_ = false;
};

}  // namespace lexdyn::test
