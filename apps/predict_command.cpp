// `plsa predict`: the real-time predictor as an LCM node.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "plsa/lcm/predictor_node.hpp"
#include "plsa/model/model_file.hpp"
#include "stop_signal.hpp"

namespace plsa::app {

void addPredictCommand(CLI::App& app) {
  auto model = std::make_shared<std::string>();
  auto o = std::make_shared<lcm::PredictorNodeOptions>();
  CLI::App* c = app.add_subcommand("predict", "Publish n-step-ahead predictions of actuator state over LCM");
  c->add_option("--model", *model, "Model file")->required()->check(CLI::ExistingFile);
  c->add_option("--horizons", o->horizons, "Horizons in samples, up to 60 s of model time")->delimiter(',');
  c->add_option("--url", o->url, "LCM URL (default: LCM_DEFAULT_URL)");
  c->add_option("--state-channel", o->state_channel, "Channel of actuator state");
  c->add_option("--prediction-channel", o->prediction_channel, "Channel for predictions");
  c->add_option("--status-channel", o->status_channel, "Channel for status");
  c->add_option("--realtime-priority", o->realtime_priority,
                "SCHED_FIFO priority where permitted (1-99; 0: normal scheduling); memory is locked either way")
      ->check(CLI::Range(0, 99));
  c->callback([model, o] {
    const DioPwlObfModel m = loadModel(*model);
    const std::atomic<bool>& stop = stopOnSignals();
    std::fprintf(stderr, "plsa predict: %s, horizons", model->c_str());
    for (int h : o->horizons) std::fprintf(stderr, " %d", h);
    std::fprintf(stderr, ", %s -> %s\n", o->state_channel.c_str(), o->prediction_channel.c_str());
    const lcm::PredictorNodeStats s = lcm::runPredictorNode(m, *o, stop);
    std::fprintf(stderr,
                 "plsa predict: stopped; %lld states, %lld predictions, %lld rejected samples, %lld over a "
                 "sample time\n",
                 static_cast<long long>(s.states), static_cast<long long>(s.predictions),
                 static_cast<long long>(s.rejected), static_cast<long long>(s.deadline_misses));
  });
}

}  // namespace plsa::app
