#pragma once
// RUBDYN_DEMAND(cond): a broken invariant is a bug. It prints the condition, function, file and
// line on stderr and aborts. It is never used for bad input (see io/case_error.hpp) nor for
// numerical trouble during a run (see core/run_types.hpp, Termination).
#include <cstdio>
#include <cstdlib>

#define RUBDYN_DEMAND(cond)                                                                     \
  do {                                                                                          \
    if (!(cond)) {                                                                              \
      std::fprintf(stderr, "rubdyn: internal error: demand '%s' failed in %s (%s:%d)\n", #cond, \
                   __func__, __FILE__, __LINE__);                                               \
      std::abort();                                                                             \
    }                                                                                           \
  } while (false)
