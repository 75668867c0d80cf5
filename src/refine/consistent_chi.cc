#include "refine/consistent_chi.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "rotorid/core/text.h"

namespace rotorid::internal {

std::vector<ChartedBody> ChartBodies(const IdimLayout& layout, const std::map<std::string, double>& mass_kg,
                                     const std::vector<int>& fixed, const Eigen::VectorXd& chi,
                                     std::vector<std::string>* notes) {
  std::vector<ChartedBody> bodies;
  std::vector<int> first_moment_column(layout.config_names.size(), -1);  // of the configuration's first flight
  for (int f = 0; f < layout.num_flights(); ++f) {
    const auto c = static_cast<size_t>(layout.flight_config[static_cast<size_t>(f)]);
    const std::string& config = layout.config_names[c];
    const std::array<int, kNumBodyParameters>& columns = layout.flight_body_columns[static_cast<size_t>(f)];
    if (first_moment_column[c] >= 0) {
      if (columns[0] != first_moment_column[c] && notes)
        notes->push_back(config + ": the first moment of " + layout.flight_source[static_cast<size_t>(f)] +
                         " is not on a chart (one per configuration; the check judges it)");
      continue;
    }
    first_moment_column[c] = columns[0];
    std::array<bool, kNumBodyParameters> held{};
    ConsistentBodyChart::Vector9 value;
    for (int k = 0; k < kNumBodyParameters; ++k) {
      held[k] = std::find(fixed.begin(), fixed.end(), columns[k]) != fixed.end();
      value[k] = chi[columns[k]];
    }
    const auto mass = mass_kg.find(config);
    if (held[3] || held[4] || held[5] || mass == mass_kg.end()) {
      if (notes) notes->push_back(config + ": not on a chart (a diagonal inertia held at 0 is no body)");
      continue;
    }
    bodies.push_back({config, ConsistentBodyChart(mass->second, held, value), columns});
  }
  return bodies;
}

ConsistentChiManifold::ConsistentChiManifold(int ambient_size, const std::vector<int>& fixed,
                                             std::vector<ChartedBody> bodies, Eigen::VectorXd chi_scale)
    : ambient_size_(ambient_size), bodies_(std::move(bodies)), chi_scale_(std::move(chi_scale)) {
  std::vector<bool> claimed(static_cast<size_t>(ambient_size), false);
  for (int k : fixed) claimed[static_cast<size_t>(k)] = true;
  for (const ChartedBody& body : bodies_)
    for (int k : body.columns) claimed[static_cast<size_t>(k)] = true;
  for (int k = 0; k < ambient_size; ++k)
    if (!claimed[static_cast<size_t>(k)]) euclidean_.push_back(k);
  tangent_size_ = static_cast<int>(euclidean_.size());
  for (const ChartedBody& body : bodies_) {
    body_offset_.push_back(tangent_size_);
    tangent_size_ += body.chart.dimension();
  }
}

bool ConsistentChiManifold::BodyCoordinates(size_t b, const double* x, Eigen::VectorXd* coordinates) const {
  ConsistentBodyChart::Vector9 chi;
  for (int k = 0; k < kNumBodyParameters; ++k) {
    const int column = bodies_[b].columns[k];
    chi[k] = x[column] * chi_scale_[column];
  }
  return bodies_[b].chart.Coordinates(chi, coordinates);
}

bool ConsistentChiManifold::BodyJacobian(size_t b, const double* x, Eigen::MatrixXd* jacobian) const {
  Eigen::VectorXd coordinates;
  if (!BodyCoordinates(b, x, &coordinates)) return false;
  using Jet = ceres::Jet<double, kNumBodyParameters>;
  const int dimension = bodies_[b].chart.dimension();
  Jet point[kNumBodyParameters], chi[kNumBodyParameters];
  for (int k = 0; k < dimension; ++k) point[k] = Jet(coordinates[k], k);
  bodies_[b].chart.Body(point, chi);
  jacobian->resize(kNumBodyParameters, dimension);
  for (int k = 0; k < kNumBodyParameters; ++k)
    for (int j = 0; j < dimension; ++j) (*jacobian)(k, j) = chi[k].v[j] / chi_scale_[bodies_[b].columns[k]];
  return true;
}

namespace {

// Where a chart ends for the solver: U's diagonal e^d_i (the RMS extents of the mass, in m) between
// 1 um and 1 km and no smaller than e^-12 of the largest (beyond it round-off in J's factorisation
// could leave the chart), and the other coordinates (lengths in m) within 1 km. Ceres' trust region
// also maps the whole gradient through Plus (its projected-gradient test), a step of any size: it must
// land on a body. A body at that end is thinner than CheckPhysicalConsistency's 1e-9 for flat (a
// simulated B ended 0.16 um thin); an end at 0.1 mm and e^-9 changed the independent simulator's
// thrust-scale diagnosis (acc_bias added), so the end stays where the diagnoses were measured.
void KeepOnChart(Eigen::VectorXd* coordinates) {
  Eigen::VectorXd& c = *coordinates;
  const double high = std::log(1e3);
  const double low = std::max(std::min(c.head<3>().maxCoeff(), high) - 12.0, std::log(1e-6));
  c.head<3>() = c.head<3>().cwiseMax(low).cwiseMin(high);
  c.tail(c.size() - 3) = c.tail(c.size() - 3).cwiseMax(-1e3).cwiseMin(1e3);
}

}  // namespace

bool ConsistentChiManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  std::copy(x, x + ambient_size_, x_plus_delta);
  for (size_t j = 0; j < euclidean_.size(); ++j) x_plus_delta[euclidean_[j]] += delta[j];
  for (size_t b = 0; b < bodies_.size(); ++b) {
    Eigen::VectorXd coordinates;
    if (!BodyCoordinates(b, x, &coordinates)) return false;
    coordinates += Eigen::Map<const Eigen::VectorXd>(delta + body_offset_[b], coordinates.size());
    KeepOnChart(&coordinates);
    ConsistentBodyChart::Vector9 chi;
    bodies_[b].chart.Body(coordinates.data(), chi.data());
    if (!chi.allFinite()) return false;
    for (int k = 0; k < kNumBodyParameters; ++k) {
      const int column = bodies_[b].columns[k];
      x_plus_delta[column] = chi[k] / chi_scale_[column];
    }
  }
  return true;
}

bool ConsistentChiManifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out(jacobian, ambient_size_,
                                                                                         tangent_size_);
  out.setZero();
  for (size_t j = 0; j < euclidean_.size(); ++j) out(euclidean_[j], static_cast<Eigen::Index>(j)) = 1.0;
  for (size_t b = 0; b < bodies_.size(); ++b) {
    Eigen::MatrixXd body;
    if (!BodyJacobian(b, x, &body)) return false;
    for (int k = 0; k < kNumBodyParameters; ++k)
      out.block(bodies_[b].columns[k], body_offset_[b], 1, body.cols()) = body.row(k);
  }
  return true;
}

bool ConsistentChiManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  for (size_t j = 0; j < euclidean_.size(); ++j) y_minus_x[j] = y[euclidean_[j]] - x[euclidean_[j]];
  for (size_t b = 0; b < bodies_.size(); ++b) {
    Eigen::VectorXd at_y, at_x;
    if (!BodyCoordinates(b, y, &at_y) || !BodyCoordinates(b, x, &at_x)) return false;
    Eigen::Map<Eigen::VectorXd>(y_minus_x + body_offset_[b], at_y.size()) = at_y - at_x;
  }
  return true;
}

// The chart's Jacobian has full column rank, so its left inverse is d Minus / d y at y = x along the
// bodies (what Ceres asks of MinusJacobian).
bool ConsistentChiManifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> out(jacobian, tangent_size_,
                                                                                         ambient_size_);
  out.setZero();
  for (size_t j = 0; j < euclidean_.size(); ++j) out(static_cast<Eigen::Index>(j), euclidean_[j]) = 1.0;
  for (size_t b = 0; b < bodies_.size(); ++b) {
    Eigen::MatrixXd body;
    if (!BodyJacobian(b, x, &body)) return false;
    const Eigen::MatrixXd left_inverse = body.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(9, 9));
    for (int k = 0; k < kNumBodyParameters; ++k)
      out.block(body_offset_[b], bodies_[b].columns[k], body.cols(), 1) = left_inverse.col(k);
  }
  return true;
}

namespace {

// A factor L^T of the inverse covariance of the body's estimated parameters in `tls` (the essential
// ones' covariance block, the profiled ones' std), zero columns for the held ones.
Eigen::MatrixXd BodySqrtInformation(const TlsSolution& tls, const std::array<int, kNumBodyParameters>& columns,
                                    ConsistentBodyChart::Vector9* std_dev) {
  Eigen::Matrix<double, kNumBodyParameters, kNumBodyParameters> covariance =
      Eigen::Matrix<double, kNumBodyParameters, kNumBodyParameters>::Zero();
  for (int a = 0; a < kNumBodyParameters; ++a) {
    const int i = columns[a];
    if (tls.Profiled(i)) covariance(a, a) = tls.profiled_std[i] * tls.profiled_std[i];
    for (int b = 0; b < kNumBodyParameters; ++b)
      if (tls.essential[i] && tls.essential[columns[b]]) covariance(a, b) = tls.covariance(i, columns[b]);
  }
  *std_dev = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(covariance);
  const double largest = std::max(eigen.eigenvalues().maxCoeff(), 0.0);
  Eigen::VectorXd inverse_sqrt = Eigen::VectorXd::Zero(kNumBodyParameters);
  for (int a = 0; a < kNumBodyParameters; ++a)
    if (eigen.eigenvalues()[a] > 1e-14 * largest && largest > 0.0)
      inverse_sqrt[a] = 1.0 / std::sqrt(eigen.eigenvalues()[a]);
  return inverse_sqrt.asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace

double ProjectStartOntoCharts(const std::vector<ChartedBody>& bodies, const TlsSolution& tls, Eigen::VectorXd* chi,
                              std::vector<std::string>* moved) {
  double largest = 0.0;
  for (const ChartedBody& body : bodies) {
    ConsistentBodyChart::Vector9 estimate;
    std::array<bool, kNumBodyParameters> held{};
    for (int k = 0; k < kNumBodyParameters; ++k) {
      estimate[k] = (*chi)[body.columns[k]];
      held[k] = !tls.essential[body.columns[k]] && !tls.Profiled(body.columns[k]);
    }
    Eigen::VectorXd coordinates;
    if (body.chart.Coordinates(estimate, &coordinates) &&
        CheckPhysicalConsistency(body.chart.mass(), BodyParameters::FromVector(estimate)).consistent)
      continue;
    ConsistentBodyChart::Vector9 std_dev;
    const Eigen::MatrixXd sqrt_information = BodySqrtInformation(tls, body.columns, &std_dev);
    const ConsistentProjection projection = ProjectOntoConsistentBodies(
        body.chart.mass(), BodyParameters::FromVector(estimate), sqrt_information, std_dev, nullptr, held);
    const ConsistentBodyChart::Vector9 projected = projection.body.ToVector();
    for (int k = 0; k < kNumBodyParameters; ++k) (*chi)[body.columns[k]] = projected[k];
    largest = std::max(largest, projection.distance_std);
    if (moved) moved->push_back(body.name + " " + ShortNumber(projection.distance_std) + " std");
  }
  return largest;
}

}  // namespace rotorid::internal
