#pragma once
// Counts every heap allocation of the process (malloc, calloc, realloc; operator new and Eigen
// go through them): alloc_counter.cpp replaces them in the allocation-test program
// (tests/CMakeLists.txt; not under the sanitizers, which replace malloc themselves).

namespace rubdyn::testing {

/// Heap allocations since the program started.
long allocations();

}  // namespace rubdyn::testing
