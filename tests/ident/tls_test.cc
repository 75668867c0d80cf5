#include "rotorid/ident/tls.h"

#include <random>

#include <gtest/gtest.h>

#include "rotorid/model/rigid_body.h"

namespace rotorid {
namespace {

Vehicle PlusQuad(const std::string& name, double mass) {
  Vehicle v{name, mass, {}, {}};
  const double d = 0.225;
  v.rotors = {{{0, -d, 0}, 1}, {{0, d, 0}, 1}, {{d, 0, 0}, -1}, {{-d, 0, 0}, -1}};
  return v;
}

BodyParameters AsymmetricBody() {
  BodyParameters body;
  body.first_moment << 0.043, -0.020, -0.013;
  body.inertia << 0.026, 2e-4, 1.9e-3, 2e-4, 0.037, -7e-4, 1.9e-3, -7e-4, 0.054;
  return body;
}

// A processed flight whose samples satisfy the model exactly: random w and rotor speeds, (s, w')
// from the forward dynamics.
ProcessedFlight ExactFlight(const Vehicle& vehicle, const BodyParameters& body, double kt, double kd, int samples,
                            unsigned seed, double yaw_rate_scale = 0.5) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ProcessedFlight f;
  f.source = "exact-" + vehicle.name;
  f.vehicle = vehicle;
  f.dt_s = 0.02;
  f.t_s = Eigen::VectorXd::LinSpaced(samples, 0, 0.02 * (samples - 1));
  f.angular_velocity.resize(samples, 3);
  f.angular_acceleration.resize(samples, 3);
  f.specific_force.resize(samples, 3);
  f.rotor.resize(samples, vehicle.num_rotors());
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector3d w(u(rng), u(rng), yaw_rate_scale * u(rng));
    Eigen::VectorXd omega(vehicle.num_rotors());
    for (int r = 0; r < omega.size(); ++r) omega[r] = 930 + 150 * u(rng);
    Eigen::Vector3d s, wd;
    ForwardDynamics<double>(w, RotorWrench<double>(omega, kt, kd, vehicle), vehicle.mass_kg, body.first_moment,
                            body.inertia, &s, &wd);
    f.angular_velocity.row(i) = w.transpose();
    f.angular_acceleration.row(i) = wd.transpose();
    f.specific_force.row(i) = s.transpose();
    f.rotor.row(i) = omega.transpose();
    f.row_samples.push_back(i);
  }
  return f;
}

class ExactDataTest : public ::testing::TestWithParam<TlsMethod> {};

TEST_P(ExactDataTest, RecoversTrueParameters) {
  const Vehicle vehicle = PlusQuad("B", 1.452);
  const BodyParameters body = AsymmetricBody();
  const double kt = 3.6e-6, kd = 5.1e-8;
  const IdimSystem system = BuildIdimSystem({ExactFlight(vehicle, body, kt, kd, 400, 1)});
  TlsOptions options;
  options.method = GetParam();
  options.select_essential = false;
  const TlsSolution solution = SolveIdim(system, options);
  ASSERT_TRUE(solution.usable) << solution.message;
  Eigen::VectorXd truth(11);
  truth << kt, kd, body.ToVector();
  for (int k = 0; k < 11; ++k)
    EXPECT_NEAR(solution.chi[k], truth[k], 1e-9 * std::abs(truth[k])) << system.parameter_names[k];
}

TEST_P(ExactDataTest, CombinedConfigurationsShareRotorCoefficients) {
  const Vehicle a = PlusQuad("A", 1.285), b = PlusQuad("B", 1.452);
  BodyParameters body_a;
  body_a.first_moment << -4e-3, -2e-3, -6e-3;
  body_a.inertia = Eigen::Vector3d(0.018, 0.019, 0.029).asDiagonal();
  const BodyParameters body_b = AsymmetricBody();
  const double kt = 3.6e-6, kd = 5.1e-8;
  ProcessedFlight fb = ExactFlight(b, body_b, kt, kd, 300, 3);
  fb.weight = 2.0;
  const IdimSystem system = BuildIdimSystem({ExactFlight(a, body_a, kt, kd, 300, 2), fb});
  ASSERT_EQ(system.num_parameters(), 20);
  EXPECT_EQ(system.parameter_names[2], "A.ms_x");
  EXPECT_EQ(system.parameter_names[11], "B.ms_x");
  TlsOptions options;
  options.method = GetParam();
  options.select_essential = false;
  const TlsSolution solution = SolveIdim(system, options);
  ASSERT_TRUE(solution.usable) << solution.message;
  EXPECT_NEAR(solution.chi[0], kt, 1e-9 * kt);
  EXPECT_NEAR(solution.chi[1], kd, 1e-9 * kd);
  // A's yaw inertia is fixed only through kd, which B identifies.
  EXPECT_NEAR(solution.chi[2 + 5], 0.029, 1e-9 * 0.029);
  EXPECT_NEAR(solution.chi[11 + 5], body_b.inertia(2, 2), 1e-9 * body_b.inertia(2, 2));
}

INSTANTIATE_TEST_SUITE_P(Methods, ExactDataTest, ::testing::Values(TlsMethod::kPaper, TlsMethod::kNoiseAware),
                         [](const auto& test_info) { return std::string(TlsMethodName(test_info.param)) == "paper" ? "Paper" : "NoiseAware"; });

// A symmetric quad alone: the yaw equation only fixes kd / I_zz, so the selection discards them and
// says which parameter each was confounded with.
TEST(EssentialTest, SymmetricQuadDiscardsYawPair) {
  const Vehicle vehicle = PlusQuad("A", 1.285);
  BodyParameters body;
  // Centre of mass on the z axis, I_xx = I_yy and no yaw rate (so no gyroscopic coupling, as in a
  // hover): I_zz appears only with kd, in the yaw equation.
  body.first_moment << 0.0, 0.0, -6e-3;
  body.inertia = Eigen::Vector3d(0.018, 0.018, 0.029).asDiagonal();
  ProcessedFlight f = ExactFlight(vehicle, body, 3.6e-6, 5.1e-8, 500, 4, /*yaw_rate_scale=*/0.0);
  // Small noise on the measured signals so that the statistics are finite.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < f.angular_acceleration.rows(); ++i)
    for (int a = 0; a < 3; ++a) {
      f.angular_acceleration(i, a) += 0.05 * n(rng);
      f.specific_force(i, a) += 0.05 * n(rng);
    }
  f.noise.angular_acceleration = Eigen::Vector3d::Constant(0.05);
  f.noise.specific_force = Eigen::Vector3d::Constant(0.05);
  const IdimSystem system = BuildIdimSystem({f});
  for (TlsMethod method : {TlsMethod::kNoiseAware, TlsMethod::kPaper}) {
    TlsOptions options;
    options.method = method;
    const TlsSolution solution = SolveIdim(system, options);
    ASSERT_TRUE(solution.usable) << solution.message;
    EXPECT_FALSE(solution.essential[1]) << "kd, " << TlsMethodName(method);
    EXPECT_FALSE(solution.essential[2 + 5]) << "A.I_zz, " << TlsMethodName(method);
    EXPECT_TRUE(solution.essential[0]) << "kt";
    EXPECT_NEAR(solution.chi[0], 3.6e-6, 0.01 * 3.6e-6);
    bool kd_reported = false;
    for (const DiscardedParameter& d : solution.discarded) kd_reported = kd_reported || d.name == "kd";
    EXPECT_TRUE(kd_reported);
  }
}

// Two parameter columns that are exactly dependent give a null vector without the mass column:
// the data cannot fix the scale, and rotorid says so instead of printing huge numbers.
TEST(ScaleTest, LostScaleIsReported) {
  const Vehicle vehicle = PlusQuad("B", 1.452);
  ProcessedFlight f = ExactFlight(vehicle, AsymmetricBody(), 3.6e-6, 5.1e-8, 200, 6);
  IdimSystem system = BuildIdimSystem({f});
  system.w.col(2 + 6) = 1e-6 * system.w.col(0);  // B.I_xy's column proportional to kt's
  TlsOptions options;
  options.method = TlsMethod::kPaper;
  options.select_essential = false;
  const TlsSolution solution = SolveIdim(system, options);
  EXPECT_FALSE(solution.usable);
  EXPECT_NE(solution.message.find("scale lost"), std::string::npos) << solution.message;
}

TEST(RelativeErrorTest, NullWhereDenominatorVanishes) {
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(12, 12);
  for (int i = 0; i < 12; ++i) w(i, 11) = 1.0;
  w(2, 0) = -2.0;
  w(8, 0) = -2.0;
  Eigen::VectorXd chi_t = Eigen::VectorXd::Zero(12);
  chi_t[0] = 1.0;
  chi_t[11] = 1.0;
  const auto rel = RelativeErrorPct(w, chi_t);
  EXPECT_FALSE(rel[0].has_value());
  EXPECT_FALSE(rel[1].has_value());
  ASSERT_TRUE(rel[2].has_value());
  EXPECT_NEAR(*rel[2], 50.0, 1e-12);  // |(-2 + 1)| / |-2|
}

// What a model predicts with: a profiled inertia's estimate when it is positive; a profiled rotor
// coefficient (kd) and a wrong-signed profiled inertia stay at the reported 0.
TEST(PredictionChiTest, PredictsWithAPositiveProfiledInertiaOnly) {
  TlsSolution solution;
  solution.chi = Eigen::VectorXd::Zero(5);
  solution.chi << 2e-8, 0.0, 1.7e-5, 0.0, 0.0;  // kt, kd, I_xx, I_yy, I_zz
  solution.profiled = {false, true, false, true, true};
  solution.profiled_chi = Eigen::VectorXd::Zero(5);
  solution.profiled_chi << 0.0, 1.7e-11, 0.0, -9e-6, 9.5e-6;
  const Eigen::VectorXd predicted = PredictionChi(solution);
  EXPECT_EQ(predicted[0], 2e-8);
  EXPECT_EQ(predicted[1], 0.0);  // kd: no identified rotor term
  EXPECT_EQ(predicted[2], 1.7e-5);
  EXPECT_EQ(predicted[3], 0.0);  // negative: no inertia
  EXPECT_EQ(predicted[4], 9.5e-6);
  EXPECT_FALSE(PredictsWithProfiled(solution, 1));
  EXPECT_FALSE(PredictsWithProfiled(solution, 3));
  EXPECT_TRUE(PredictsWithProfiled(solution, 4));
}

}  // namespace
}  // namespace rotorid
