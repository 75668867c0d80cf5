#pragma once

// What the analysing commands (identify, validate, refine, delay, ablate, diagnose) share: the
// flights of a command line read and cut (INTERFACE.md 4), the report sections every command
// writes, and the console texts. Each command's own Run<Command>(options) -> <Command>Result, its
// JSON writer, report builder and console brief live in rotorid/commands/<command>_command.h; the
// CLI only parses its options into these structs and prints.
//
//   CommandInputOptions input;
//   input.training.vehicle_paths = {"A.yaml"};
//   input.training.log_paths = {"A.csv"};
//   if (const std::string problem = input.Validate(); !problem.empty()) ...;  // a usage error
//   LoadedFlights flights = LoadFlights(input.training, input);

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/ident/checks.h"
#include "rotorid/ident/identify.h"
#include "rotorid/io/flight_selection.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/model/effects.h"
#include "rotorid/report/html_report.h"

namespace rotorid {

// The logs of one role (training or held-out), paired in order: vehicle file, log, weight, window.
struct FlightFiles {
  std::vector<std::string> vehicle_paths;
  std::vector<std::string> log_paths;
  std::vector<double> weights;       // empty (all 1) or one per log
  std::vector<std::string> windows;  // empty or one "START,END" per log (ParseTimeWindow)
  // The option the logs came from, for messages ("--log", "--validate-log").
  std::string log_option = "--log";
};

// The flights and the report plumbing of one analysing command.
struct CommandInputOptions {
  FlightFiles training;
  FlightFiles held_out{{}, {}, {}, {}, "--validate-log"};
  SegmentMode segment = SegmentMode::kAuto;
  FlightSourceOptions source;
  // The --config file's options, written into the JSON report as "config" (null: none given).
  nlohmann::json config;
  // The HTML report's folder ("" for none), and whether the console stays silent (progress lines,
  // notes, the report's own warnings).
  std::string report_dir;
  bool quiet = false;
  // Called with each log's "read:" line as it is read (long logs take seconds); may be empty.
  std::function<void(const std::string&)> on_read;
  // Called with notes worth a line on stderr (an effect "all" leaves out); may be empty.
  std::function<void(const std::string&)> on_note;

  // Empty when valid, else what is wrong (a usage error): unpaired vehicle files, weights or
  // windows, a weight that is not positive, an unknown rotor signal (RotorSignalProblem).
  std::string Validate() const;
};

// The flights of the command line: each log cut to its window and segmented, so one log may give
// several flights (one per kept stretch, same vehicle and weight).
struct LoadedFlights {
  std::vector<FlightData> flights;
  std::vector<FlightInputSummary> inputs;  // one per log file, in the order given
};
// Reads the paired flights of `files` (training or options.held_out); throws rotorid::Error naming
// the file at fault.
LoadedFlights LoadFlights(const FlightFiles& files, const CommandInputOptions& options);

// Per-flight first moments: fits the first moment of each held-out flight (FitHeldOutFirstMoments)
// into `parameters`, with the rows `effects` give; returns them by name (empty when the parameters
// share their first moments).
std::map<std::string, double> FitHeldOutFirstMomentsWithEffects(std::vector<ProcessedFlight>* flights,
                                                                std::map<std::string, double>* parameters,
                                                                const Effects& effects);
// {name: value} of FitHeldOutFirstMomentsWithEffects's result (an empty object for none).
nlohmann::json FirstMomentsJson(const std::map<std::string, double>& first_moments);

// The effects an --effects value names. "all" (and "every") leaves out the effects whose inputs a
// training flight lacks (rotor_drag without a velocity, say), with a note through options.on_note
// unless quiet; an effect named explicitly is kept, and the refinement refuses it with the reason.
std::vector<EffectKind> EffectsForFlights(const std::string& list, const IdentificationResult& linear,
                                          const CommandInputOptions& options);

// The head of every command's JSON report: rotorid_version, command, settings.
nlohmann::json CommandJsonHead(const std::string& command, const nlohmann::json& settings);
// Sections every report carries whatever the command: input.flights[] (and
// input.validate_flights[] when `held_out`), and the --config file's options when one was given.
void AddCommonReportSections(const CommandInputOptions& options, const LoadedFlights& training,
                             const LoadedFlights* held_out, nlohmann::json* report);

// The HTML report's parts every command has: title "rotorid COMMAND", version, the signal
// processing, what was read and the run settings (`settings`, the JSON report's "settings").
ReportInput CommandReportInput(const std::string& command, const ObservationOptions& observation,
                               const LoadedFlights& training, const LoadedFlights* held_out,
                               const nlohmann::json& settings);
// Writes the HTML report into options.report_dir (when given) and returns its path ("" without).
std::string WriteCommandReport(const CommandInputOptions& options, const ReportInput& input);

// Console texts: "Fx 1.23 %  Fy ..." of the components that have a value, and the parameter table
// (value, std, %sigma, essential; what a discarded inertia is predicted with and the range a body
// allows it).
std::string ComponentsText(const std::vector<std::optional<double>>& values);
std::string ParameterTableText(const std::vector<std::string>& names, const TlsSolution& solution);
// "delay,motor_lag,...": the effects' names, comma-separated (for --help texts).
std::string EffectListText(const std::vector<EffectKind>& effects);

}  // namespace rotorid
