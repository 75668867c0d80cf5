#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the delay issue lands: registers the subcommand and refuses to run.
Command AddDelayCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("delay", "delay (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'delay' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
