// libFuzzer entry point over one of the targets of FuzzTargets.h (CRUMBLE_FUZZ_TARGET).
// Input errors are the expected outcome of most inputs; anything else aborts so libFuzzer
// keeps the input.
#include <cstdlib>
#include <iostream>
#include <string>

#include "tests/fuzz/FuzzTargets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::string what;
  if (crumble::fuzz::CRUMBLE_FUZZ_TARGET(text, &what) == crumble::fuzz::Outcome::OtherError) {
    std::cerr << "not an input error: " << what << "\n";
    std::abort();
  }
  return 0;
}
