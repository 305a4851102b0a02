// Hands immutable values (compiled models) from set-up threads to one
// real-time thread without a lock, an allocation or a free on the real-time
// side. Ownership travels through three atomic slots: `offer` puts a value
// in `pending`; the real-time thread's `adopt` takes it and moves the one it
// used into `retired`; any other thread frees the retired one (`offer` does,
// or `collect`). A value the real-time thread never adopted is freed by the
// next `offer`. So the real-time thread never frees, and never sees a value
// freed while it uses it.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

namespace plsa {

template <class T>
class ModelHandOff {
 public:
  explicit ModelHandOff(std::shared_ptr<const T> first)
      : active_(std::make_unique<Holder>(Holder{std::move(first), 0})) {}
  ~ModelHandOff() {
    std::unique_ptr<Holder>(pending_.exchange(nullptr)).reset();
    std::unique_ptr<Holder>(retired_.exchange(nullptr)).reset();
  }
  ModelHandOff(const ModelHandOff&) = delete;
  ModelHandOff& operator=(const ModelHandOff&) = delete;

  /// Any thread but the real-time one: `next` (tagged `id`) is adopted at the real-time
  /// thread's next adopt(); an earlier offer it never took is dropped. Allocates.
  void offer(std::shared_ptr<const T> next, std::uint64_t id) {
    collect();
    auto holder = std::make_unique<Holder>(Holder{std::move(next), id});
    std::unique_ptr<Holder>(pending_.exchange(holder.release(), std::memory_order_acq_rel)).reset();
  }
  /// Any thread but the real-time one: frees what the real-time thread let go of.
  void collect() { std::unique_ptr<Holder>(retired_.exchange(nullptr, std::memory_order_acq_rel)).reset(); }

  /// Real-time thread: takes the offered value, if any and if the last one it
  /// let go of has been collected, calling on_swap(previous, next) first
  /// (both alive for the call). Returns whether it changed. Never allocates or frees.
  template <class OnSwap>
  bool adopt(OnSwap&& on_swap) noexcept {
    if (retired_.load(std::memory_order_acquire) != nullptr) return false;
    Holder* next = pending_.exchange(nullptr, std::memory_order_acq_rel);
    if (!next) return false;
    on_swap(*active_->value, *next->value);
    Holder* previous = active_.release();  // handed to retired_, never freed here
    active_.reset(next);
    retired_.store(previous, std::memory_order_release);  // from here another thread may free it
    return true;
  }
  /// Real-time thread: the value in force.
  const T& current() const noexcept { return *active_->value; }
  /// Real-time thread: the tag of the value in force (0 for the first).
  std::uint64_t currentId() const noexcept { return active_->id; }
  /// Real-time thread (or before it starts): the value in force, shared.
  const std::shared_ptr<const T>& currentShared() const noexcept { return active_->value; }

 private:
  struct Holder {
    std::shared_ptr<const T> value;
    std::uint64_t id;
  };
  std::unique_ptr<Holder> active_;  // read and replaced by the real-time thread only
  // Owned while set: a shared_ptr cannot travel through a lock-free atomic, a raw pointer can.
  std::atomic<Holder*> pending_{nullptr};
  std::atomic<Holder*> retired_{nullptr};
};

}  // namespace plsa
