#pragma once

// A Betaflight / INAV blackbox log (rotorid/io/blackbox.h) as one rotorid flight (INTERFACE.md
// conventions: FLU body, SI units), and a Quad-X vehicle for it. docs/blackbox.md has the mapping:
//
//   time         `time` (us since boot) -> t_s from 0 at the first frame
//   gyro         gyroADC[0..2]: deg/s x gyro_scale (header float), / 10 with
//                blackbox_high_resolution:1; a gyro_scale below 1e-3 is old Cleanflight's rad/us
//   acc          accSmooth[0..2] / acc_1G x 9.80665
//   rotor        measured speed: omega[i] (rad/s, forks such as Indiflight), or eRPM[i]
//                (eRPM / 100, Betaflight 4.3+) x 100 x 2 / motor_poles x 2 pi / 60; else the
//                command motor[i] normalised to 0..1 (metadata `rotor_signal: command`): DShot
//                (motor_pwm_protocol 5..8) u = (m - 48) / (motorOutput[1] - 48), other protocols
//                u = (m - 1000) / (motorOutput[1] - 1000)
//   voltage      vbatLatest x 0.01 V (Betaflight >= 4, INAV; older firmware: not mapped)
//   pose         forks that uplink motion capture (Indiflight): position extPos[0..2] (mm, NED)
//                and velocity extVel[0..2] (cm/s, NED) as world (x, -y, -z), interpolated
//                linearly between the frames where they change (a new mocap sample, 24 Hz on the
//                TU Delft logs); attitude the onboard quat[0..3] (FRD body -> NED, every frame),
//                else extAtt[0..2] (mrad roll, pitch, yaw), as FLU body -> z-up world
//
// Betaflight's gyroADC and accSmooth are already FLU (x forward, y left, z up: roll positive
// right side down, pitch positive nose down, yaw positive nose left), so only units change.
// Rotor columns keep Betaflight's motor order: rotor i is motor[i] (Betaflight's motor i+1;
// Quad-X: rear-right, front-right, rear-left, front-left).

#include <string>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"
#include "rotorid/io/blackbox.h"

namespace rotorid {

struct BlackboxFlightOptions {
  // Which log of the file, 1-based; 0 takes the log with the most main frames. Default: 0.
  int log_index = 0;
  // "auto" (measured speed when the log has omega[] or eRPM[], else the command), "rpm" or
  // "command". Default: "auto".
  std::string rotor_signal = "auto";

  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// The log `options.log_index` picks from a decoded file (throws when it does not exist, or its
// header is unusable).
const BlackboxLog& SelectBlackboxLog(const std::vector<BlackboxLog>& logs, const std::string& source,
                                     int log_index = 0);

// The flight in one decoded log with `num_rotors` rotor columns (<= 0: the log's motor count).
// Frames whose time does not increase are dropped (counted in metadata). Throws rotorid::Error
// naming `source`, the log and the fields looked for when a needed field is missing.
FlightLog BlackboxToFlight(const BlackboxLog& log, const std::string& source, int num_rotors = -1,
                           const BlackboxFlightOptions& options = {});
// Reads a file, picks the log and maps it.
FlightLog LoadBlackboxFlight(const std::string& path, int num_rotors = -1, const BlackboxFlightOptions& options = {});

// What a Quad-X vehicle needs beyond the blackbox header, which records neither.
struct QuadXGeometry {
  double arm_length_m = 0.0;  // hub-to-centre distance of each rotor (m); required
  double mass_kg = 0.0;       // 0: unknown (the user must then set it in the vehicle file)
  bool props_out = false;     // reversed props (Betaflight's yaw_motors_reversed)
};

// A Quad-X vehicle in Betaflight's motor order (rotor i = motor[i]): hubs at 45 degrees,
// rear-right (-d, -d), front-right (d, -d), rear-left (-d, d), front-left (d, d) with
// d = arm / sqrt(2), z = 0; spins (props in) -1, +1, +1, -1 (CW, CCW, CCW, CW seen from above),
// all negated when props_out or the header says yaw_motors_reversed:1. Throws rotorid::Error
// asking for the geometry when arm_length_m is not positive, and saying why when the header
// does not describe a Quad-X (motor count other than 4, or a mixer other than QUADX).
Vehicle SuggestVehicleFromBlackboxHeader(const BlackboxLog& log, const QuadXGeometry& geometry,
                                         const std::string& name = "A");

}  // namespace rotorid
