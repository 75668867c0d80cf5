#include "commands.h"

#include "rotorid/core/error.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/io/vehicle_yaml.h"

namespace rotorid::cli {

void AddFlightOptions(CLI::App* app, FlightOptions* options, bool held_out) {
  app->add_option("--vehicle", options->vehicle_paths, "vehicle file (YAML); repeat for several configurations")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--log", options->log_paths, "flight log, paired in order with --vehicle")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("--weight", options->weights, "weight of each --vehicle/--log pair (default 1)");
  if (held_out) {
    app->add_option("--validate-vehicle", options->validate_vehicle_paths, "vehicle file of a held-out flight")
        ->check(CLI::ExistingFile);
    app->add_option("--validate-log", options->validate_log_paths, "held-out flight log, paired with --validate-vehicle")
        ->check(CLI::ExistingFile);
  }
  app->add_option("--json", options->json_path, "write the machine-readable report here");
  app->add_option("--report", options->report_dir, "write an HTML report with figures into this folder");
  app->add_flag("--quiet,-q", options->quiet, "print nothing but errors");
  app->add_flag("--verbose,-v", options->verbose, "print solver details");
}

std::vector<Flight> LoadFlights(const std::vector<std::string>& vehicle_paths, const std::vector<std::string>& log_paths,
                                const std::vector<double>& weights) {
  if (vehicle_paths.size() != log_paths.size())
    throw Error("got " + std::to_string(vehicle_paths.size()) + " vehicle files and " +
                std::to_string(log_paths.size()) + " logs; give them in pairs");
  if (!weights.empty() && weights.size() != log_paths.size())
    throw Error("got " + std::to_string(weights.size()) + " --weight values for " + std::to_string(log_paths.size()) +
                " flights; give one per flight or none");
  std::vector<Flight> flights;
  for (size_t i = 0; i < log_paths.size(); ++i) {
    Flight flight;
    flight.vehicle = ReadVehicleYaml(vehicle_paths[i]);
    flight.log = LoadFlightLog(log_paths[i], flight.vehicle);
    flight.weight = weights.empty() ? 1.0 : weights[i];
    if (!(flight.weight > 0.0)) throw Error("--weight must be positive, got " + std::to_string(flight.weight));
    flights.push_back(std::move(flight));
  }
  return flights;
}

std::vector<Flight> LoadTrainingFlights(const FlightOptions& options) {
  return LoadFlights(options.vehicle_paths, options.log_paths, options.weights);
}

std::vector<Flight> LoadValidationFlights(const FlightOptions& options) {
  return LoadFlights(options.validate_vehicle_paths, options.validate_log_paths, {});
}

}  // namespace rotorid::cli
