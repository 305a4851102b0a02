// The part of long training logs the structure search scores its candidates
// on. Every candidate of the search is a pass over the data, so on an hour
// of 80 Hz data the search is minutes of CPU time; scored on windows spread
// evenly over the logs it costs what a few minutes of data cost, while the
// paper's stages before it (local fits, poles, partition) and the final fit
// of the chosen structure still use every sample (IdentifyOptions::
// search_max_samples).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace plsa::identify {

/// Rows [begin, begin + length) of training log `log`.
struct SearchWindow {
  std::size_t log = 0;
  Eigen::Index begin = 0, length = 0;
};

/// The windows the search scores on, sorted by log and start. Logs totalling
/// at most max_samples (or max_samples <= 0): every log whole. Otherwise
/// max_samples / window windows (at least one) of max_samples / count rows
/// each, centred at evenly spaced points of the logs laid end to end, each
/// moved to lie inside the log its centre falls in; a log no longer than a
/// window is taken whole, and windows that overlap or touch in one log are
/// merged. The windows never exceed max_samples in total. Throws on a
/// negative log length or a window of fewer than one row.
std::vector<SearchWindow> searchWindows(const std::vector<Eigen::Index>& log_lengths, Eigen::Index max_samples,
                                        Eigen::Index window);

}  // namespace plsa::identify
