// The structure search on a sample of long logs (search_sample.hpp): the
// windows, the swap of the run's data to them before the search, and back to
// every sample for the final fit.
#include "plsa/identify/search_sample.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "identification_run.hpp"
#include "plsa/core/check.hpp"
#include "plsa/core/number_text.hpp"

namespace plsa::identify {
namespace {

// A window's first rows start its filters from a guessed state (the level
// of its first sample, as if it had rested there): fitted, never scored.
constexpr double kSearchWarmupS = 10.0;

// The window whose centre is row `centre` of the logs laid end to end.
SearchWindow windowAround(const std::vector<Eigen::Index>& lengths, Eigen::Index centre, Eigen::Index w) {
  std::size_t r = 0;
  while (r + 1 < lengths.size() && centre >= lengths[r]) centre -= lengths[r++];
  if (lengths[r] <= w) return {r, 0, lengths[r]};
  return {r, std::clamp<Eigen::Index>(centre - w / 2, 0, lengths[r] - w), w};
}

std::string minutes(Eigen::Index rows, double dt) {
  const double s = static_cast<double>(rows) * dt;
  return s >= 120 ? formatNumber(std::round(s / 6) / 10) + " min" : formatNumber(std::round(s)) + " s";
}

}  // namespace

std::vector<SearchWindow> searchWindows(const std::vector<Eigen::Index>& log_lengths, Eigen::Index max_samples,
                                        Eigen::Index window) {
  PLSA_CHECK(window >= 1, "searchWindows: a window needs at least one row");
  Eigen::Index total = 0;
  for (Eigen::Index n : log_lengths) {
    PLSA_CHECK(n >= 0, "searchWindows: a log length is negative");
    total += n;
  }
  std::vector<SearchWindow> out;
  if (max_samples <= 0 || total <= max_samples) {
    for (std::size_t r = 0; r < log_lengths.size(); ++r) out.push_back({r, 0, log_lengths[r]});
    return out;
  }
  const Eigen::Index count = std::max<Eigen::Index>(1, max_samples / std::min(window, max_samples));
  const Eigen::Index w = max_samples / count;
  for (Eigen::Index j = 0; j < count; ++j) {
    const Eigen::Index centre = static_cast<Eigen::Index>(
        (2.0 * static_cast<double>(j) + 1.0) * static_cast<double>(total) / (2.0 * static_cast<double>(count)));
    const SearchWindow s = windowAround(log_lengths, centre, w);
    if (!out.empty() && out.back().log == s.log && s.begin <= out.back().begin + out.back().length)
      out.back().length = std::max(out.back().begin + out.back().length, s.begin + s.length) - out.back().begin;
    else
      out.push_back(s);
  }
  return out;
}

// Before the search: on logs longer than search_max_samples, U, Y and times
// become the windows (each its own record) and every log is kept aside for
// fitFinal. Rows in a window's warm-up are listed for cutFolds.
void IdentificationRun::sampleForSearch() {
  rep.search_samples = total;
  if (o.search_max_samples <= 0 || total <= o.search_max_samples) return;  // searchWindows: every log whole
  const auto window = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::lround(o.search_window_s / dt)));
  // Fewer samples than one window: windows of the warm-up alone, scored on nothing.
  if (o.search_max_samples < window)
    throw std::invalid_argument(
        "identify: --search-samples " + std::to_string(o.search_max_samples) + " (" +
        formatNumber(static_cast<double>(o.search_max_samples) * dt) + " s) is under one search window (" +
        formatNumber(o.search_window_s) + " s, whose first " + formatNumber(kSearchWarmupS) +
        " s are not scored): give at least " + std::to_string(window) + ", or 0 to search on every sample");
  std::vector<Eigen::Index> lengths;
  for (const auto& u : U) lengths.push_back(u.rows());
  const std::vector<SearchWindow> windows = searchWindows(lengths, o.search_max_samples, window);
  all_U = std::move(U);
  all_Y = std::move(Y);
  all_times = std::move(times);
  U.clear(), Y.clear(), times.clear(), warmup_rows.clear();
  const auto warmup = static_cast<Eigen::Index>(std::lround(kSearchWarmupS / dt));
  Eigen::Index kept = 0;
  for (const SearchWindow& s : windows) {
    U.push_back(all_U[s.log].middleRows(s.begin, s.length));
    Y.push_back(all_Y[s.log].middleRows(s.begin, s.length));
    times.push_back(all_times[s.log].segment(s.begin, s.length));
    warmup_rows.push_back(s.begin == 0 ? 0 : std::min(warmup, s.length));
    kept += s.length;
  }
  rep.search_samples = kept;
  say("[5/5] structure search on " + minutes(kept, dt) + " of the " + minutes(total, dt) +
      " logged: " + std::to_string(windows.size()) + " windows spread over the logs, each window's first " +
      formatNumber(kSearchWarmupS) +
      " s fitted but not scored; the chosen structure is then fitted on every sample (--search-samples 0 searches "
      "on all)");
}

// After the search: every sample again, the outputs less the drift the search
// estimated (a rate and a reference time, which hold for every sample).
void IdentificationRun::restoreAllData() {
  if (all_U.empty()) return;
  U = std::move(all_U);
  Y = std::move(all_Y);
  times = std::move(all_times);
  Yfit = rep.drift_taken_out ? removeOutputDrift(Y, times, rep.output_drift) : Y;
}

}  // namespace plsa::identify
