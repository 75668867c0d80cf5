// What the HTML report costs on top of an identification of a 90 s log (issue: "rendering the
// report adds under 1 s to a 90 s log's identify").
//
//   report_bench                              Google Benchmark timings
//   report_bench --sample_report=DIR          also writes the full report (linear + refined,
//                                             identification + held-out flight) into DIR, with
//                                             the gnuplot scripts in DIR/gnuplot
//
// The flights are synthetic (tests/report/synthetic_flight.h): 200 Hz logs of the paper's
// configuration A whose rotor signal leads the motion by 15 ms, so that refining a delay changes
// the figures.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include "report/synthetic_flight.h"
#include "rotorid/ident/identify.h"
#include "rotorid/refine/refine.h"
#include "rotorid/report/html_report.h"
#include "rotorid/report/json.h"
#include "rotorid/report/refine_json.h"

namespace rotorid {
namespace {

struct Fixture {
  FlightLog log_90s;
  std::vector<FlightData> flights;
  IdentifyOptions identify;
  std::unique_ptr<IdentificationResult> linear;
  std::unique_ptr<RefineResult> refined;
  ProcessedFlight held_out;
  RefineOptions refine;
};

const Fixture& GetFixture() {
  static const Fixture* fixture = [] {
    auto* f = new Fixture;
    const Vehicle vehicle = testing::PaperVehicleA();
    testing::SyntheticFlightOptions options;
    options.duration_s = 90.0;
    options.delay_s = 0.015;
    options.gyro_noise_radps = 0.01;
    options.acc_noise_mps2 = 0.15;
    f->log_90s = testing::SyntheticFlight(vehicle, testing::PaperParametersA(), options, "synthetic_90s.csv");
    f->flights = {{vehicle, f->log_90s, 1.0}};
    f->linear = std::make_unique<IdentificationResult>(Identify(f->flights, f->identify));
    f->refine.effects = {ParseEffectKind("delay")};
    f->refined = std::make_unique<RefineResult>(Refine(*f->linear, f->refine));
    options.duration_s = 60.0;
    options.seed = 7;
    f->held_out =
        ProcessFlight(testing::SyntheticFlight(vehicle, testing::PaperParametersA(), options, "held_out_60s.csv"),
                      vehicle, 1.0, f->identify.observation);
    return f;
  }();
  return *fixture;
}

// What `identify --report` adds: one flight, the linear parameters.
ReportInput IdentifyReportInput(const Fixture& f) {
  ReportInput input;
  input.title = "rotorid identify (benchmark)";
  input.command = "identify";
  input.rotorid_version = kRotoridVersion;
  input.observation = f.identify.observation;
  input.settings = SettingsRows(
      {{"observation", ObservationOptionsJson(f.identify.observation)}, {"tls", TlsOptionsJson(f.identify.tls)}});
  input.linear = f.linear.get();
  input.flights = {{"synthetic 90 s flight", &f.linear->flights[0], false}};
  input.parameter_sets = {{"linear", NamedParameters(f.linear->system, f.linear->solution.chi), Effects()}};
  return input;
}

// What a refine report with a held-out flight draws: two flights, linear and refined side by side.
ReportInput RefineReportInput(const Fixture& f) {
  ReportInput input = IdentifyReportInput(f);
  input.title = "rotorid refine (benchmark)";
  input.command = "refine";
  input.settings = SettingsRows({{"observation", ObservationOptionsJson(f.identify.observation)},
                                 {"tls", TlsOptionsJson(f.identify.tls)},
                                 {"refine", RefineOptionsJson(f.refine)}});
  input.refined = f.refined.get();
  input.flights.push_back({"synthetic 60 s flight", &f.held_out, true});
  input.parameter_sets.push_back(
      {"refined", NamedParameters(f.linear->system, f.refined->refined.chi), f.refined->effects});
  return input;
}

void RenderAndCount(benchmark::State& state, const ReportInput& input) {
  const std::string dir = (std::filesystem::temp_directory_path() / "rotorid-report-bench").string();
  ReportOptions options;
  options.print_warnings = false;
  ReportSummary summary;
  for (auto _ : state) summary = WriteHtmlReport(dir, input, options);
  state.counters["figures"] = static_cast<double>(summary.figure_paths.size());
  state.counters["html_MB"] = static_cast<double>(std::filesystem::file_size(summary.html_path)) / 1e6;
  if (!summary.figures_drawn) state.SkipWithError("figures were not drawn (is gnuplot installed?)");
  std::filesystem::remove_all(dir);
}

// Reference: the identification the report is added to (reading excluded: the log is in memory).
void BM_Identify90s(benchmark::State& state) {
  const Fixture& f = GetFixture();
  for (auto _ : state) benchmark::DoNotOptimize(Identify(f.flights, f.identify));
}
BENCHMARK(BM_Identify90s)->Unit(benchmark::kMillisecond)->Iterations(5);

void BM_IdentifyReport90s(benchmark::State& state) { RenderAndCount(state, IdentifyReportInput(GetFixture())); }
BENCHMARK(BM_IdentifyReport90s)->Unit(benchmark::kMillisecond)->Iterations(5);

void BM_RefineReport90sPlusHeldOut(benchmark::State& state) { RenderAndCount(state, RefineReportInput(GetFixture())); }
BENCHMARK(BM_RefineReport90sPlusHeldOut)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace
}  // namespace rotorid

int main(int argc, char** argv) {
  // Our own flag first; Google Benchmark rejects flags it does not know.
  std::string sample_dir;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    const char* prefix = "--sample_report=";
    if (std::strncmp(argv[i], prefix, std::strlen(prefix)) == 0)
      sample_dir = argv[i] + std::strlen(prefix);
    else
      argv[kept++] = argv[i];
  }
  argc = kept;
  if (!sample_dir.empty()) {
    rotorid::ReportOptions options;
    options.keep_gnuplot_files = true;
    const rotorid::ReportSummary summary =
        rotorid::WriteHtmlReport(sample_dir, rotorid::RefineReportInput(rotorid::GetFixture()), options);
    std::printf("sample report: %s (%zu figures)\n", summary.html_path.c_str(), summary.figure_paths.size());
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
