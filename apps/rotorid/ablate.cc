#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the ablate issue lands: registers the subcommand and refuses to run.
Command AddAblateCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("ablate", "ablate (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'ablate' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
