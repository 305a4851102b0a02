#include "plsa/identify/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "plsa/core/check.hpp"

namespace plsa::identify {

std::vector<LocalDataSet> segmentSteps(const Eigen::MatrixXd& ref, double min_step, Eigen::Index min_length) {
  PLSA_CHECK(min_step > 0, "segmentSteps: min_step must be positive");
  std::vector<Eigen::Index> changes;
  for (Eigen::Index k = 1; k < ref.rows(); ++k)
    if ((ref.row(k) - ref.row(k - 1)).cwiseAbs().maxCoeff() > min_step) changes.push_back(k);
  std::vector<LocalDataSet> out;
  for (std::size_t i = 0; i < changes.size(); ++i) {
    const Eigen::Index b = changes[i];
    const Eigen::Index e = i + 1 < changes.size() ? changes[i + 1] : ref.rows();
    if (e - b < min_length) continue;
    const Eigen::RowVectorXd d = ref.row(b) - ref.row(b - 1);
    int moved = 0, which = 0;
    for (Eigen::Index j = 0; j < d.size(); ++j)
      if (std::abs(d(j)) > min_step) {
        ++moved;
        which = static_cast<int>(j);
      }
    if (moved != 1) continue;
    out.push_back({b, e, which, ref(b - 1, which), ref(b, which)});
  }
  return out;
}

std::vector<std::vector<double>> referenceLevels(const Eigen::MatrixXd& ref, double resolution,
                                                 Eigen::Index min_length) {
  PLSA_CHECK(resolution > 0, "referenceLevels: resolution must be positive");
  std::vector<std::vector<double>> levels(static_cast<std::size_t>(ref.cols()));
  for (Eigen::Index j = 0; j < ref.cols(); ++j) {
    std::map<long long, double> held;  // rounded key -> the level as held
    Eigen::Index run = 1;
    for (Eigen::Index k = 1; k <= ref.rows(); ++k) {
      if (k < ref.rows() && std::abs(ref(k, j) - ref(k - 1, j)) <= resolution / 2) {
        ++run;
        continue;
      }
      if (run >= min_length) held.emplace(std::llround(ref(k - 1, j) / resolution), ref(k - 1, j));
      run = 1;
    }
    for (const auto& [key, value] : held) levels[static_cast<std::size_t>(j)].push_back(value);
  }
  return levels;
}

}  // namespace plsa::identify
