#pragma once

// Flight phases of thrown and self-launched FPV quads (blackbox logs), and segmentation settings
// for them. The general segmentation (rotorid/io/segmentation.h) assumes a take-off from the
// ground with a 1 s margin and a 4 g impact threshold: on a 3-inch quad that is launched by hand
// or by a 3.5 g boost and excited by 100 ms single-motor pulses, that margin swallows the most
// informative half second, and FPV flight itself reaches 7-8 g. docs/blackbox.md has the numbers.

#include <string>
#include <vector>

#include "rotorid/core/flight_log.h"
#include "rotorid/io/segmentation.h"

namespace rotorid {

enum class FlightPhase {
  kMotorsStopped,  // every rotor signal below stopped_fraction of its flying median
  kArmedIdle,      // rotors turning but below ground_thrust_fraction of hover, vehicle at rest
  kFreeFall,       // specific force below free_fall_g: ballistic (thrown, or rotors spun down)
  kPowered,        // everything else: flying under power (or carried by hand)
};

// "motors stopped", "armed idle", "free fall", "powered".
const char* ToString(FlightPhase phase);

struct FlightPhaseOptions {
  // Rotor signal below this fraction of its median over the running samples: stopped. Default 0.05.
  double stopped_fraction = 0.05;
  // Specific-force norm below this (in g) over a free_fall_window_s moving average: free fall.
  // Defaults: 0.3 g, 0.02 s.
  double free_fall_g = 0.3;
  double free_fall_window_s = 0.02;
  // Phases shorter than this merge into the one before. Default: 0.02 s.
  double min_phase_s = 0.02;

  std::string Validate() const;
};

struct FlightPhaseSpan {
  FlightPhase phase = FlightPhase::kPowered;
  int begin = 0, end = 0;  // samples [begin, end)
  double t_begin_s = 0.0, t_end_s = 0.0;
};

// The log cut into consecutive phases (covering every sample). `segmentation` supplies the rest
// test and the hover-thrust fraction. Throws rotorid::Error for invalid options.
std::vector<FlightPhaseSpan> FlightPhases(const FlightLog& log, const FlightPhaseOptions& options = {},
                                          const SegmentationOptions& segmentation = {});
// One line per phase, for the CLI and the docs.
std::string PhaseReport(const std::vector<FlightPhaseSpan>& phases);

// Segmentation settings for thrown / self-launched FPV quads: take-off margin 0.1 s, landing
// margin 0.3 s, impacts above 10 g or 20000 rad/s^2, gyro limit 34 rad/s (0.97 of +-2000 deg/s),
// kept stretches from 0.3 s.
SegmentationOptions ThrownQuadSegmentationOptions();

// SegmentFlight with `options`, then also leaves out every "motors stopped" phase (a vehicle that
// moves with its motors stopped is carried by hand, about to be thrown) as "on ground" with the
// detail "motors stopped", dropping kept pieces shorter than options.min_segment_s. The pose's
// height is not used (the resting height of a thrown vehicle is a hand's, not the floor's).
Segmentation SegmentThrownFlight(const FlightLog& log,
                                 const SegmentationOptions& options = ThrownQuadSegmentationOptions());

}  // namespace rotorid
