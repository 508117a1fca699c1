#pragma once
// The state of the contacts in the event-driven engine: one mode per contact (the hybrid state
// is their tuple: one contact is the smallest case), sets of contacts as bit masks, and the
// witnesses of a phase (what ends it) with the one rule of their scaling.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <span>

#include "decision_tolerances.hpp"
#include "rubdyn/core/run_types.hpp"

namespace rubdyn::detail {

inline bool closed(Phase p) {
  return p != Phase::Free;
}
inline bool slipping(Phase p) {
  return p == Phase::SlipPos || p == Phase::SlipNeg;
}
/// The slip direction s of a slip mode (F_T = -mu s F_N).
inline int slip_sign(Phase p) {
  return p == Phase::SlipPos ? 1 : -1;
}

/// A set of contacts (indices below kMaxContacts), one bit each.
class ContactSet {
 public:
  constexpr ContactSet() = default;
  static constexpr ContactSet of(int k) {
    ContactSet s;
    s.set(k);
    return s;
  }
  constexpr void set(int k, bool on = true) {
    if (on) {
      bits_ |= bit(k);
    } else {
      bits_ &= ~bit(k);
    }
  }
  constexpr void reset(int k) { bits_ &= ~bit(k); }
  constexpr bool test(int k) const { return (bits_ & bit(k)) != 0; }
  constexpr bool any() const { return bits_ != 0; }
  constexpr bool none() const { return bits_ == 0; }
  constexpr int count() const { return std::popcount(bits_); }
  constexpr void clear() { bits_ = 0; }
  constexpr ContactSet operator|(ContactSet o) const { return from(bits_ | o.bits_); }
  constexpr ContactSet operator&(ContactSet o) const { return from(bits_ & o.bits_); }
  constexpr ContactSet minus(ContactSet o) const { return from(bits_ & ~o.bits_); }
  constexpr bool operator==(const ContactSet&) const = default;

 private:
  static_assert(kMaxContacts <= 32);
  static constexpr std::uint32_t bit(int k) { return std::uint32_t{1} << k; }
  static constexpr ContactSet from(std::uint32_t b) {
    ContactSet s;
    s.bits_ = b;
    return s;
  }
  std::uint32_t bits_ = 0;
};

/// The modes of the K contacts.
struct Modes {
  int K = 0;
  std::array<Phase, kMaxContacts> p{};  // every contact free
  Phase& operator[](int k) { return p[static_cast<std::size_t>(k)]; }
  Phase operator[](int k) const { return p[static_cast<std::size_t>(k)]; }
  std::span<const Phase> span() const { return {p.data(), static_cast<std::size_t>(K)}; }
  bool any_closed() const { return closed_set().any(); }
  ContactSet closed_set() const {
    ContactSet s;
    for (int k = 0; k < K; ++k) s.set(k, closed(p[static_cast<std::size_t>(k)]));
    return s;
  }
  /// The phase the books (phase_time, phase_steps) count: the first closed contact's mode.
  Phase books() const {
    for (int k = 0; k < K; ++k)
      if (closed(p[static_cast<std::size_t>(k)])) return p[static_cast<std::size_t>(k)];
    return Phase::Free;
  }
  bool operator==(const Modes&) const = default;
};

/// What ends a phase (event_driven.hpp lists them per mode).
enum class Witness { Gap, GapRate, NormalForce, SlipSpeed, ConeUpper, ConeLower, Omega };
const char* witness_name(Witness w);

/// One witness: its kind and its contact (-1: omega).
struct WitnessRef {
  Witness w = Witness::Gap;
  int k = -1;
};

/// How the witnesses of contacts that have just switched start. A session's witnesses are fixed
/// from its restart to its next one (CVODE's root arrays are set up only at a restart: changed
/// in the middle of an integration, they would be compared with values never computed); what
/// changes between steps is only how some of them are evaluated:
///   gap_banded:    free, after leaving the constraint: the onset witness is d_N + graze_tol until
///                  the gap exceeds graze_tol (then d_N; both positive at the switch);
///   rate_deferred: free, after a release: the gap-minimum witness is the constant 1 until v_N
///                  exceeds v_tol (then v_N / v_ref; both positive at the switch);
///   slip_banded:   slip that starts from rest (v_t ~ 0, e.g. at the end of a stick): the
///                  slip-speed witness is s v_t + v_tol (in units of v_ref) until s v_t exceeds
///                  v_tol (then s v_t), so that the slip is not ended by its own start; a slip
///                  that goes the wrong way beyond v_tol still ends at once;
///   omega_done:    omega_lim crossed: its witness is the constant 1.
struct Arming {
  ContactSet gap_banded, rate_deferred, slip_banded;
  bool omega_done = false;
  bool any() const { return gap_banded.any() || rate_deferred.any() || slip_banded.any(); }
};

/// The witnesses of the running phase and their root directions (room for every witness of
/// kMaxContacts contacts: rebuilding the list allocates nothing).
struct WitnessList {
  static constexpr std::size_t kCapacity = 5 * kMaxContacts + 1;
  std::array<WitnessRef, kCapacity> list{};
  std::array<int, kCapacity> dirs{};
  int n = 0;
  void clear() { n = 0; }
  void add(Witness w, int k, int dir) {
    list[static_cast<std::size_t>(n)] = {w, k};
    dirs[static_cast<std::size_t>(n)] = dir;
    ++n;
  }
  int size() const { return n; }
  const WitnessRef& operator[](int i) const { return list[static_cast<std::size_t>(i)]; }
};

/// The one scaling of the witnesses (the root function divides by it): gaps by the gap's scale,
/// speeds by the reference speed, forces by the contact forces' scale, omega by omega_lim.
inline double witness_scale(Witness w, const SwitchTolerances& tol, double F_ref,
                            double omega_lim) {
  switch (w) {
    case Witness::Gap: return tol.g0;
    case Witness::GapRate:
    case Witness::SlipSpeed: return tol.v_ref;
    case Witness::Omega: return omega_lim;
    default: return F_ref;
  }
}

}  // namespace rubdyn::detail
