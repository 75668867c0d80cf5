#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the diagnose issue lands: registers the subcommand and refuses to run.
Command AddDiagnoseCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("diagnose", "diagnose (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'diagnose' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
