#include "rotorid/core/flight_log.h"

#include <algorithm>
#include <vector>

namespace rotorid {

double FlightLog::MedianDt() const {
  if (t_s.size() < 2) return 0.0;
  std::vector<double> dt(t_s.size() - 1);
  for (Eigen::Index i = 0; i + 1 < t_s.size(); ++i) dt[i] = t_s[i + 1] - t_s[i];
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

FlightLog FlightLog::Slice(int begin, int end) const {
  FlightLog out;
  const int n = end - begin;
  out.source = source;
  out.t_s = t_s.segment(begin, n);
  out.gyro_radps = gyro_radps.middleRows(begin, n);
  out.acc_mps2 = acc_mps2.middleRows(begin, n);
  out.rotor_radps = rotor_radps.middleRows(begin, n);
  if (mocap) {
    out.mocap = MocapTrack{mocap->position_w_m.middleRows(begin, n), mocap->bryant_rad.middleRows(begin, n)};
    if (mocap->velocity_w_mps) out.mocap->velocity_w_mps = mocap->velocity_w_mps->middleRows(begin, n);
  }
  if (voltage_v) out.voltage_v = voltage_v->segment(begin, n);
  if (rotor_command) out.rotor_command = rotor_command->middleRows(begin, n);
  out.gravity_mps2 = gravity_mps2;
  out.metadata = metadata;
  return out;
}

}  // namespace rotorid
