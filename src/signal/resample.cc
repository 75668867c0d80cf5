#include "rotorid/signal/resample.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/units.h"

namespace rotorid {
namespace {

// Guards against a unit mix-up (ms for s, kHz for Hz) silently allocating gigabytes.
constexpr double kMaxTimeBaseSamples = 1e9;

void CheckSamples(const char* function, const Eigen::Ref<const Eigen::VectorXd>& t,
                  const Eigen::Ref<const Eigen::MatrixXd>& x) {
  std::ostringstream message;
  message << function << ": ";
  if (t.size() != x.rows()) {
    message << t.size() << " time stamps but " << x.rows() << " rows of samples";
    throw Error(message.str());
  }
  if (t.size() == 0) {
    message << "needs at least one sample";
    throw Error(message.str());
  }
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    if (!std::isfinite(t[k])) {
      message << "time stamp at sample " << k << " is not finite (" << t[k] << ")";
      throw Error(message.str());
    }
    if (k > 0 && !(t[k] > t[k - 1])) {
      message.precision(17);
      message << "time stamps not strictly increasing at sample " << k << " (t[" << k - 1 << "] = " << t[k - 1]
              << " s, t[" << k << "] = " << t[k] << " s)";
      throw Error(message.str());
    }
  }
}

// Finds, for each query, the last sample at or before it. Sorted queries advance a cursor by galloping
// (O(n + m) in total); a query earlier than the previous one falls back to a binary search.
class SampleLocator {
 public:
  explicit SampleLocator(const Eigen::Ref<const Eigen::VectorXd>& t) : begin_(t.data()), size_(t.size()) {}

  // Largest k with t[k] <= query, or -1 when the query precedes t[0].
  Eigen::Index AtOrBefore(double query) {
    if (query < begin_[cursor_]) {
      cursor_ = std::upper_bound(begin_, begin_ + cursor_, query) - begin_;
      if (cursor_ == 0) return -1;
      return --cursor_;
    }
    Eigen::Index low = cursor_;  // t[low] <= query
    Eigen::Index high = low + 1;
    Eigen::Index step = 1;
    while (high < size_ && begin_[high] <= query) {
      low = high;
      step *= 2;
      high = std::min(low + step, size_);
    }
    // Now t[low] <= query < t[high] (or high == size): binary search in between.
    cursor_ = std::upper_bound(begin_ + low + 1, begin_ + high, query) - begin_ - 1;
    return cursor_;
  }

 private:
  const double* begin_;
  Eigen::Index size_;
  Eigen::Index cursor_ = 0;
};

double CheckedQuery(const char* function, const Eigen::Ref<const Eigen::VectorXd>& t_query, Eigen::Index i) {
  const double query = t_query[i];
  if (std::isnan(query)) {
    throw Error(std::string(function) + ": query time " + std::to_string(i) + " is NaN");
  }
  return query;
}

}  // namespace

Eigen::VectorXd UniformTimeBase(double t_begin_s, double t_end_s, double rate_hz) {
  std::ostringstream message;
  message << "UniformTimeBase: ";
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0)) {
    message << "rate must be positive and finite (got " << rate_hz << " Hz)";
    throw Error(message.str());
  }
  if (!(std::isfinite(t_begin_s) && std::isfinite(t_end_s) && t_end_s >= t_begin_s)) {
    message << "needs finite t_begin <= t_end (got " << t_begin_s << " s to " << t_end_s << " s)";
    throw Error(message.str());
  }
  // The tolerance keeps t_end when it lies on the grid up to rounding.
  const double intervals = std::floor((t_end_s - t_begin_s) * rate_hz + 1e-6);
  if (intervals + 1 > kMaxTimeBaseSamples) {
    message << "a grid from " << t_begin_s << " s to " << t_end_s << " s at " << rate_hz << " Hz would have "
            << intervals + 1 << " samples";
    throw Error(message.str());
  }
  const Eigen::Index count = static_cast<Eigen::Index>(intervals) + 1;
  Eigen::VectorXd t(count);
  // k / rate rather than an accumulated sum, so the grid does not drift over long logs.
  for (Eigen::Index k = 0; k < count; ++k) t[k] = t_begin_s + static_cast<double>(k) / rate_hz;
  return t;
}

Eigen::MatrixXd InterpolateLinear(const Eigen::Ref<const Eigen::VectorXd>& t,
                                  const Eigen::Ref<const Eigen::MatrixXd>& x,
                                  const Eigen::Ref<const Eigen::VectorXd>& t_query) {
  constexpr const char* kFunction = "InterpolateLinear";
  CheckSamples(kFunction, t, x);
  const Eigen::Index n = t.size();
  const Eigen::Index m = t_query.size();
  // Locate every query once, then interpolate column by column over contiguous memory.
  std::vector<Eigen::Index> lower(static_cast<std::size_t>(m)), upper(static_cast<std::size_t>(m));
  std::vector<double> weight(static_cast<std::size_t>(m));
  SampleLocator locator(t);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double query = CheckedQuery(kFunction, t_query, i);
    const Eigen::Index k = locator.AtOrBefore(query);
    const std::size_t slot = static_cast<std::size_t>(i);
    if (k < 0 || k == n - 1) {  // Outside the samples (or on the last one): the end value.
      lower[slot] = upper[slot] = k < 0 ? 0 : n - 1;
      weight[slot] = 0.0;
    } else {
      lower[slot] = k;
      upper[slot] = k + 1;
      weight[slot] = (query - t[k]) / (t[k + 1] - t[k]);
    }
  }
  Eigen::MatrixXd result(m, x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    const double* column = x.col(c).data();
    double* out = result.col(c).data();
    for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i) {
      const double start = column[lower[i]];
      out[i] = start + weight[i] * (column[upper[i]] - start);
    }
  }
  return result;
}

Eigen::MatrixXd InterpolateHold(const Eigen::Ref<const Eigen::VectorXd>& t, const Eigen::Ref<const Eigen::MatrixXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& t_query) {
  constexpr const char* kFunction = "InterpolateHold";
  CheckSamples(kFunction, t, x);
  const Eigen::Index m = t_query.size();
  std::vector<Eigen::Index> source(static_cast<std::size_t>(m));
  SampleLocator locator(t);
  for (Eigen::Index i = 0; i < m; ++i) {
    // Before the first sample nothing has been held yet; the first value is the best guess.
    source[static_cast<std::size_t>(i)] =
        std::max<Eigen::Index>(locator.AtOrBefore(CheckedQuery(kFunction, t_query, i)), 0);
  }
  Eigen::MatrixXd result(m, x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    const double* column = x.col(c).data();
    double* out = result.col(c).data();
    for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i) out[i] = column[source[i]];
  }
  return result;
}

Eigen::MatrixXd Decimate(const Eigen::Ref<const Eigen::MatrixXd>& x, int factor, int offset) {
  if (factor < 1) throw Error("Decimate: factor must be >= 1 (got " + std::to_string(factor) + ")");
  if (offset < 0) throw Error("Decimate: offset must be >= 0 (got " + std::to_string(offset) + ")");
  const Eigen::Index rows = x.rows() > offset ? (x.rows() - 1 - offset) / factor + 1 : 0;
  Eigen::MatrixXd result(rows, x.cols());
  if (rows == 0) return result;
  using StridedMap = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
  result = StridedMap(x.data() + offset, rows, x.cols(),
                      Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(x.outerStride(), factor));
  return result;
}

Eigen::VectorXd UnwrapAngle(const Eigen::Ref<const Eigen::VectorXd>& angle_rad) {
  Eigen::VectorXd unwrapped(angle_rad.size());
  if (angle_rad.size() == 0) return unwrapped;
  unwrapped[0] = angle_rad[0];
  // Whole turns added so far; counting turns (not summing corrections) keeps long logs drift-free.
  double turns = 0.0;
  for (Eigen::Index k = 1; k < angle_rad.size(); ++k) {
    const double step = angle_rad[k] - angle_rad[k - 1];
    if (std::abs(step) >= kPi) {
      // As numpy.unwrap: the step is mapped into [-pi, pi), and a positive step of exactly pi stays pi.
      double step_turns = std::floor((step + kPi) / (2.0 * kPi));
      if (step - 2.0 * kPi * step_turns == -kPi && step > 0.0) step_turns -= 1.0;
      turns -= step_turns;
    }
    unwrapped[k] = angle_rad[k] + 2.0 * kPi * turns;
  }
  return unwrapped;
}

}  // namespace rotorid
