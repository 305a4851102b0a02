// Step 1 of the paper's Table I and the local fits of step 2: the step
// segments of the references (the commands, or the plateaus of measured
// inputs logged without them) and each segment's local LTI fit per output.
#include <string>
#include <utility>
#include <vector>

#include "identification_run.hpp"
#include "plsa/identify/local_fit.hpp"
#include "plsa/identify/segmentation.hpp"

namespace plsa::identify {

// Each step segment's local fit, per output.
void IdentificationRun::fitStepSegments(const std::vector<io::Log>& logs) {
  rep.segments = 0;
  for (std::size_t r = 0; r < logs.size(); ++r) {
    for (const LocalDataSet& seg : segmentSteps(Ref[r], step, min_len)) {
      ++rep.segments;
      const Eigen::Index n = seg.end - seg.begin;
      for (int out_i = 0; out_i < no; ++out_i) {
        const LocalFit f =
            fitLocalModel(U[r].col(seg.input).segment(seg.begin, n), Ym[r].col(out_i).segment(seg.begin, n),
                          U[r](seg.begin - 1, seg.input), Ym[r](seg.begin - 1, out_i), o.local_order);
        PairPoles& pp = pairAt(seg.input, out_i);
        if (f.usable) {
          pp.identified.insert(pp.identified.end(), f.poles.begin(), f.poles.end());
        } else {
          if (f.uncertain) pp.uncertain.insert(pp.uncertain.end(), f.poles.begin(), f.poles.end());
          ++pp.rejected;
          pp.rejections.push_back(logs[r].source + " samples " + std::to_string(seg.begin) + "-" +
                                  std::to_string(seg.end) + ": " + f.reason);
        }
      }
    }
  }
}

// Measured inputs as their own references (no commands logged, none named)
// that give no step: their noise cuts them at every sample. The plateaus
// they hold (plateauReference) give the steps and levels a staircase's
// commands would, when they hold any.
void IdentificationRun::stepsFromPlateaus(const std::vector<io::Log>& logs) {
  std::vector<Eigen::MatrixXd> plateaus;
  for (const Eigen::MatrixXd& u : U) plateaus.push_back(plateauReference(u, min_len, step));
  std::swap(Ref, plateaus);
  fitStepSegments(logs);
  if (rep.segments == 0) {
    std::swap(Ref, plateaus);  // nothing held: the inputs stay the references
    return;
  }
  rep.references_from_plateaus = true;
  say("[2/5] step references: the inputs, logged without commands, step nowhere as logged (their noise); the "
      "plateaus they hold for 1 s or more within 5 times their noise give " +
      std::to_string(rep.segments) + " step segments");
}

}  // namespace plsa::identify
