// libFuzzer entry point: one per target, chosen at compile time by
// PLSA_FUZZ_TARGET (a function of fuzz_targets.hpp).
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  plsa::fuzz::PLSA_FUZZ_TARGET(data, size);
  return 0;
}
