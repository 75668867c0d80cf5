#include "rotorid/ident/body_consistency.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rotorid/core/text.h"

namespace rotorid {
namespace {

// The nine parameter names of one body: its first moment's ("A.flight2.ms_x") and its
// configuration's inertia ("A.I_xx").
std::array<std::string, kNumBodyParameters> BodyNames(const std::string& body, const std::string& config) {
  std::array<std::string, kNumBodyParameters> names;
  for (int k = 0; k < kNumBodyParameters; ++k) names[k] = (k < 3 ? body : config) + "." + kBodyParameterNames[k];
  return names;
}

double Lookup(const std::map<std::string, double>& map, const std::string& name, double otherwise = 0.0) {
  const auto it = map.find(name);
  return it == map.end() ? otherwise : it->second;
}

bool Essential(const CheckedParameters& p, const std::string& name) {
  const auto it = p.essential.find(name);
  return p.value.count(name) && (it == p.essential.end() || it->second);
}

// The value the model predicts with and its std (0: not known).
double Predicted(const CheckedParameters& p, const std::string& name) {
  const auto it = p.predicts_with.find(name);
  return it != p.predicts_with.end() ? it->second : Lookup(p.value, name);
}
double PredictedStd(const CheckedParameters& p, const std::string& name) {
  if (p.predicts_with.count(name)) return Lookup(p.predicts_with_std, name);
  return Essential(p, name) ? Lookup(p.std, name) : 0.0;
}

// A factor L^T of the inverse covariance of the body's known parameters (the covariance block where
// known, else their std), zero columns for those the flights do not fix. Rows: 0 when none is known.
Eigen::MatrixXd SqrtInformation(const CheckedParameters& p, const std::array<std::string, kNumBodyParameters>& names,
                                const Eigen::Matrix<double, kNumBodyParameters, 1>& std_dev) {
  std::vector<int> known;
  for (int k = 0; k < kNumBodyParameters; ++k)
    if (std_dev[k] > 0.0 && std::isfinite(std_dev[k])) known.push_back(k);
  const auto n = static_cast<Eigen::Index>(known.size());
  if (n == 0) return Eigen::MatrixXd(0, kNumBodyParameters);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(n, n);
  std::vector<int> column(kNumBodyParameters, -1);
  for (int k = 0; k < kNumBodyParameters; ++k) {
    const auto it = std::find(p.covariance_names.begin(), p.covariance_names.end(), names[k]);
    if (it != p.covariance_names.end() && Essential(p, names[k]) && !p.predicts_with.count(names[k]))
      column[k] = static_cast<int>(it - p.covariance_names.begin());
  }
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = 0; b < n; ++b) {
      const int i = column[known[a]], j = column[known[b]];
      if (a == b)
        covariance(a, a) = std_dev[known[a]] * std_dev[known[a]];
      else if (i >= 0 && j >= 0 && p.covariance.rows() > std::max(i, j))
        covariance(a, b) = p.covariance(i, j);
    }
  // Cov^(-1/2) through its eigenvalues: a nearly singular block (two parameters the flights only fix as
  // a sum) keeps the directions it knows.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(covariance);
  const double largest = eigen.eigenvalues().maxCoeff();
  Eigen::VectorXd inverse_sqrt = Eigen::VectorXd::Zero(n);
  for (Eigen::Index a = 0; a < n; ++a)
    if (eigen.eigenvalues()[a] > 1e-14 * largest) inverse_sqrt[a] = 1.0 / std::sqrt(eigen.eigenvalues()[a]);
  const Eigen::MatrixXd factor = inverse_sqrt.asDiagonal() * eigen.eigenvectors().transpose();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, kNumBodyParameters);
  for (Eigen::Index a = 0; a < n; ++a) out.col(known[a]) = factor.col(a);
  return out;
}

std::string ValueWithStd(double value, double std_dev) {
  return ShortNumber(value) + (std_dev > 0.0 ? " +- " + ShortNumber(std_dev) : "");
}

// Why the body is none: its discarded inertias, a first moment the flights do not fix, or else the
// mass and geometry the identification assumed.
std::string CauseOf(const CheckedParameters& p, const BodyAssessment& a,
                    const std::array<std::string, kNumBodyParameters>& names) {
  std::vector<std::string> causes;
  std::string discarded;
  for (int k = 3; k < 6; ++k)
    if (!Essential(p, names[k]))
      discarded +=
          (discarded.empty() ? "" : ", ") + std::string(kBodyParameterNames[k]) +
          (p.predicts_with.count(names[k]) ? " (predicted with its estimate " +
                                                 ValueWithStd(Predicted(p, names[k]), PredictedStd(p, names[k])) + ")"
                                           : " (held at 0)");
  if (!discarded.empty())
    causes.push_back("a discarded inertia the flights do not fix: " + discarded +
                     (p.value.count(names[5]) && !Essential(p, names[5])
                          ? "; I_zz's scale needs yaw excitation, or a second configuration with an asymmetric "
                            "payload (the paper's B)"
                          : ""));
  BodyParameters at_origin = a.predicted;
  at_origin.first_moment.setZero();
  const bool inertia_alone_possible = CheckPhysicalConsistency(a.mass_kg, at_origin).consistent;
  if (!inertia_alone_possible && discarded.empty())
    causes.push_back(
        "the inertia at O_d alone is no body: an I_zz from a yaw equation whose scale the flights do not fix, or a "
        "wrong rotor geometry, order or unit (see the inertia and input checks)");
  if (inertia_alone_possible) {
    std::string weak;
    for (int k = 0; k < 3; ++k) {
      const double value = Predicted(p, names[k]), std_dev = PredictedStd(p, names[k]);
      if (!Essential(p, names[k]) || !(std::abs(value) >= 3.0 * std_dev))
        weak += (weak.empty() ? "" : ", ") + std::string(kBodyParameterNames[k]) + " = " +
                ValueWithStd(value, std_dev) + " (" + ShortNumber(1e3 * value / a.mass_kg) + " mm)";
    }
    causes.push_back(
        !weak.empty()
            ? "a first moment the flights do not fix (" + weak +
                  "): fly manoeuvres that excite it (roll and pitch accelerations with thrust changes), or measure "
                  "the centre of mass"
            : "the centre of mass lies farther from O_d than this inertia allows: a mass in the vehicle file "
              "smaller than the real one (" +
                  ShortNumber(a.mass_kg) + " kg), the IMU away from O_d, or a wrong rotor geometry");
  }
  return Join(causes, "; ");
}

}  // namespace

namespace {

// The values of t with which every body (one per first moment) of a configuration, with the inertia
// columns' predicted values plus t `direction`, is physical.
InertiaRange CommonShift(double mass_kg, const std::vector<int>& first_moments, const std::array<int, 6>& inertia,
                         const Eigen::VectorXd& predicted, const Eigen::Matrix3d& direction) {
  InertiaRange range{0.0, std::numeric_limits<double>::infinity()};
  for (int ms : first_moments) {
    Eigen::Matrix<double, kNumBodyParameters, 1> chi;
    for (int i = 0; i < 3; ++i) chi[i] = predicted[ms + i];
    for (int i = 0; i < 6; ++i) chi[3 + i] = predicted[inertia[i]];
    const InertiaRange body = AllowedInertiaShift(mass_kg, BodyParameters::FromVector(chi), direction);
    if (body.empty()) return {0.0, 0.0};
    range = {std::max(range.low, body.low), std::min(range.high, body.high)};
  }
  return range;
}

// A discarded I_zz: these flights do not fix the yaw scale (kd and I_zz are one ratio in the yaw
// equation), so its value is one a body allows, not an estimate; what would fix it.
std::string YawScaleNote(const CheckedParameters& p, const BodyAssessment& a) {
  const std::string zz = a.config + ".I_zz";
  if (!p.value.count(zz) || Essential(p, zz)) return "";
  return "; I_zz is not fixed by these flights (predicted with " + ShortNumber(a.predicted.inertia(2, 2)) +
         ", a value a body allows): yaw manoeuvres, or a second configuration with an asymmetric payload (the "
         "paper's B), fix the yaw scale";
}

}  // namespace

void SetAllowedRanges(const IdimLayout& layout, const std::map<std::string, double>& mass_kg, TlsSolution* solution) {
  const Eigen::Index p = layout.num_parameters();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  solution->allowed_low = solution->allowed_high = solution->within_range_chi = Eigen::VectorXd::Constant(p, nan);
  Eigen::VectorXd predicted = PredictionChi(*solution);
  for (const std::string& config : layout.config_names) {
    const auto mass = mass_kg.find(config);
    if (mass == mass_kg.end()) continue;
    std::vector<int> first_moments;  // the ms_x column of each body
    for (int k = 0; k < p; ++k) {
      const std::string& name = layout.parameter_names[k];
      if (name.compare(0, config.size() + 1, config + ".") == 0 && EndsWith(name, ".ms_x")) first_moments.push_back(k);
    }
    std::array<int, 6> inertia;
    for (int k = 0; k < 6; ++k) inertia[k] = layout.Column(config + "." + kBodyParameterNames[3 + k]);
    if (first_moments.empty() || *std::min_element(inertia.begin(), inertia.end()) < 0) continue;
    std::array<bool, 3> has_value{};  // an estimate, or a value the joint shift below gave
    Eigen::Matrix3d discarded = Eigen::Matrix3d::Zero();
    for (int axis = 0; axis < 3; ++axis) {
      has_value[axis] = PredictsWithProfiled(*solution, inertia[axis]);
      if (!solution->essential[inertia[axis]]) discarded(axis, axis) = 1.0;
    }
    // Several discarded entries can each have no range with the others as predicted (NanoBench: I_xx
    // and I_yy profiled at 3.4e-6 and 4.0e-6, I_zz held at 0, the centre of mass 23 mm below O_d):
    // first raised together, 10 % beyond the smallest shift that makes every body physical.
    const InertiaRange shift = discarded.trace() >= 2.0
                                   ? CommonShift(mass->second, first_moments, inertia, predicted, discarded)
                                   : InertiaRange{0.0, 0.0};
    if (!shift.empty() && shift.low > 0.0)
      for (int axis = 0; axis < 3; ++axis)
        if (discarded(axis, axis) > 0.0) {
          predicted[inertia[axis]] += std::min(1.1 * shift.low, 0.5 * (shift.low + shift.high));
          has_value[axis] = true;
        }
    for (int axis = 0; axis < 3; ++axis) {
      const int k = inertia[axis];
      if (solution->essential[k]) continue;
      Eigen::Matrix3d direction = Eigen::Matrix3d::Zero();
      direction(axis, axis) = 1.0;
      const double value = predicted[k];
      predicted[k] = 0.0;
      const InertiaRange range = CommonShift(mass->second, first_moments, inertia, predicted, direction);
      predicted[k] = value;
      if (range.empty()) continue;  // the others make it no body whatever its value: physical_consistency says so
      solution->allowed_low[k] = range.low;
      solution->allowed_high[k] = range.high;
      const double margin = 0.01 * (range.high - range.low);
      predicted[k] =
          has_value[axis] ? std::clamp(value, range.low + margin, range.high - margin) : 0.5 * (range.low + range.high);
    }
  }
  const Eigen::VectorXd original = PredictionChi(*solution);
  for (Eigen::Index k = 0; k < p; ++k)
    if (predicted[k] != original[k]) solution->within_range_chi[k] = predicted[k];
}

std::vector<BodyAssessment> AssessBodies(const CheckedParameters& p) {
  std::vector<BodyAssessment> out;
  for (const auto& [config, mass] : p.mass_kg) {
    if (!p.value.count(config + ".I_xx")) continue;
    const std::string prefix = config + ".";
    for (const auto& [name, value] : p.value) {
      if (name.compare(0, prefix.size(), prefix) != 0 || !EndsWith(name, ".ms_x")) continue;
      BodyAssessment a;
      a.name = name.substr(0, name.size() - 5);
      a.config = config;
      a.mass_kg = mass;
      const std::array<std::string, kNumBodyParameters> names = BodyNames(a.name, config);
      Eigen::Matrix<double, kNumBodyParameters, 1> chi, estimate, std_dev;
      for (int k = 0; k < kNumBodyParameters; ++k) {
        chi[k] = estimate[k] = Predicted(p, names[k]);
        std_dev[k] = PredictedStd(p, names[k]);
        if (!Essential(p, names[k]) && p.profiled.count(names[k])) {
          estimate[k] = p.profiled.at(names[k]);
          std_dev[k] = Lookup(p.profiled_std, names[k]);
        }
      }
      a.predicted = BodyParameters::FromVector(chi);
      a.estimate = BodyParameters::FromVector(estimate);
      a.consistency = CheckPhysicalConsistency(mass, a.predicted);
      const Eigen::MatrixXd sqrt_information = SqrtInformation(p, names, std_dev);
      a.has_projection = sqrt_information.rows() > 0 && estimate.allFinite();
      if (a.has_projection)
        a.projection = ProjectOntoConsistentBodies(mass, a.estimate, sqrt_information, std_dev, &a.predicted);
      if (!a.consistency.consistent) a.cause = CauseOf(p, a, names);
      out.push_back(std::move(a));
    }
  }
  return out;
}

std::vector<Check> PhysicalConsistencyChecks(const CheckedParameters& p, const std::string& label) {
  std::vector<Check> checks;
  for (const BodyAssessment& a : AssessBodies(p)) {
    const PhysicalConsistency& c = a.consistency;
    const std::string name = label + " " + a.name;
    const ConsistentProjection& q = a.projection;
    std::string distance;
    if (a.has_projection && q.distance_std > 0.0)
      distance =
          "; the nearest physical body lies " + ShortNumber(q.distance_std) + " std from the estimate (Mahalanobis" +
          (q.largest_move_parameter >= 0 ? std::string(", most in ") + kBodyParameterNames[q.largest_move_parameter] +
                                               ": " + ShortNumber(q.largest_move_std) + " std"
                                         : std::string()) +
          ")";
    if (!c.consistent) {
      checks.push_back({"physical_consistency", CheckStatus::kError,
                        name + ": the values it predicts with are no physical body (" + c.problem +
                            "); likely cause: " + a.cause + distance});
      continue;
    }
    const Eigen::Vector3d com = 1e3 * c.centre_of_mass_m;
    const bool far = a.has_projection && q.distance_std > kFarFromABodyStd;
    checks.push_back(
        {"physical_consistency", far ? CheckStatus::kWarning : CheckStatus::kOk,
         name + ": a physically possible body with the values it predicts with: centre of mass (" +
             ShortNumber(com.x()) + ", " + ShortNumber(com.y()) + ", " + ShortNumber(com.z()) +
             ") mm, inertia about it " + ShortNumber(c.principal_moments_at_com[0]) + ", " +
             ShortNumber(c.principal_moments_at_com[1]) + ", " + ShortNumber(c.principal_moments_at_com[2]) +
             " kg m^2" + distance +
             (far ? ": the discarded inertias are predicted within the range a body allows, but the estimate is "
                    "no body; the flights or the model (mass, geometry, an unmodelled effect) are wrong"
                  : "") +
             YawScaleNote(p, a)});
  }
  return checks;
}

}  // namespace rotorid
