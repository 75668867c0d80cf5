#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the validate issue lands: registers the subcommand and refuses to run.
Command AddValidateCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("validate", "validate (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'validate' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
