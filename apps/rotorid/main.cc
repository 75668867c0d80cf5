// rotorid: identification of multirotor inertia parameters and propeller coefficients from
// flight logs, refinement with unmodelled effects, and diagnosis of the model's residual.

#include <iostream>

#include <glog/logging.h>

#include "commands.h"
#include "rotorid/core/error.h"

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  FLAGS_minloglevel = google::GLOG_WARNING;

  CLI::App root{"rotorid: identifies a multirotor's inertia parameters and propeller coefficients from flight logs "
                "(IDIM-TLS, Six et al. RA-L 2020), refines them with unmodelled effects, and diagnoses what the model "
                "still gets wrong."};
  root.require_subcommand(1);
  root.set_version_flag("--version", "rotorid 0.1.0");
  using namespace rotorid::cli;
  const std::vector<Command> commands = {AddSimulateCommand(root), AddIdentifyCommand(root), AddValidateCommand(root),
                                         AddRefineCommand(root),   AddDelayCommand(root),    AddAblateCommand(root),
                                         AddDiagnoseCommand(root)};
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return root.exit(e);
  }
  try {
    for (const Command& command : commands)
      if (command.app->parsed()) return command.run();
  } catch (const rotorid::Error& e) {
    std::cerr << "rotorid: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "rotorid: internal error: " << e.what() << "\n";
    return 3;
  }
  return 2;
}
