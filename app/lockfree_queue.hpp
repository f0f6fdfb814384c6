#pragma once
// Bounded lock-free queues for handing data out of the real-time control thread.
//
// SpscRing: one producer, one consumer, trivially copyable elements, power-of-two capacity.
// BoundedMpmcQueue: any number of producers and consumers (D. Vyukov's bounded queue: one
// sequence number per cell, a CAS on the enqueue/dequeue position). Both only ever try:
// a full queue returns false at once, an empty one returns false at once.
#include <atomic>
#include <cstddef>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace flexirob::app {

namespace detail {
inline std::size_t roundUpToPowerOfTwo(std::size_t n) {
  if (n < 2) return 2;
  std::size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}
// A fixed value rather than std::hardware_destructive_interference_size, whose value GCC
// warns may differ between compilation units.
inline constexpr std::size_t kCacheLine = 64;
}  // namespace detail

template <typename T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds trivially copyable records");

 public:
  /// Holds at least `capacity` elements (rounded up to a power of two).
  explicit SpscRing(std::size_t capacity)
      : capacity_(detail::roundUpToPowerOfTwo(capacity)),
        mask_(capacity_ - 1),
        slots_(std::make_unique<T[]>(capacity_)) {}

  std::size_t capacity() const { return capacity_; }

  /// Producer only. False if full.
  bool tryPush(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - cached_tail_ >= capacity_) {
      cached_tail_ = tail_.load(std::memory_order_acquire);
      if (head - cached_tail_ >= capacity_) return false;
    }
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. False if empty.
  bool tryPop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == cached_head_) {
      cached_head_ = head_.load(std::memory_order_acquire);
      if (tail == cached_head_) return false;
    }
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Approximate element count (exact when called from either side while the other is idle).
  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<T[]> slots_;
  alignas(detail::kCacheLine) std::atomic<std::size_t> head_{0};  // written by the producer
  std::size_t cached_tail_ = 0;                                   // producer's view of tail_
  alignas(detail::kCacheLine) std::atomic<std::size_t> tail_{0};  // written by the consumer
  std::size_t cached_head_ = 0;                                   // consumer's view of head_
};

template <typename T>
class BoundedMpmcQueue {
  static_assert(std::is_nothrow_move_constructible_v<T> && std::is_nothrow_move_assignable_v<T>,
                "elements are moved in and out without throwing");

 public:
  explicit BoundedMpmcQueue(std::size_t capacity)
      : capacity_(detail::roundUpToPowerOfTwo(capacity)),
        mask_(capacity_ - 1),
        cells_(std::make_unique<Cell[]>(capacity_)) {
    for (std::size_t i = 0; i < capacity_; ++i) cells_[i].sequence.store(i, std::memory_order_relaxed);
  }

  std::size_t capacity() const { return capacity_; }

  /// Any producer. False if full; `value` is then left untouched.
  bool tryPush(T& value) noexcept {
    std::size_t pos = enqueue_pos_.load(std::memory_order_relaxed);
    for (;;) {
      Cell& cell = cells_[pos & mask_];
      const std::size_t seq = cell.sequence.load(std::memory_order_acquire);
      const auto diff = static_cast<std::ptrdiff_t>(seq) - static_cast<std::ptrdiff_t>(pos);
      if (diff == 0) {
        if (enqueue_pos_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          cell.value = std::move(value);
          cell.sequence.store(pos + 1, std::memory_order_release);
          return true;
        }
      } else if (diff < 0) {
        return false;  // full
      } else {
        pos = enqueue_pos_.load(std::memory_order_relaxed);
      }
    }
  }

  /// Any consumer. False if empty.
  bool tryPop(T& out) noexcept {
    std::size_t pos = dequeue_pos_.load(std::memory_order_relaxed);
    for (;;) {
      Cell& cell = cells_[pos & mask_];
      const std::size_t seq = cell.sequence.load(std::memory_order_acquire);
      const auto diff = static_cast<std::ptrdiff_t>(seq) - static_cast<std::ptrdiff_t>(pos + 1);
      if (diff == 0) {
        if (dequeue_pos_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          out = std::move(cell.value);
          cell.sequence.store(pos + capacity_, std::memory_order_release);
          return true;
        }
      } else if (diff < 0) {
        return false;  // empty
      } else {
        pos = dequeue_pos_.load(std::memory_order_relaxed);
      }
    }
  }

 private:
  struct Cell {
    std::atomic<std::size_t> sequence{0};
    T value{};
  };
  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<Cell[]> cells_;
  alignas(detail::kCacheLine) std::atomic<std::size_t> enqueue_pos_{0};
  alignas(detail::kCacheLine) std::atomic<std::size_t> dequeue_pos_{0};
};

}  // namespace flexirob::app
