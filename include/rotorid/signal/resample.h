#pragma once

// Putting jittered or multi-rate streams onto one time base.

#include <string>

#include <Eigen/Core>

namespace rotorid {

// A uniform grid from t_begin to t_end (inclusive where it lands) at the given rate.
Eigen::VectorXd UniformTimeBase(double t_begin_s, double t_end_s, double rate_hz);

// Linear interpolation of the columns of x (sampled at strictly increasing t) at t_query. Query
// times outside [t.front(), t.back()] take the end values. Throws rotorid::Error when t is not
// strictly increasing or sizes disagree.
Eigen::MatrixXd InterpolateLinear(const Eigen::Ref<const Eigen::VectorXd>& t, const Eigen::Ref<const Eigen::MatrixXd>& x,
                                  const Eigen::Ref<const Eigen::VectorXd>& t_query);

// Zero-order hold (last value at or before each query), for commands and counters. Queries before
// t.front() take the first value. Throws rotorid::Error like InterpolateLinear.
Eigen::MatrixXd InterpolateHold(const Eigen::Ref<const Eigen::VectorXd>& t, const Eigen::Ref<const Eigen::MatrixXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& t_query);

// Every `factor`-th row starting at row `offset` (call after a low-pass that suits the new rate).
Eigen::MatrixXd Decimate(const Eigen::Ref<const Eigen::MatrixXd>& x, int factor, int offset = 0);

// Unwraps an angle sequence (rad) so that consecutive samples differ by less than pi.
Eigen::VectorXd UnwrapAngle(const Eigen::Ref<const Eigen::VectorXd>& angle_rad);

}  // namespace rotorid
