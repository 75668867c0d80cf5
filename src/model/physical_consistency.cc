#include "rotorid/model/physical_consistency.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rotorid/core/error.h"
#include "rotorid/core/text.h"

namespace rotorid {

namespace {

// (tr(A)/2) 1 - A: the second-moment matrix int p p^T dm of a body whose inertia is A.
Eigen::Matrix3d SecondMoments(const Eigen::Matrix3d& inertia) {
  return 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
}

std::string AxisText(const Eigen::Vector3d& axis) {
  // An axis has no sign: show it with its largest entry positive.
  Eigen::Index largest = 0;
  axis.cwiseAbs().maxCoeff(&largest);
  const Eigen::Vector3d a = axis[largest] < 0 ? Eigen::Vector3d(-axis) : axis;
  return "(" + FormatValue("%.2f", a.x()) + ", " + FormatValue("%.2f", a.y()) + ", " + FormatValue("%.2f", a.z()) + ")";
}

// The body of mass m whose centre of mass is c and whose second moments about it are sigma_c.
BodyParameters BodyOfSecondMoments(double mass_kg, const Eigen::Vector3d& c, const Eigen::Matrix3d& sigma_c) {
  const Eigen::Matrix3d sigma = sigma_c + mass_kg * c * c.transpose();
  BodyParameters body;
  body.first_moment = mass_kg * c;
  body.inertia = sigma.trace() * Eigen::Matrix3d::Identity() - sigma;
  return body;
}

// (chi(coordinates) - chi0) whitened by sqrt_information, on a chart with the known mass held.
struct ProjectionResidual {
  const ConsistentBodyChart* chart;
  Eigen::Matrix<double, kNumBodyParameters, 1> chi0;
  Eigen::MatrixXd sqrt_information;

  template <typename T>
  bool operator()(T const* const* coordinates, T* residual) const {
    T chi[kNumBodyParameters];
    chart->Body(coordinates[0], chi);
    for (Eigen::Index r = 0; r < sqrt_information.rows(); ++r) {
      residual[r] = T(0.0);
      for (int k = 0; k < kNumBodyParameters; ++k) residual[r] += sqrt_information(r, k) * (chi[k] - chi0[k]);
    }
    return true;
  }
};

// A consistent body near an inconsistent one: its centre of mass, and its second moments about it
// raised to at least `relative_floor` times the largest, and to an RMS extent of at least 1 mm (a body
// with every inertia discarded and held at 0 has none).
BodyParameters RepairedBody(double mass_kg, const PhysicalConsistency& check, double relative_floor) {
  const Eigen::Vector3d sigma = check.second_moments_at_com;
  const double floor = std::max(relative_floor * sigma[2], 1e-6 * mass_kg);
  const Eigen::Vector3d raised = sigma.cwiseMax(floor);
  const Eigen::Matrix3d sigma_c = check.principal_axes * raised.asDiagonal() * check.principal_axes.transpose();
  return BodyOfSecondMoments(mass_kg, check.centre_of_mass_m, sigma_c);
}

}  // namespace

Eigen::Matrix4d PseudoInertia(double mass_kg, const BodyParameters& body) {
  Eigen::Matrix4d j;
  j.topLeftCorner<3, 3>() = SecondMoments(body.inertia);
  j.topRightCorner<3, 1>() = body.first_moment;
  j.bottomLeftCorner<1, 3>() = body.first_moment.transpose();
  j(3, 3) = mass_kg;
  return j;
}

PhysicalConsistency CheckPhysicalConsistency(double mass_kg, const BodyParameters& body, double relative_tolerance) {
  PhysicalConsistency result;
  if (!std::isfinite(mass_kg) || mass_kg <= 0.0) {
    result.problem = "the mass " + ShortNumber(mass_kg) + " kg is not positive";
    return result;
  }
  if (!body.first_moment.allFinite() || !body.inertia.allFinite()) {
    result.problem = "a first moment or inertia is not finite";
    return result;
  }
  const Eigen::Vector3d c = body.first_moment / mass_kg;
  result.centre_of_mass_m = c;
  const Eigen::Matrix3d symmetric = 0.5 * (body.inertia + body.inertia.transpose());
  result.inertia_at_com = symmetric - mass_kg * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> second(SecondMoments(result.inertia_at_com));
  result.second_moments_at_com = second.eigenvalues();
  result.principal_axes = second.eigenvectors();
  // I_c = tr(Sigma_c) 1 - Sigma_c shares Sigma_c's axes: its moments are the sums of the other two.
  const Eigen::Vector3d sigma = result.second_moments_at_com;
  result.principal_moments_at_com = Eigen::Vector3d(sigma[1] + sigma[2], sigma[0] + sigma[2], sigma[0] + sigma[1]);
  std::sort(result.principal_moments_at_com.data(), result.principal_moments_at_com.data() + 3);
  for (int k = 0; k < 3; ++k) result.rms_extent_m[k] = std::copysign(std::sqrt(std::abs(sigma[k]) / mass_kg), sigma[k]);
  const double largest = std::max(sigma.cwiseAbs().maxCoeff(), 0.0);
  result.consistent = sigma[0] > relative_tolerance * largest && largest > 0.0;
  if (!result.consistent) {
    result.problem = "the mass would have an RMS extent of " + ShortNumber(1e3 * result.rms_extent_m[0]) +
                     " mm along " + AxisText(result.principal_axes.col(0)) + " about the centre of mass (" +
                     ShortNumber(1e3 * c.x()) + ", " + ShortNumber(1e3 * c.y()) + ", " + ShortNumber(1e3 * c.z()) +
                     ") mm; inertia about it " + ShortNumber(result.principal_moments_at_com[0]) + ", " +
                     ShortNumber(result.principal_moments_at_com[1]) + ", " +
                     ShortNumber(result.principal_moments_at_com[2]) + " kg m^2";
  }
  return result;
}

InertiaRange AllowedInertiaShift(double mass_kg, const BodyParameters& body, const Eigen::Matrix3d& direction) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!(mass_kg > 0.0) || !body.first_moment.allFinite() || !body.inertia.allFinite()) return {nan, nan};
  // The smallest second moment about the centre of mass is concave in t (the smallest eigenvalue of a
  // matrix affine in it): its maximum by golden section, the two roots by bisection.
  const auto smallest = [&](double t) {
    BodyParameters b = body;
    b.inertia += t * direction;
    return CheckPhysicalConsistency(mass_kg, b, 0.0).second_moments_at_com[0];
  };
  // The search's end: beyond it some second moment is negative whatever the rest, or (a direction that
  // raises every moment) the body has an RMS extent of metres.
  const double upper = (2.0 * (body.inertia.cwiseAbs().sum() + body.first_moment.squaredNorm() / mass_kg) + mass_kg) /
                       std::max(direction.cwiseAbs().maxCoeff(), 1e-300);
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = 0.0, b = upper;
  for (int i = 0; i < 200 && b - a > 1e-15 * upper; ++i) {
    const double x1 = b - golden * (b - a), x2 = a + golden * (b - a);
    if (smallest(x1) < smallest(x2))
      a = x1;
    else
      b = x2;
  }
  const double peak = 0.5 * (a + b);
  if (!(smallest(peak) > 0.0)) return {nan, nan};
  // The root between `outside` (not a body, or the end of the search) and `inside` (a body).
  const auto root = [&](double outside, double inside) {
    if (smallest(outside) > 0.0) return outside;
    for (int i = 0; i < 200 && std::abs(inside - outside) > 1e-15 * upper; ++i) {
      const double middle = 0.5 * (outside + inside);
      if (smallest(middle) > 0.0)
        inside = middle;
      else
        outside = middle;
    }
    return 0.5 * (outside + inside);
  };
  return {root(0.0, peak), root(upper, peak)};
}

InertiaRange AllowedDiagonalInertia(double mass_kg, const BodyParameters& body, int axis) {
  BodyParameters without = body;
  without.inertia(axis, axis) = 0.0;
  Eigen::Matrix3d direction = Eigen::Matrix3d::Zero();
  direction(axis, axis) = 1.0;
  return AllowedInertiaShift(mass_kg, without, direction);
}

namespace {

// theta of the body `chi` (ToVector's order) of mass m: J = U U^T with U upper triangular, from the bottom
// right: U_33 = sqrt(m), U_i3 = ms_i / U_33, and the rest factors J's Schur complement
// Sigma_c = Sigma - ms ms^T / m. False when a pivot is not positive (J not positive definite).
bool LogCholeskyFactor(double mass_kg, const Eigen::Matrix<double, kNumBodyParameters, 1>& chi,
                       Eigen::Matrix<double, kNumLogCholesky, 1>* theta) {
  if (!(mass_kg > 0.0) || !chi.allFinite()) return false;
  const BodyParameters body = BodyParameters::FromVector(chi);
  Eigen::Matrix4d u = Eigen::Matrix4d::Zero();
  u(3, 3) = std::sqrt(mass_kg);
  u.topRightCorner<3, 1>() = body.first_moment / u(3, 3);
  const Eigen::Matrix3d symmetric = 0.5 * (body.inertia + body.inertia.transpose());
  Eigen::Matrix3d rest = SecondMoments(symmetric) - u.topRightCorner<3, 1>() * u.topRightCorner<3, 1>().transpose();
  for (int k = 2; k >= 0; --k) {
    if (!(rest(k, k) > 0.0)) return false;
    u(k, k) = std::sqrt(rest(k, k));
    for (int i = 0; i < k; ++i) u(i, k) = rest(i, k) / u(k, k);
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) rest(i, j) -= u(i, k) * u(j, k);
  }
  const double scale = u(3, 3);
  *theta << std::log(scale), std::log(u(0, 0) / scale), std::log(u(1, 1) / scale), std::log(u(2, 2) / scale),
      u(0, 1) / scale, u(1, 2) / scale, u(0, 2) / scale, u(0, 3) / scale, u(1, 3) / scale, u(2, 3) / scale;
  return true;
}

// theta's entry that a held body parameter fixes (ms_i: t_i; a product of inertia: its s_ij), -1 for
// the diagonal inertia.
constexpr std::array<int, kNumBodyParameters> kThetaOfHeldParameter = {7, 8, 9, -1, -1, -1, 4, 6, 5};

}  // namespace

Eigen::Matrix<double, kNumLogCholesky, 1> LogCholeskyOf(double mass_kg, const BodyParameters& body) {
  const PhysicalConsistency check = CheckPhysicalConsistency(mass_kg, body);
  if (!check.consistent) throw Error("no log-Cholesky parameters: not a physical body: " + check.problem);
  Eigen::Matrix<double, kNumLogCholesky, 1> theta;
  if (!LogCholeskyFactor(mass_kg, body.ToVector(), &theta))
    throw Error("no log-Cholesky parameters: the pseudo-inertia is not positive definite");
  return theta;
}

ConsistentBodyChart::ConsistentBodyChart(double mass_kg, const std::array<bool, kNumBodyParameters>& held,
                                         const Vector9& held_value)
    : mass_(mass_kg), alpha_(0.5 * std::log(mass_kg)), held_(held), held_value_(held_value) {
  if (!(mass_kg > 0.0)) throw Error("a chart of consistent bodies needs a positive mass, got " + ShortNumber(mass_kg));
  std::array<bool, kNumLogCholesky> fixed{};
  for (int k = 0; k < kNumBodyParameters; ++k) {
    if (!held[k]) continue;
    if (kThetaOfHeldParameter[k] < 0)
      throw Error(std::string("a chart of consistent bodies cannot hold ") + kBodyParameterNames[k] +
                  ": no body has a diagonal inertia of 0");
    fixed[kThetaOfHeldParameter[k]] = true;
  }
  for (int t = 1; t < kNumLogCholesky; ++t)
    if (!fixed[t]) free_theta_.push_back(t);
}

bool ConsistentBodyChart::Coordinates(const Vector9& chi, Eigen::VectorXd* coordinates) const {
  Eigen::Matrix<double, kNumLogCholesky, 1> theta;
  if (!LogCholeskyFactor(mass_, chi, &theta)) return false;
  coordinates->resize(dimension());
  for (int k = 0; k < dimension(); ++k) (*coordinates)[k] = theta[free_theta_[k]];
  return true;
}

namespace {

// One Ceres descent on `chart` from a body (its coordinates: ConsistentBodyChart::Coordinates), and the
// projection it ends at.
ConsistentProjection DescendFrom(const ConsistentBodyChart& chart, const BodyParameters& estimate,
                                 const Eigen::MatrixXd& sqrt_information,
                                 const Eigen::Matrix<double, kNumBodyParameters, 1>& std_dev,
                                 const BodyParameters& start_body) {
  Eigen::VectorXd coordinates;
  if (!chart.Coordinates(start_body.ToVector(), &coordinates)) throw Error("the projection's start is no body");
  auto* cost = new ceres::DynamicAutoDiffCostFunction<ProjectionResidual, kNumBodyParameters>(
      new ProjectionResidual{&chart, estimate.ToVector(), sqrt_information});
  cost->AddParameterBlock(chart.dimension());
  cost->SetNumResiduals(static_cast<int>(sqrt_information.rows()));
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, coordinates.data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 500;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ConsistentProjection out;
  out.converged = summary.IsSolutionUsable();
  // A chart holding parameters keeps its end inside, where its J is positive definite beyond round-off:
  // U's diagonal (e^d_i, the RMS extents of the mass left after the rows below, in m) at least 1 mm and
  // e^-7 (a millionth in second moment) of its largest, as RepairedBody keeps a body.
  if (chart.dimension() < kNumLogCholesky - 1) {
    const double floor = std::max(coordinates.head<3>().maxCoeff() - 7.0, std::log(1e-3));
    coordinates.head<3>() = coordinates.head<3>().cwiseMax(floor);
  }
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  chart.Body(coordinates.data(), chi.data());
  out.body = BodyParameters::FromVector(chi);
  // The minimum lies on the boundary (J singular), which the parameterisation approaches without
  // reaching: where the solver stopped closer than CheckPhysicalConsistency tells from flat, the body
  // keeps a millionth of its largest second moment along that axis (a chart holding parameters was kept
  // inside above: the repair would move what it holds).
  if (const PhysicalConsistency reached = CheckPhysicalConsistency(chart.mass(), out.body);
      !reached.consistent && chart.dimension() == kNumLogCholesky - 1)
    out.body = RepairedBody(chart.mass(), reached, 1e-6);
  const Eigen::Matrix<double, kNumBodyParameters, 1> projected = out.body.ToVector();
  out.distance_std = (sqrt_information * (projected - estimate.ToVector())).norm();
  for (int k = 0; k < kNumBodyParameters; ++k) {
    if (!(std_dev[k] > 0.0) || !std::isfinite(std_dev[k])) continue;
    const double move = std::abs(projected[k] - estimate.ToVector()[k]) / std_dev[k];
    if (move > out.largest_move_std) out.largest_move_std = move, out.largest_move_parameter = k;
  }
  return out;
}

}  // namespace

ConsistentProjection ProjectOntoConsistentBodies(double mass_kg, const BodyParameters& estimate,
                                                 const Eigen::MatrixXd& sqrt_information,
                                                 const Eigen::Matrix<double, kNumBodyParameters, 1>& std_dev,
                                                 const BodyParameters* start_body,
                                                 const std::array<bool, kNumBodyParameters>& held) {
  if (sqrt_information.cols() != kNumBodyParameters)
    throw Error("ProjectOntoConsistentBodies: the information factor needs one column per body parameter");
  ConsistentProjection out;
  out.body = estimate;
  const PhysicalConsistency check = CheckPhysicalConsistency(mass_kg, estimate);
  if (check.consistent) return out;
  out.converged = false;
  if (!(mass_kg > 0.0) || !estimate.first_moment.allFinite() || !estimate.inertia.allFinite()) return out;
  // The problem is not convex in theta and its minimum lies on the boundary the parameterisation only
  // approaches: descents from the given body and from the estimate's repairs (its negative second
  // moments raised to a thousandth and to a tenth of the largest) can stop apart (the bundled A + B:
  // 4.7 and 150 std); the nearest end is the projection.
  std::vector<BodyParameters> starts = {RepairedBody(mass_kg, check, 1e-3), RepairedBody(mass_kg, check, 1e-1)};
  if (start_body) starts.push_back(*start_body);
  out.distance_std = std::numeric_limits<double>::infinity();
  const ConsistentBodyChart chart(mass_kg, held, estimate.ToVector());
  for (const BodyParameters& start : starts) {
    if (!CheckPhysicalConsistency(mass_kg, start).consistent) continue;
    const ConsistentProjection descent = DescendFrom(chart, estimate, sqrt_information, std_dev, start);
    if (descent.distance_std < out.distance_std) out = descent;
  }
  if (!std::isfinite(out.distance_std)) out.distance_std = 0.0, out.body = estimate;
  return out;
}

}  // namespace rotorid
