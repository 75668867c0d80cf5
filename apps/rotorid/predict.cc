#include "rotorid/predict/predict.h"

#include <iostream>
#include <memory>

#include "commands.h"
#include "rotorid/report/json.h"

namespace rotorid::cli {

Command AddPredictCommand(CLI::App& root) {
  struct Options {
    PredictOptions predict;
    std::vector<std::string> windows, overrides;
    std::string segment = "auto", scope = "airborne", json_path, report_dir;
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  Command command;
  command.app = root.add_subcommand("predict",
                                    "flies a report's model open loop from every logged state over N steps and "
                                    "scores it against the log and the naive predictor x(t+h) = x(t)");
  CLI::App* app = command.app;
  PredictOptions& p = o->predict;
  app->add_option("--params", p.params_path, "identify/refine report (or simulate --truth)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--vehicle", p.vehicle_paths, "vehicle file (YAML), paired with --log")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--log", p.log_paths, "flight log, paired with --vehicle")->required()->check(CLI::ExistingFile);
  app->add_option("--window", o->windows, "START,END of each --log, in order")->check(ParsesWith(ParseTimeWindow));
  app->add_option("--segment", o->segment, "auto or none")
      ->check(CLI::IsMember({"auto", "none"}))
      ->capture_default_str();
  app->add_option("--column-map", p.source.column_map_path, "column map (YAML) for CSV exports of other tools");
  app->add_option("--rotor-signal", p.source.rotor_signal, "auto, rpm or command")->capture_default_str();
  app->add_option("--horizon", p.horizon_steps, "steps ahead N")->capture_default_str();
  app->add_option("--stride", p.stride, "every K-th start instant")->capture_default_str();
  app->add_option("--dt", p.dt_s, "prediction grid (s)")->capture_default_str();
  app->add_option("--scope", o->scope, "airborne or whole")
      ->check(CLI::IsMember({"airborne", "whole"}))
      ->capture_default_str();
  app->add_option("--block", p.block, "linear or refined (default: refined when present)")
      ->check(CLI::IsMember({"linear", "refined"}));
  app->add_option("--set", o->overrides, "NAME=VALUE: fly with this report parameter replaced (repeatable)")
      ->check(ParsesWith(ParseParameterOverride));
  app->add_option("--torque-bias-window", p.torque_bias_window_s,
                  "seconds before each start over which a torque bias is observed (0: open loop)")
      ->capture_default_str();
  app->add_option("--threads", p.threads, "threads (0: every core)")->capture_default_str();
  app->add_option("--json", o->json_path, "write the machine-readable report to this file");
  app->add_option("--report", o->report_dir, "write predict.html (MAE against h, tables) into this folder");
  app->add_flag("--quiet,-q", o->quiet, "print nothing but errors");
  command.run = [o]() {
    o->predict.scope = ParsePredictionScope(o->scope);
    o->predict.segment = ParseSegmentMode(o->segment);
    for (const std::string& w : o->windows) o->predict.windows.push_back(ParseTimeWindow(w));
    for (const std::string& text : o->overrides) o->predict.parameter_overrides.insert(ParseParameterOverride(text));
    if (const std::string problem = o->predict.Validate(); !problem.empty()) throw UsageError(problem);
    MarkOptionsValidated();
    const PredictResult result = RunPredict(o->predict);
    if (!o->json_path.empty()) WriteJsonFile(o->json_path, PredictJson(result));
    const std::string report = o->report_dir.empty() ? "" : WritePredictReport(o->report_dir, result);
    if (!o->quiet) {
      for (const FlightInputSummary& input : result.inputs) std::cout << input.ConsoleLine() << "\n";
      std::cout << PredictBriefReport(result) << (report.empty() ? "" : "report: " + report + "\n");
    }
    return PrintChecks(result.checks, o->quiet);
  };
  return command;
}

}  // namespace rotorid::cli
