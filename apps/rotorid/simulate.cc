#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the simulate issue lands: registers the subcommand and refuses to run.
Command AddSimulateCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("simulate", "simulate (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'simulate' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
