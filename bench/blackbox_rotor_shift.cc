// Writes the kept segment (SegmentThrownFlight) of a blackbox log as rotorid CSVs with the rotor
// speed shifted by each given delay: Omega(t) = Omega_log(t - delay), as the `delay` effect's
// definition, but applied before processing, so that the rotor acceleration Omega' the
// `rotor_inertia` effect uses moves with it (the refinement's delay shifts Omega only). Used by
// bench/blackbox_rotor_inertia.sh; docs/blackbox.md 6 has the numbers.
//
//   blackbox_rotor_shift LOG.BFL OUT_PREFIX DELAY_MS...   ->  OUT_PREFIX_<delay>ms.csv

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "rotorid/io/blackbox_flight.h"
#include "rotorid/io/blackbox_segments.h"
#include "rotorid/io/flight_csv.h"
#include "rotorid/signal/resample.h"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: blackbox_rotor_shift LOG.BFL OUT_PREFIX DELAY_MS...\n";
    return 2;
  }
  const rotorid::FlightLog log = rotorid::LoadBlackboxFlight(argv[1], 4);
  const rotorid::SampleRange kept = rotorid::SegmentThrownFlight(log).kept.at(0);
  for (int a = 3; a < argc; ++a) {
    const double delay_ms = std::atof(argv[a]);
    rotorid::FlightLog shifted = log;
    const Eigen::VectorXd t_source = log.t_s.array() - delay_ms * 1e-3;
    shifted.rotor_radps = rotorid::InterpolateLinear(log.t_s, log.rotor_radps, t_source);
    const std::string path = std::string(argv[2]) + "_" + argv[a] + "ms.csv";
    rotorid::WriteFlightCsv(path, shifted.Slice(kept.begin, kept.end));
    std::printf("%s: %.3f-%.3f s, rotor speed shifted by %s ms\n", path.c_str(), log.t_s[kept.begin],
                log.t_s[kept.end - 1], argv[a]);
  }
  return 0;
}
