#include "rotorid/report/input_json.h"

namespace rotorid {

nlohmann::json FlightInputJson(const FlightInputSummary& s) {
  nlohmann::json kept = nlohmann::json::array();
  for (const KeptStretch& k : s.kept) kept.push_back({{"start", k.start_s}, {"end", k.end_s}});
  nlohmann::json left_out = nlohmann::json::array();
  for (const LeftOutStretch& l : s.left_out) {
    nlohmann::json entry = {{"start", l.start_s}, {"end", l.end_s}, {"reason", l.reason}};
    if (!l.detail.empty()) entry["detail"] = l.detail;
    left_out.push_back(entry);
  }
  nlohmann::json j = {{"file", s.file},
                      {"format", s.format},
                      {"log_span_s", {s.log_start_s, s.log_end_s}},
                      {"window_s", s.window ? nlohmann::json{s.window->start_s, s.window->end_s} : nlohmann::json()},
                      {"segment", s.segment_mode},
                      {"used_s", s.used_s},
                      {"sample_rates_hz", {{"imu", s.imu_rate_hz}}},
                      {"rotor_signal", s.rotor_signal},
                      {"rotor_signal_source", s.rotor_signal_source},
                      {"sources", s.sources},
                      {"segments_kept", kept},
                      {"segments_left_out", left_out},
                      {"notes", s.notes}};
  return j;
}

nlohmann::json InputJson(const std::vector<FlightInputSummary>& flights,
                         const std::vector<FlightInputSummary>& validate_flights) {
  nlohmann::json input = {{"flights", nlohmann::json::array()}};
  for (const FlightInputSummary& s : flights) input["flights"].push_back(FlightInputJson(s));
  if (!validate_flights.empty()) {
    input["validate_flights"] = nlohmann::json::array();
    for (const FlightInputSummary& s : validate_flights) input["validate_flights"].push_back(FlightInputJson(s));
  }
  return input;
}

}  // namespace rotorid
