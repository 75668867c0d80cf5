// libFuzzer target for column maps and the CSV read through them: arbitrary bytes must either
// parse or throw rotorid::Error, never crash, hang or trip the sanitizers.
//
// An input holding a NUL byte is split there into a map (before) and a CSV (after). Any input
// is also read as a map on its own, and as a CSV through a fixed map that uses every optional
// quantity, so that both parsers see every mutation.
//
//   ./fuzz/column_map_fuzzer -runs=1000000 corpus_dir

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "rotorid/core/error.h"
#include "rotorid/io/column_map.h"

namespace {

const char* kFixedMap = R"(time: {column: t, unit: us}
gyro: {columns: [gx, gy, gz], unit: deg/s}
acc: {columns: [ax, ay, az], unit: g}
rotors: {columns: [r1, r2], unit: rpm}
rotor_commands: {columns: [u1, u2], unit: us, range: [1000, 2000]}
position: {columns: [x, y, z], unit: mm}
quaternion: {columns: [qw, qx, qy, qz]}
voltage: {column: v, unit: mV}
frame: frd
comment: "#"
)";

void ReadCsv(std::string_view csv, const rotorid::ColumnMap& map, size_t selector) {
  static const char* kSignals[] = {"auto", "rpm", "command"};
  try {
    const rotorid::FlightLog log =
        rotorid::ParseMappedCsv(csv, "fuzz.csv", map, (selector & 4) ? 2 : -1, kSignals[selector % 3]);
    double sum = log.t_s.sum() + log.gyro_radps.sum() + log.rotor_radps.sum();
    if (log.mocap) sum += log.mocap->bryant_rad.sum();
    if (sum == 1.2345) std::abort();
  } catch (const rotorid::Error&) {
    // Expected for malformed input.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const rotorid::ColumnMap fixed_map = rotorid::ParseColumnMap(kFixedMap, "fixed.yaml");
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const size_t nul = text.find('\0');
  if (nul != std::string_view::npos) {
    try {
      const rotorid::ColumnMap map = rotorid::ParseColumnMap(std::string(text.substr(0, nul)), "fuzz.yaml");
      ReadCsv(text.substr(nul + 1), map, size);
    } catch (const rotorid::Error&) {
    }
    return 0;
  }
  try {
    rotorid::ParseColumnMap(std::string(text), "fuzz.yaml");
  } catch (const rotorid::Error&) {
  }
  ReadCsv(text, fixed_map, size);
  return 0;
}
