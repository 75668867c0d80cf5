// rotorid: identification of multirotor inertia parameters and propeller coefficients from
// flight logs, refinement with unmodelled effects, and diagnosis of the model's residual.

#include <glog/logging.h>

#include <iostream>

#include "commands.h"
#include "rotorid/core/error.h"
#include "rotorid/core/heap.h"
#include "rotorid/core/interrupt.h"
#include "rotorid/core/text.h"

namespace {

int UsageFailure(const std::string& message, const std::string& hint) {
  std::cerr << "rotorid: error: " << rotorid::ShortText(message) << " (" << hint << ")\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  rotorid::PrepareHeapForLargeArrays();
  // Before any thread starts: Ctrl-C and SIGTERM remove the run's temporary files (exit 130, 143).
  rotorid::InstallInterruptCleanup();
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  // Library (Ceres, glog) lines reach the console only under --verbose.
  FLAGS_minloglevel = google::GLOG_FATAL;

  CLI::App root{
      "rotorid: identifies a multirotor's inertia parameters and propeller coefficients from flight logs "
      "(IDIM-TLS, Six et al. RA-L 2020), refines them with unmodelled effects, and diagnoses what the model "
      "still gets wrong."};
  root.require_subcommand(1);
  root.set_version_flag("--version", "rotorid 0.1.0");
  using namespace rotorid::cli;
  const std::vector<Command> commands = {AddSimulateCommand(root), AddIdentifyCommand(root), AddValidateCommand(root),
                                         AddRefineCommand(root),   AddDelayCommand(root),    AddAblateCommand(root),
                                         AddDiagnoseCommand(root), AddVehicleCommand(root),  AddExportCommand(root),
                                         AddBatchCommand(root),    AddPredictCommand(root)};
  ApplyConventions(commands);
  AddConfigOption(&root);
  if (const std::string unknown = UnknownSubcommand(root, argc, argv); !unknown.empty())
    return UsageFailure(unknown, "run 'rotorid --help' for the subcommands");
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return root.exit(e);  // --help, --version
    return UsageFailure(e.what(), UsageHint(root, argc, argv));
  }
  for (const Command& command : commands) {
    const CLI::Option* verbose = command.app->get_option_no_throw("--verbose");
    if (command.app->parsed() && verbose && verbose->count() > 0) FLAGS_minloglevel = google::GLOG_INFO;
  }
  try {
    for (const Command& command : commands) {
      if (!command.app->parsed()) continue;
      CheckOutputsAgainstInputs(*command.app);
      return command.run();
    }
  } catch (const UsageError& e) {
    return UsageFailure(e.what(), UsageHint(root, argc, argv));
  } catch (const rotorid::Error& e) {
    if (!OptionsValidated()) return UsageFailure(e.what(), UsageHint(root, argc, argv));
    std::cerr << "rotorid: error: " << rotorid::ShortText(e.what()) << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "rotorid: internal error: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
