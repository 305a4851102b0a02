// Base fixture for end-to-end tests that start `plsa` processes and talk to
// them over LCM: skips outside run_isolated.sh (private network namespace),
// finds the binary from PLSA_EXE and opens LCM.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include <lcm/lcm-cpp.hpp>

namespace plsa::test {

class IsolatedLcmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("PLSA_LCM_ISOLATED"))
      GTEST_SKIP() << "LCM tests run only inside run_isolated.sh (private network namespace)";
    exe_ = std::getenv("PLSA_EXE") ? std::getenv("PLSA_EXE") : "";
    ASSERT_TRUE(std::filesystem::exists(exe_)) << "PLSA_EXE does not name the plsa binary: " << exe_;
    lcm_ = std::make_unique<::lcm::LCM>();
    ASSERT_TRUE(lcm_->good());
  }

  std::string exe_;
  std::unique_ptr<::lcm::LCM> lcm_;
};

}  // namespace plsa::test
