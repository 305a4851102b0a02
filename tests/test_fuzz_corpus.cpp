// Every committed fuzz input (seeds, and the regression inputs of defects
// found by hand or by the fuzzers) through its target's function, in the
// ordinary build: a decoder that crashes, throws something other than a
// named error, or breaks an invariant on any of them fails here, with or
// without clang and libFuzzer.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "fuzz/fuzz_targets.hpp"

namespace fs = std::filesystem;

namespace {

using Target = std::function<void(const std::uint8_t*, std::size_t)>;

const std::map<std::string, Target>& targets() {
  static const std::map<std::string, Target> all = {
      {"csv_log", plsa::fuzz::csvLog},
      {"model_file", plsa::fuzz::modelFile},
      {"sim_config", plsa::fuzz::simConfig},
      {"signal_map", plsa::fuzz::signalMap},
      {"can_frame", plsa::fuzz::canFrames},
      {"udp_datagram", plsa::fuzz::udpDatagram},
      {"candump_log", plsa::fuzz::candumpLog},
      {"lcm_command", plsa::fuzz::lcmMessage<plsa_lcm::pressure_command_t>},
      {"lcm_state", plsa::fuzz::lcmMessage<plsa_lcm::actuator_state_t>},
      {"lcm_prediction", plsa::fuzz::lcmMessage<plsa_lcm::prediction_t>},
      {"lcm_status", plsa::fuzz::lcmMessage<plsa_lcm::status_t>},
      {"lcm_log", plsa::fuzz::lcmLog}};
  return all;
}

std::string bytesOf(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

TEST(FuzzCorpus, EveryTargetHasSeedsAndRegressionInputsThatRunClean) {
  const fs::path corpus = fs::path(PLSA_FUZZ_CORPUS_DIR);
  ASSERT_TRUE(fs::is_directory(corpus)) << corpus;
  for (const auto& [name, run] : targets()) {
    const fs::path dir = corpus / name;
    ASSERT_TRUE(fs::is_directory(dir)) << "no corpus for fuzz target " << name;
    int inputs = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string bytes = bytesOf(entry.path());
      SCOPED_TRACE(entry.path().string());
      EXPECT_NO_THROW(run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
      ++inputs;
    }
    EXPECT_GT(inputs, 0) << name;
  }
  for (const auto& entry : fs::directory_iterator(corpus))
    EXPECT_TRUE(targets().count(entry.path().filename().string()))
        << "corpus folder " << entry.path() << " belongs to no target";
}
