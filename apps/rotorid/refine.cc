#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the refine issue lands: registers the subcommand and refuses to run.
Command AddRefineCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("refine", "refine (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'refine' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
