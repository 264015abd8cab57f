#include "commands.hpp"

namespace ncservo::cli {

Handler monitorCommand(CLI::App& command) {
  (void)command;
  return [] { return kExitUsage; };
}

}  // namespace ncservo::cli
