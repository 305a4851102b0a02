#include "plsa/can/can_transport.hpp"

#include <algorithm>
#include <condition_variable>
#include <thread>

namespace plsa::can {

struct InProcessBus::Endpoint : CanTransport {
  Endpoint(std::shared_ptr<InProcessBus> bus, std::size_t capacity) : bus_(std::move(bus)), capacity_(capacity) {}
  ~Endpoint() override {
    std::lock_guard<std::mutex> lock(bus_->mutex_);
    auto& e = bus_->endpoints_;
    e.erase(std::remove(e.begin(), e.end(), this), e.end());
  }
  TransportStatus send(const CanFrame& frame) override {
    if (frame.dlc > 8 || frame.id > 0x7FF) return TransportStatus::kBadFrame;
    if (bus_->busState() == BusState::kBusOff) return TransportStatus::kBusOff;
    bus_->deliver(this, frame);
    std::lock_guard<std::mutex> lock(m_);
    ++stats_.sent;
    return TransportStatus::kOk;
  }
  TransportStatus receive(CanFrame& frame, std::chrono::microseconds timeout) override {
    std::unique_lock<std::mutex> lock(m_);
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (!queue_.empty() && queue_.front().timestamp_us <= steadyClockUs()) {
        frame = queue_.front();
        queue_.pop_front();
        ++stats_.received;
        return TransportStatus::kOk;
      }
      if (std::chrono::steady_clock::now() >= until) return TransportStatus::kTimeout;
      cv_.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::microseconds(200)));
    }
  }
  BusState busState() const override { return bus_->busState(); }
  TransportStats stats() const override {
    std::lock_guard<std::mutex> lock(m_);
    return stats_;
  }
  void push(const CanFrame& f, bool dropped, bool corrupted) {
    std::lock_guard<std::mutex> lock(m_);
    if (dropped) {
      ++stats_.dropped;
      return;
    }
    if (corrupted) ++stats_.corrupted;
    if (queue_.size() >= capacity_) {
      ++stats_.overflows;  // like SO_RXQ_OVFL: the oldest frame is lost
      queue_.pop_front();
    }
    queue_.push_back(f);
    cv_.notify_all();
  }

  std::shared_ptr<InProcessBus> bus_;
  std::size_t capacity_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<CanFrame> queue_;
  TransportStats stats_;
};

std::unique_ptr<CanTransport> InProcessBus::connect(std::size_t queue_capacity) {
  auto e = std::make_unique<Endpoint>(shared_from_this(), queue_capacity);
  std::lock_guard<std::mutex> lock(mutex_);
  endpoints_.push_back(e.get());
  return e;
}

void InProcessBus::setFaults(const FaultInjection& f) {
  std::lock_guard<std::mutex> lock(mutex_);
  faults_ = f;
  rng_.seed(f.seed);
}

void InProcessBus::setBusState(BusState s) {
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = s;
}

BusState InProcessBus::busState() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

void InProcessBus::deliver(const Endpoint* from, const CanFrame& frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (Endpoint* e : endpoints_) {
    if (e == from) continue;
    CanFrame f = frame;
    f.timestamp_us = steadyClockUs() + faults_.delay.count();
    const bool drop = uni(rng_) < faults_.drop_probability;
    const bool corrupt = !drop && f.dlc > 0 && uni(rng_) < faults_.corrupt_probability;
    if (corrupt) f.data[static_cast<std::size_t>(rng_() % f.dlc)] ^= static_cast<std::uint8_t>(1u << (rng_() % 8));
    e->push(f, drop, corrupt);
  }
}

}  // namespace plsa::can

namespace plsa::can {

const char* toString(TransportStatus s) {
  switch (s) {
    case TransportStatus::kOk:
      return "ok";
    case TransportStatus::kTimeout:
      return "timeout";
    case TransportStatus::kBackPressure:
      return "transmit queue full (back-pressure)";
    case TransportStatus::kBusOff:
      return "bus-off";
    case TransportStatus::kBadFrame:
      return "bad frame (DLC above 8 or id above 11 bits)";
    case TransportStatus::kIoError:
      return "I/O error";
  }
  return "unknown";
}

const char* toString(BusState s) {
  switch (s) {
    case BusState::kActive:
      return "error-active";
    case BusState::kErrorPassive:
      return "error-passive";
    case BusState::kBusOff:
      return "bus-off";
  }
  return "unknown";
}

}  // namespace plsa::can
