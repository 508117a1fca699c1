// The K-contact solver (rubdyn/contact/contact_set.hpp) allocates nothing in solve(): its
// workspaces are sized when it is built. Checked by counting every heap allocation of the
// process (malloc, calloc, realloc; operator new and Eigen go through them) around solves of
// every kind: enumeration for K = 1..4 with each outcome, Gauss-Seidel for K = 8, the first-guess
// path. Part of the allocation-test program (tests/CMakeLists.txt; the counter: alloc_counter.hpp).

#include <catch2/catch.hpp>
#include <cstddef>
#include <vector>

#include "alloc/alloc_counter.hpp"
#include "rubdyn/contact/contact_set.hpp"

using namespace rubdyn;

TEST_CASE("No allocation in the K-contact solver: enumeration and Gauss-Seidel", "[alloc]") {
  // problems built before counting: W = a coupled SPD matrix, u0 closing every contact; the
  // contacts' friction and sliding chosen so that several outcomes occur
  const int K_max = 8;
  ContactSetSolver solver(K_max);
  std::vector<Mat> Ws;
  std::vector<Vec> us;
  std::vector<std::vector<SetContact>> cs;
  for (int K = 1; K <= K_max; ++K) {
    Mat W = Mat::Identity(2 * K, 2 * K) * 2.0;
    for (int i = 0; i + 1 < 2 * K; ++i) W(i, i + 1) = W(i + 1, i) = 0.4;
    Vec u0 = Vec::Constant(2 * K, -1.0);
    std::vector<SetContact> c(K);
    for (int i = 0; i < K; ++i) c[i] = {0.1 + 0.6 * (i % 3), i % 4 == 3 ? 1 : 0, {}};
    Ws.push_back(W);
    us.push_back(u0);
    cs.push_back(c);
  }
  // a Painleve-inconsistent contact (the kernel's example, sliding +1 while closing)
  Mat Wp = Mat::Zero(4, 4);
  Wp(0, 0) = Wp(1, 1) = 1.0;
  Wp.bottomRightCorner(2, 2) << 1, 2, 2, 5;
  Vec up(4);
  up << -1, 0, -1, 0;
  std::vector<SetContact> cp = {{0.5, 0, {}}, {1.0, 1, {}}};
  const std::vector<Phase> stick(2, Phase::Stick), open(2, Phase::Free);  // guesses
  long outcomes = 0;
  const long before = rubdyn::testing::allocations();
  for (int K = 1; K <= K_max; ++K) {
    const SetBand band = contact_set_band(Ws[K - 1], us[K - 1]);
    outcomes += static_cast<int>(solver.solve(Ws[K - 1], us[K - 1], cs[K - 1], band));
    if (K <= kMaxEnumContacts)
      outcomes +=
          static_cast<int>(solver.solve(Ws[K - 1], us[K - 1], cs[K - 1], band, SetMethod::Pgs));
  }
  outcomes += static_cast<int>(solver.solve(Wp, up, cp, contact_set_band(Wp, up)));
  outcomes += static_cast<int>(solver.solve(Wp, up, cp, contact_set_band(Wp, up), SetMethod::Pgs));
  // a block of a larger matrix and a segment of a longer vector, as a caller with fewer active
  // contacts than its workspace would pass them
  outcomes += static_cast<int>(
      solver.solve(Ws[3].topLeftCorner(4, 4), us[3].head(4), std::span(cs[3]).first(2),
                   contact_set_band(Ws[3].topLeftCorner(4, 4), us[3].head(4))));
  // the first-guess path (Moreau-Jean's): the certificate, a guess taken and one refused
  {
    const SetBand band = contact_set_band(Ws[1], us[1]);
    outcomes += unique_by_monotonicity(Ws[1], cs[1]) ? 1 : 0;
    outcomes += static_cast<int>(solver.solve_guess(Ws[1], us[1], cs[1], band, stick));
    outcomes += static_cast<int>(solver.solve_guess(Ws[1], us[1], cs[1], band, open));
  }
  const long n = rubdyn::testing::allocations() - before;
  INFO("allocations " << n << " (outcomes " << outcomes << ")");
  CHECK(n == 0);
  // the counter counts: building a solver allocates its workspaces
  const long before_build = rubdyn::testing::allocations();
  { ContactSetSolver other(2); }
  CHECK(rubdyn::testing::allocations() > before_build);
}
