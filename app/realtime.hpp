#pragma once
// What the 1 kHz loops (ControlThread, WorkflowThread) share: the monotonic clock on an absolute
// schedule, a lock-free running maximum for statistics other threads read, and the request for
// real-time scheduling. Header-only: these run inside the cycle and must inline.
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <Eigen/Core>
#include <string_view>
#include <thread>

namespace flexirob::app::realtime {

inline constexpr long kNanosPerSecond = 1'000'000'000L;

inline timespec now() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t;
}

/// Moves an absolute deadline on by `nanos` (the schedule does not drift when a cycle is late).
inline void advance(timespec& t, long nanos) {
  t.tv_nsec += nanos;
  while (t.tv_nsec >= kNanosPerSecond) {
    t.tv_nsec -= kNanosPerSecond;
    ++t.tv_sec;
  }
}

inline double microsBetween(const timespec& from, const timespec& to) {
  return static_cast<double>(to.tv_sec - from.tv_sec) * 1e6 + static_cast<double>(to.tv_nsec - from.tv_nsec) * 1e-3;
}

/// target = max(target, value), lock-free (the loop writes, any thread reads).
inline void atomicMax(std::atomic<double>& target, double value) {
  double current = target.load(std::memory_order_relaxed);
  while (value > current && !target.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
  }
}

/// Asks for SCHED_FIFO just below the top priority; without the privilege the thread stays
/// normal (and runs all the same).
inline void requestRealtimePriority(std::thread& thread) {
  sched_param parameter{};
  parameter.sched_priority = sched_get_priority_max(SCHED_FIFO) - 1;
  pthread_setschedparam(thread.native_handle(), SCHED_FIFO, &parameter);
}

/// Names a thread as `top`, ps and profilers show it (at most 15 characters on Linux).
inline void nameThread(std::thread& thread, const char* name) { pthread_setname_np(thread.native_handle(), name); }

/// The calling thread back at normal priority: a thread started from the real-time loop
/// inherits SCHED_FIFO, and background work (learning) must never compete with the loop.
inline void runAtNormalPriority() {
  sched_param parameter{};
  parameter.sched_priority = 0;
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &parameter);
}

/// Copies as many values as both hold into a fixed-size snapshot array.
template <typename Array>
void copyInto(Array& destination, const Eigen::VectorXd& source) {
  const auto n = std::min<std::size_t>(destination.size(), static_cast<std::size_t>(source.size()));
  for (std::size_t i = 0; i < n; ++i) destination[i] = source[static_cast<Eigen::Index>(i)];
}

/// Copies text into a fixed, zero-terminated snapshot buffer. A text too long for it is cut
/// after its last whole word that fits, with "…" after it: never inside a word or a UTF-8
/// character, so that what a person reads is visibly shortened and not silently wrong.
template <std::size_t N>
void copyText(std::array<char, N>& destination, std::string_view text) {
  static_assert(N > 8);
  if (text.size() <= N - 1) {
    std::memcpy(destination.data(), text.data(), text.size());
    destination[text.size()] = '\0';
    return;
  }
  constexpr std::string_view kEllipsis = "\u2026";
  std::size_t n = N - 1 - kEllipsis.size();
  const std::size_t space = text.rfind(' ', n);
  if (space != std::string_view::npos && space > n / 2) {
    n = space;
  } else {
    while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;  // not inside a character
  }
  std::memcpy(destination.data(), text.data(), n);
  std::memcpy(destination.data() + n, kEllipsis.data(), kEllipsis.size());
  destination[n + kEllipsis.size()] = '\0';
}

}  // namespace flexirob::app::realtime
