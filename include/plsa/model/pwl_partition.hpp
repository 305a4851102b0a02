// The DIO-PWL partition: local regions from a grid of reference pressures on
// the scheduling inputs, optionally split by each input's direction of change
// (increase/decrease cases). Switched (the paper: one region's coefficients at
// a time) or interpolated (coefficients blended multilinearly between grid
// nodes). Lookup is O(log levels), allocation-free, noexcept.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>

#include "plsa/core/check.hpp"

namespace plsa {

/// Direction memory of the scheduler: +1 rising, -1 falling, per scheduling input.
struct DirectionState {
  static constexpr int kMaxInputs = 8;
  std::array<std::int8_t, kMaxInputs> dir{};
  DirectionState() { dir.fill(1); }  // from vented, the first move is a rise
};

/// Regions and weights whose coefficients make up one sample's model.
struct ScheduleBlend {
  static constexpr int kMax = 16;  // 2^4 corners: at most 4 interpolated inputs
  int count = 0;
  std::array<int, kMax> region{};
  std::array<double, kMax> weight{};
};

enum class Scheduling { kSwitched, kInterpolated };

class PwlPartition {
 public:
  /// Most cells a partition may have (a grid of 1024 x 1024 nodes): each holds
  /// a coefficient block, and the predictor a filter bank per node.
  static constexpr int kMaxRegions = 1 << 20;
  /// Most inputs an interpolated partition schedules on (2^4 corners a sample, ScheduleBlend).
  static constexpr int kMaxInterpolatedInputs = 4;

  PwlPartition() = default;

  /// Interpolated scheduling: `levels[s]` are the grid nodes of input
  /// `inputs[s]`; outside the outer nodes the nearest node's coefficients hold.
  static PwlPartition interpolated(std::vector<int> inputs, std::vector<std::vector<double>> levels,
                                   bool direction_split = false, double direction_threshold = 1e-3) {
    PLSA_CHECK(inputs.size() <= static_cast<std::size_t>(kMaxInterpolatedInputs),
               "PwlPartition: interpolated scheduling takes at most 4 inputs");
    for (const auto& l : levels) PLSA_CHECK(!l.empty(), "PwlPartition: every interpolated input needs a level");
    // Nodes are stored as "breakpoints"; a node's cell is its index.
    PwlPartition p(std::move(inputs), std::move(levels), direction_split, direction_threshold);
    p.mode_ = Scheduling::kInterpolated;
    p.cells_ = 1;
    p.strides_.clear();
    for (const auto& l : p.breakpoints_) {
      PLSA_CHECK(l.size() <= static_cast<std::size_t>(kMaxRegions / p.cells_), regionLimitMessage());
      p.strides_.push_back(p.cells_);
      p.cells_ *= static_cast<int>(l.size());
    }
    return p;
  }
  Scheduling scheduling() const noexcept { return mode_; }

  /// `breakpoints[s]` splits scheduling input `inputs[s]` into cells
  /// (-inf, b0), [b0, b1), ..., [b_last, inf). A direction split doubles the
  /// regions per scheduling input; a change counts once |du| > threshold.
  PwlPartition(std::vector<int> inputs, std::vector<std::vector<double>> breakpoints, bool direction_split = false,
               double direction_threshold = 1e-3)
      : inputs_(std::move(inputs)),
        breakpoints_(std::move(breakpoints)),
        direction_split_(direction_split),
        direction_threshold_(direction_threshold) {
    PLSA_CHECK(inputs_.size() == breakpoints_.size(), "PwlPartition: one breakpoint list per scheduling input");
    PLSA_CHECK(inputs_.size() <= static_cast<std::size_t>(DirectionState::kMaxInputs),
               "PwlPartition: at most 8 scheduling inputs");
    PLSA_CHECK(direction_threshold_ >= 0 && std::isfinite(direction_threshold_),
               "PwlPartition: the direction threshold must be finite and >= 0");
    cells_ = 1;
    for (std::size_t s = 0; s < inputs_.size(); ++s) {
      PLSA_CHECK(inputs_[s] >= 0, "PwlPartition: scheduling input indices must be >= 0");
      const auto& b = breakpoints_[s];
      for (std::size_t i = 0; i < b.size(); ++i) {
        PLSA_CHECK(std::isfinite(b[i]), "PwlPartition: breakpoints must be finite");
        PLSA_CHECK(i == 0 || b[i] > b[i - 1],
                   "PwlPartition: breakpoints of input " + std::to_string(inputs_[s]) + " must increase strictly");
      }
      PLSA_CHECK(b.size() < static_cast<std::size_t>(kMaxRegions / cells_), regionLimitMessage());
      strides_.push_back(cells_);
      cells_ *= static_cast<int>(b.size()) + 1;
    }
  }

  /// The global linear model: one region.
  static PwlPartition single() { return PwlPartition({}, {}); }

  static std::string regionLimitMessage() {
    return "PwlPartition: more than " + std::to_string(kMaxRegions) + " cells";
  }

  int cellCount() const noexcept { return cells_; }
  int regionCount() const noexcept { return cells_ * (direction_split_ ? (1 << inputs_.size()) : 1); }
  const std::vector<int>& inputs() const noexcept { return inputs_; }
  const std::vector<std::vector<double>>& breakpoints() const noexcept { return breakpoints_; }
  bool directionSplit() const noexcept { return direction_split_; }
  double directionThreshold() const noexcept { return direction_threshold_; }
  int maxInputIndex() const noexcept {
    int m = -1;
    for (int i : inputs_) m = std::max(m, i);
    return m;
  }

  /// Latches each scheduling input's direction from its latest difference.
  template <class Vec>
  void updateDirections(const Vec& du, DirectionState& state) const noexcept {
    const std::size_t n =
        std::min(inputs_.size(), state.dir.size());  // the constructor caps it; say so to the compiler
    for (std::size_t s = 0; s < n; ++s) {
      const double d = du[inputs_[s]];
      if (d > direction_threshold_)
        state.dir[s] = 1;
      else if (d < -direction_threshold_)
        state.dir[s] = -1;
    }
  }

  /// The regions and weights for input u: one region (weight 1) when
  /// switched, the surrounding grid nodes when interpolated.
  template <class Vec>
  void blend(const Vec& u, const DirectionState& state, ScheduleBlend& out) const noexcept {
    if (mode_ == Scheduling::kSwitched) {
      out.count = 1;
      out.region[0] = region(u, state);
      out.weight[0] = 1.0;
      return;
    }
    const int offset = cells_ * directionBits(state);
    out.count = 1;
    out.region[0] = offset;
    out.weight[0] = 1.0;
    for (std::size_t s = 0; s < inputs_.size(); ++s) {
      const auto& n = breakpoints_[s];
      const double x = u[inputs_[s]];
      int i = 0;
      double t = 0.0;
      if (x >= n.back()) {
        i = static_cast<int>(n.size()) - 1;
      } else if (x > n.front()) {
        i = static_cast<int>(std::upper_bound(n.begin(), n.end(), x) - n.begin()) - 1;
        t = (x - n[static_cast<std::size_t>(i)]) /
            (n[static_cast<std::size_t>(i) + 1] - n[static_cast<std::size_t>(i)]);
      }
      const int c = out.count;
      for (int m = 0; m < c; ++m) {
        if (t > 0.0) {
          out.region[static_cast<std::size_t>(c + m)] = out.region[static_cast<std::size_t>(m)] + (i + 1) * strides_[s];
          out.weight[static_cast<std::size_t>(c + m)] = out.weight[static_cast<std::size_t>(m)] * t;
        }
        out.region[static_cast<std::size_t>(m)] += i * strides_[s];
        out.weight[static_cast<std::size_t>(m)] *= 1.0 - t;
      }
      if (t > 0.0) out.count = 2 * c;
    }
  }

  /// Region of an input vector u (any indexable type) and direction state;
  /// when interpolated, the nearest grid node.
  template <class Vec>
  int region(const Vec& u, const DirectionState& state) const noexcept {
    if (mode_ == Scheduling::kInterpolated) {
      int cell = 0;
      for (std::size_t s = 0; s < inputs_.size(); ++s) {
        const auto& n = breakpoints_[s];
        const double x = u[inputs_[s]];
        std::size_t best = 0;
        for (std::size_t i = 1; i < n.size(); ++i)
          if (std::abs(n[i] - x) < std::abs(n[best] - x)) best = i;
        cell += static_cast<int>(best) * strides_[s];
      }
      return cell + cells_ * directionBits(state);
    }
    int cell = 0;
    for (std::size_t s = 0; s < inputs_.size(); ++s) {
      const auto& b = breakpoints_[s];
      const int c = static_cast<int>(std::upper_bound(b.begin(), b.end(), u[inputs_[s]]) - b.begin());
      cell += c * strides_[s];
    }
    return cell + cells_ * directionBits(state);
  }

  int directionBits(const DirectionState& state) const noexcept {
    if (!direction_split_) return 0;
    int bits = 0;
    for (std::size_t s = 0; s < inputs_.size(); ++s)
      if (state.dir[s] < 0) bits |= 1 << s;
    return bits;
  }

  /// Cell index of scheduling input s within region r, and its direction.
  int cellOf(int region, std::size_t s) const noexcept {
    const int per = static_cast<int>(breakpoints_[s].size()) + (mode_ == Scheduling::kSwitched ? 1 : 0);
    return (region % cells_) / strides_[s] % per;
  }
  bool fallingOf(int region, std::size_t s) const noexcept { return direction_split_ && ((region / cells_) >> s) & 1; }

  /// Words for a region, e.g. "p_1 in [0.225, 0.275) rising, p_2 in [0.275, inf) rising".
  std::string describe(int region, const std::vector<std::string>& input_names) const {
    if (inputs_.empty()) return "whole operating range";
    std::string out;
    for (std::size_t s = 0; s < inputs_.size(); ++s) {
      const int c = cellOf(region, s);
      const auto& b = breakpoints_[s];
      if (mode_ == Scheduling::kInterpolated) {
        const auto idx = static_cast<std::size_t>(inputs_[s]);
        const std::string name = idx < input_names.size() ? input_names[idx] : "u" + std::to_string(idx + 1);
        out += (s ? ", " : "") + name + " = " + fmt(b[static_cast<std::size_t>(c)]);
        if (direction_split_) out += fallingOf(region, s) ? " falling" : " rising";
        continue;
      }
      const std::string lo = c == 0 ? "-inf" : fmt(b[static_cast<std::size_t>(c - 1)]);
      const std::string hi = c == static_cast<int>(b.size()) ? "inf" : fmt(b[static_cast<std::size_t>(c)]);
      const auto idx = static_cast<std::size_t>(inputs_[s]);
      const std::string name = idx < input_names.size() ? input_names[idx] : "u" + std::to_string(idx + 1);
      out += (s ? ", " : "") + name + " in [" + lo + ", " + hi + ")";
      if (direction_split_) out += fallingOf(region, s) ? " falling" : " rising";
    }
    return out;
  }

 private:
  static std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }

  std::vector<int> inputs_;
  std::vector<std::vector<double>> breakpoints_;
  std::vector<int> strides_;
  bool direction_split_ = false;
  double direction_threshold_ = 1e-3;
  int cells_ = 1;
  Scheduling mode_ = Scheduling::kSwitched;
};

}  // namespace plsa
