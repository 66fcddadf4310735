// Bad input that is not a scenario value: an --out folder that holds another run, a --resume
// that does not match it, a malformed --vary, a missing stages.csv. The command line exits
// with status 2 for it, as for a ConfigError (core/Config.h), which names a JSON path.
#pragma once
#include <stdexcept>

namespace crumble {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace crumble
