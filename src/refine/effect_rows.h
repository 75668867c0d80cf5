#pragma once

// Internal: the IDIM rows of a flight's row samples with effects, differentiated with respect to
// the scalar coordinates of the free effects by ceres::Jet. The one model that the refinement's
// residual blocks and the diagnosis' linearisation both evaluate, so that their derivatives
// cannot disagree. Per sample: the IMU effects correct the logged IMU, then the rotor-wrench
// effects change the rotor columns (per-rotor factors) and the known column (their extra wrench).

#include <Eigen/Core>
#include <vector>

#include "rotorid/ident/observation.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid::internal {

class EffectRows {
 public:
  // `rotor`: the rotor signal at the row samples with derivatives with respect to the free
  // rotor-signal effects (EffectiveRotorAtRows(flight, effects, free rotor-signal effects)); it
  // must outlive this object.
  EffectRows(const ProcessedFlight* flight, const Effects& effects, const std::vector<EffectKind>& free,
             const EffectiveRotor* rotor);

  // One free scalar coordinate: its effect (index into `free`), its index in the effect, and for
  // rotor-signal effects its derivative in `rotor` (else -1).
  struct Coordinate {
    int effect, index, rotor_derivative;
  };
  const std::vector<Coordinate>& coordinates() const { return coordinates_; }

  // The effects' values of one pass over the row samples (scalar type T, Jet slots from coordinate
  // `first`): the same at every row sample, so built once per pass rather than per row.
  template <typename T>
  struct PassValues {
    size_t first = 0, last = 0;  // the coordinates [first, last) whose derivatives this pass carries
    std::vector<Eigen::Matrix<T, Eigen::Dynamic, 1>> imu, wrench;
    std::vector<const T*> imu_pointers, wrench_pointers;  // into imu and wrench
  };
  template <typename T>
  PassValues<T> Pass(size_t first = 0) const;

  // The 6 rows of row sample `row_sample`; with T a Jet, its slot k is the derivative with respect
  // to coordinate pass.first + k (those beyond the last coordinate stay zero).
  template <typename T>
  Eigen::Matrix<T, 6, kNumIdimColumns> Rows(int row_sample, const PassValues<T>& pass) const;
  template <typename T>
  Eigen::Matrix<T, 6, kNumIdimColumns> Rows(int row_sample, size_t first = 0) const {
    return Rows<T>(row_sample, Pass<T>(first));
  }

 private:
  const ProcessedFlight* flight_;
  const EffectiveRotor* rotor_;
  // The acting effects (non-zero or free) of the stages evaluated per sample, chain order, and
  // per link its index into `free` (or -1).
  struct Stage {
    EffectChain chain;
    std::vector<int> free_index;
  };
  Stage imu_, wrench_;
  bool imu_rates_ = false;  // an IMU effect of the chain reads s' and s''
  std::vector<Coordinate> coordinates_;
};

}  // namespace rotorid::internal
