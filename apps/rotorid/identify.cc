#include "commands.h"

#include "rotorid/core/error.h"

namespace rotorid::cli {

// Placeholder until the identify issue lands: registers the subcommand and refuses to run.
Command AddIdentifyCommand(CLI::App& root) {
  Command command;
  command.app = root.add_subcommand("identify", "identify (not yet available)");
  command.app->allow_extras();
  command.run = [] () -> int { throw Error("'identify' is not available in this build yet"); };
  return command;
}

}  // namespace rotorid::cli
