// The real-time predictor with its pole count checked at set-up:
// Predictor<NP> over NStepPredictor (n_step_predictor.hpp), which holds the
// compiled model's hand-off, the state and every prediction path.
#pragma once

#include <memory>
#include <string>

#include "plsa/core/check.hpp"
#include "plsa/predict/n_step_predictor.hpp"

namespace plsa {

/// NP: poles per filter bank when known at compile time (checked at set-up),
/// or Eigen::Dynamic for any.
template <int NP = Eigen::Dynamic>
class Predictor : public NStepPredictor {
 public:
  explicit Predictor(const DioPwlObfModel& model, const PredictorOptions& options = {})
      : NStepPredictor(checkedPoles(model), options) {}
  Predictor(std::shared_ptr<const CompiledModel> model, const PredictorOptions& options)
      : NStepPredictor(std::move(model), options) {
    PLSA_CHECK(NP == Eigen::Dynamic || compiledModel()->poles == NP,
               "Predictor<" + std::to_string(NP) + ">: the model's pole sets have " +
                   std::to_string(compiledModel()->poles) + " poles");
  }

 private:
  static const DioPwlObfModel& checkedPoles(const DioPwlObfModel& m) {
    if constexpr (NP != Eigen::Dynamic) {
      m.validate();
      for (const auto& row : m.poles)
        for (const auto& ps : row)
          PLSA_CHECK(ps.size() == NP, "Predictor<" + std::to_string(NP) + ">: the model's pole sets have " +
                                          std::to_string(ps.size()) + " poles");
    }
    return m;
  }
};

}  // namespace plsa
