// libFuzzer target for the Crazyflie micro-SD log reader and its mapping to a flight: arbitrary
// bytes must either parse or throw rotorid::Error, never crash, hang or trip the sanitizers.
//
// Each input is read three ways: as is (CRC checked, so almost every mutation stops there),
// with the CRC check off (so the header and record framing see the mutations), and with a
// valid CRC put in place of the last 4 bytes. Logs that parse are mapped to a flight with each
// rotor signal choice, which exercises the variable lookup, unit conversion and mocap resampling.
//
//   ./fuzz/crazyflie_usd_fuzzer -runs=1000000 corpus_dir

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "rotorid/core/error.h"
#include "rotorid/io/crazyflie_flight.h"
#include "rotorid/io/crazyflie_usd.h"

namespace {

void MapToFlight(const rotorid::CrazyflieUsdLog& log, size_t size) {
  static const char* kSignals[] = {"auto", "rpm", "command"};
  rotorid::CrazyflieFlightOptions options;
  options.rotor_signal = kSignals[size % 3];
  try {
    const rotorid::FlightLog flight = rotorid::CrazyflieUsdToFlight(log, (size & 4) ? 4 : -1, options);
    double sum = flight.t_s.sum() + flight.rotor_radps.sum();
    if (flight.mocap) sum += flight.mocap->bryant_rad.sum();
    if (sum == 1.2345) std::abort();  // keeps the work from being optimised away
  } catch (const rotorid::Error&) {
    // Expected: missing variables, too few records, time going backwards.
  }
}

void Parse(std::string_view bytes, bool verify_crc, bool map) {
  rotorid::CrazyflieUsdOptions options;
  options.verify_crc = verify_crc;
  try {
    const rotorid::CrazyflieUsdLog log = rotorid::ParseCrazyflieUsd(bytes, "fuzz.bin", options);
    double sum = 0.0;
    for (const rotorid::UsdEventTable& event : log.events) {
      for (const auto& column : event.columns)
        for (const double v : column) sum += v;
    }
    if (sum == 1.2345) std::abort();
    if (map) MapToFlight(log, bytes.size());
  } catch (const rotorid::Error&) {
    // Expected for malformed input.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  Parse(bytes, /*verify_crc=*/true, /*map=*/false);
  Parse(bytes, /*verify_crc=*/false, /*map=*/true);
  if (size >= 4) {
    std::string fixed(bytes);
    const uint32_t crc = rotorid::Crc32(fixed.data(), fixed.size() - 4);
    std::memcpy(&fixed[fixed.size() - 4], &crc, 4);
    Parse(fixed, /*verify_crc=*/true, /*map=*/false);
  }
  return 0;
}
