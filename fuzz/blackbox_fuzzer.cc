// libFuzzer target for the blackbox decoder: arbitrary bytes must decode (losing what is damaged)
// or throw rotorid::Error, never crash, hang or trip the sanitizers. Each decoded log is also
// mapped to a flight, so that the header values and fields the decoder accepted are exercised.
// Inputs that do not start with a log header get one prepended on odd lengths, so that the
// fuzzer reaches the frame decoder without first having to find the 60-byte header line.
//
//   ./fuzz/blackbox_fuzzer -runs=1000000 corpus_dir

#include <cstddef>
#include <cstdint>
#include <string>

#include "rotorid/core/error.h"
#include "rotorid/io/blackbox.h"
#include "rotorid/io/blackbox_flight.h"

namespace {

const char kHeader[] =
    "H Product:Blackbox flight data recorder by Nicholas Sherlock\nH Data version:2\n"
    "H Field I name:loopIteration,time,gyroADC[0],gyroADC[1],gyroADC[2],accSmooth[0],accSmooth[1],accSmooth[2],"
    "motor[0],motor[1],motor[2],motor[3],vbatLatest,eRPM[0],eRPM[1],eRPM[2],eRPM[3]\n"
    "H Field I signed:0,0,1,1,1,1,1,1,0,0,0,0,0,0,0,0,0\n"
    "H Field I predictor:0,0,0,0,0,0,0,0,11,5,5,5,9,0,0,0,0\n"
    "H Field I encoding:1,1,0,0,0,0,0,0,1,0,0,0,3,1,1,1,1\n"
    "H Field P predictor:6,2,3,3,3,1,1,1,3,3,3,3,1,1,1,1,1\n"
    "H Field P encoding:9,0,7,7,7,10,10,10,8,8,8,8,0,6,6,6,6\n"
    "H Field S name:flightModeFlags\nH Field S signed:0\nH Field S predictor:0\nH Field S encoding:1\n"
    "H I interval:32\nH P interval:4\nH acc_1G:2048\nH motorOutput:158,2047\nH vbatref:1600\n"
    "H motor_poles:14\nH motor_pwm_protocol:7\nH Firmware revision:Betaflight 4.4.0\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size % 2 == 1 && !rotorid::LooksLikeBlackbox(bytes)) bytes = kHeader + bytes;
  try {
    const std::vector<rotorid::BlackboxLog> logs = rotorid::DecodeBlackbox(bytes, "fuzz.bbl");
    std::size_t sum = 0;
    for (const rotorid::BlackboxLog& log : logs) {
      sum += log.Summary().size();
      try {
        const rotorid::FlightLog flight = rotorid::BlackboxToFlight(log, "fuzz.bbl");
        sum += static_cast<std::size_t>(flight.num_samples());
      } catch (const rotorid::Error&) {
        // Expected: a log without the fields a flight needs.
      }
    }
    if (sum == 12345) return 0;  // keeps the work from being optimised away
  } catch (const rotorid::Error&) {
    // Expected for input without any log header.
  }
  return 0;
}
