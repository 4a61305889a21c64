// Error types shared by every module; the CLI maps them to exit codes.
#pragma once

#include <stdexcept>
#include <string>

namespace carenav {

/** Bad usage or bad input (missing file, malformed profile, corrupt rawlog):
 *  the CLI prints the message and exits with code 2. The message names the
 *  file and what is wrong. */
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

/** Exit codes of the `carenav` binary (docs/design.md, 'Exit codes and errors'). */
enum ExitCode : int { kExitOk = 0, kExitRuntime = 1, kExitInput = 2 };

}  // namespace carenav
