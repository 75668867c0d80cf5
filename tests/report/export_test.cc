// Exports that fly (INTERFACE.md 6): for the bundled B (plus quad), a Crazyflie and the TU Delft quad
// (X) and an X hexa, from an identify-like report (discarded parameters, one predicted with) and a
// refine-like report (motor lag, rotor drag, flapping, delay), every format is written, read back by
// the readers below and flown in the simulator (MultirotorDynamics) against the report's model:
// the same trajectory to 1e-9, compared on what each format carries. Refusals are checked by name.

#include "rotorid/report/export.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include "report/export_cases.h"
#include "rotorid/core/error.h"
#include "rotorid/core/units.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/physical_consistency.h"
#include "rotorid/sim/dynamics.h"
#include "support/test_support.h"

namespace rotorid {
namespace {

using testing::Case;
using testing::Cases;
using testing::Entry;
using testing::Report;

// A model as a simulator would run it.
struct FlyingModel {
  Vehicle vehicle;
  VehicleParameters parameters;
  double motor_tau_s = 0.0;
  double rotor_drag = 0.0;
  double flapping = 0.0;
};

FlyingModel FromExport(const ExportModel& m) {
  return {m.vehicle, m.parameters, m.motor_tau_s, m.rotor_drag_coefficient, m.flapping_moment_coefficient};
}

// --- readers: each rebuilds the model from the text a simulator would read ---------------------

// The text of the first <tag>...</tag> in [from, to) of `text`, and where it ends.
std::optional<std::string> Tag(const std::string& text, const std::string& tag, size_t from = 0,
                               size_t to = std::string::npos, size_t* end = nullptr) {
  const size_t open = text.find("<" + tag + ">", from);
  if (open == std::string::npos || open >= to) return std::nullopt;
  const size_t start = open + tag.size() + 2, close = text.find("</" + tag + ">", start);
  if (end) *end = close;
  return text.substr(start, close - start);
}

Eigen::Vector3d Triple(const std::string& words) {
  std::istringstream in(words);
  Eigen::Vector3d v;
  in >> v.x() >> v.y() >> v.z();
  return v;
}

// gz and Gazebo Classic model.sdf: the links' inertials summed about O_d, rotors from the rotor
// links and their motor model plugins.
FlyingModel ReadSdf(const std::string& sdf, const std::string& name) {
  FlyingModel out;
  out.vehicle.name = name;
  BodyParameters body;
  double mass = 0.0;
  std::map<std::string, Eigen::Vector3d> link_pose;
  for (size_t at = sdf.find("<link name=\""); at != std::string::npos; at = sdf.find("<link name=\"", at + 1)) {
    const size_t name_end = sdf.find('"', at + 12), end = sdf.find("</link>", at);
    const std::string link = sdf.substr(at + 12, name_end - at - 12);
    const size_t inertial = sdf.find("<inertial>", at);
    const std::optional<std::string> pose = Tag(sdf, "pose", at, inertial);
    const Eigen::Vector3d origin = pose ? Triple(*pose) : Eigen::Vector3d::Zero();
    link_pose[link] = origin;
    const Eigen::Vector3d r = origin + Triple(*Tag(sdf, "pose", inertial, end));
    const double m = std::stod(*Tag(sdf, "mass", inertial, end));
    Eigen::Matrix3d i;
    const auto get = [&](const char* t) { return std::stod(*Tag(sdf, t, inertial, end)); };
    i << get("ixx"), get("ixy"), get("ixz"), get("ixy"), get("iyy"), get("iyz"), get("ixz"), get("iyz"), get("izz");
    body = AddPointMass(body, m, r);
    body.inertia += i;
    mass += m;
  }
  out.parameters.mass_kg = mass;
  out.parameters.body = body;
  for (size_t at = sdf.find("<plugin"); at != std::string::npos; at = sdf.find("<plugin", at + 1)) {
    const size_t end = sdf.find("</plugin>", at);
    const auto value = [&](const char* t) { return std::stod(*Tag(sdf, t, at, end)); };
    const std::string link = *Tag(sdf, "linkName", at, end);
    out.vehicle.rotors.push_back({link_pose.at(link), *Tag(sdf, "turningDirection", at, end) == "ccw" ? +1 : -1});
    out.parameters.rotor = {value("motorConstant"), value("momentConstant") * value("motorConstant")};
    out.motor_tau_s = value("timeConstantUp");
    EXPECT_EQ(value("timeConstantDown"), out.motor_tau_s);
    out.rotor_drag = value("rotorDragCoefficient");
  }
  return out;
}

std::map<std::string, double> ReadParamSet(const std::string& text) {
  std::map<std::string, double> out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string param, set, name;
    double x = 0;
    if (words >> param >> set >> name >> x && param == "param") out[name] = x;
  }
  return out;
}

Eigen::Vector3d Flu(const Eigen::Vector3d& frd) { return {frd.x(), -frd.y(), -frd.z()}; }

// The PX4 file: geometry about the centre of mass, kt and kd from CT and KM at SIM_GZ_EC_MAX, the
// mass from the hover thrust. It carries no inertia: `inertia` is the reference's.
FlyingModel ReadPx4(const std::string& text, const Eigen::Matrix3d& inertia) {
  const auto p = ReadParamSet(text);
  FlyingModel out;
  const int n = static_cast<int>(p.at("CA_ROTOR_COUNT"));
  const double w = p.at("SIM_GZ_EC_MAX1"), ct = p.at("CA_ROTOR0_CT");
  out.parameters.rotor = {ct / (w * w), std::abs(p.at("CA_ROTOR0_KM")) * ct / (w * w)};
  for (int i = 0; i < n; ++i) {
    const std::string k = "CA_ROTOR" + std::to_string(i) + "_";
    out.vehicle.rotors.push_back(
        {Flu(Eigen::Vector3d(p.at(k + "PX"), p.at(k + "PY"), p.at(k + "PZ"))), p.at(k + "KM") > 0 ? 1 : -1});
    EXPECT_EQ(p.at(k + "CT"), ct);
    EXPECT_EQ(p.at("SIM_GZ_EC_MIN" + std::to_string(i + 1)), 0.0);
  }
  EXPECT_EQ(p.at("THR_MDL_FAC"), 1.0);
  out.parameters.mass_kg = p.at("MPC_THR_HOVER") * n * ct / kStandardGravity;
  out.parameters.body.inertia = inertia;
  return out;
}

// SIH: its fixed layouts (sih.cpp) scaled by the arms; thrust and torque at full command over w^2.
FlyingModel ReadSih(const std::string& text, double w) {
  const auto p = ReadParamSet(text);
  FlyingModel out;
  const bool quad = p.at("SIH_VEHICLE_TYPE") == 0;
  EXPECT_TRUE(quad || p.at("SIH_VEHICLE_TYPE") == 4);
  const std::vector<std::pair<double, int>> slots =
      quad ? std::vector<std::pair<double, int>>{{45, 1}, {-135, 1}, {-45, -1}, {135, -1}}
           : std::vector<std::pair<double, int>>{{30, 1}, {90, -1}, {150, 1}, {-150, -1}, {-90, 1}, {-30, -1}};
  for (const auto& [bearing, spin] : slots) {
    const double b = bearing * M_PI / 180.0;
    const double fx = quad ? std::copysign(1.0, std::cos(b)) : std::cos(b);
    const double fy = quad ? std::copysign(1.0, std::sin(b)) : std::sin(b);
    out.vehicle.rotors.push_back({Flu(Eigen::Vector3d(p.at("SIH_L_PITCH") * fx, p.at("SIH_L_ROLL") * fy, 0.0)), spin});
  }
  out.parameters.mass_kg = p.at("SIH_MASS");
  Eigen::Matrix3d i;
  i << p.at("SIH_IXX"), p.at("SIH_IXY"), p.at("SIH_IXZ"), p.at("SIH_IXY"), p.at("SIH_IYY"), p.at("SIH_IYZ"),
      p.at("SIH_IXZ"), p.at("SIH_IYZ"), p.at("SIH_IZZ");
  const Eigen::Matrix3d f = Eigen::Vector3d(1, -1, -1).asDiagonal();
  out.parameters.body.inertia = f * i * f;
  out.parameters.rotor = {p.at("SIH_T_MAX") / (w * w), p.at("SIH_Q_MAX") / (w * w)};
  out.motor_tau_s = p.at("SIH_T_TAU");
  return out;
}

// ArduPilot's frame JSON as SIM_Frame.cpp and SIM_Motor.cpp use it (static thrust, yaw torque at
// the hover command, momentum drag), w the rotor speed at full command.
FlyingModel ReadArduPilot(const std::string& text, double w) {
  const nlohmann::json j = nlohmann::json::parse(text);
  FlyingModel out;
  const int n = j.at("num_motors");
  const double m = j.at("mass"), hover = j.at("hoverThrOut"), e = j.at("propExpo"), d = j.at("diagonal_size");
  const double kt = m * kStandardGravity / n / hover / (w * w);
  const double c_hover = e == 0.0 ? hover : (-(1 - e) + std::sqrt((1 - e) * (1 - e) + 4 * e * hover)) / (2 * e);
  out.parameters.mass_kg = m;
  out.parameters.body.inertia =
      Eigen::Vector3d(j.at("moment_inertia")[0], j.at("moment_inertia")[1], j.at("moment_inertia")[2]).asDiagonal();
  double kd = 0.0;
  for (int k = 1; k <= n; ++k) {
    const std::string key = "motor" + std::to_string(k) + "_";
    const auto& q = j.at(key + "position");
    const double yaw = j.at(key + "yaw");
    out.vehicle.rotors.push_back({Flu(Eigen::Vector3d(q[0], q[1], q[2])), yaw > 0 ? 1 : -1});
    kd = std::abs(yaw) * c_hover * 0.05 * d * kt;
    EXPECT_EQ(j.at(key + "vector"), nlohmann::json({0.0, 0.0, -1.0}));
  }
  out.parameters.rotor = {kt, kd};
  const double mdrag = j.at("mdrag_coef"), disc_area = j.at("disc_area");
  out.rotor_drag = mdrag * std::sqrt(1.225 * disc_area / n * kt);
  // SITL's Frame::init splits the drag at refSpd, refAngle into momentum and body drag and rescales
  // mdrag_coef when the momentum share exceeds it: equal shares keep mdrag_coef and no body drag.
  const double angle = j.at("refAngle").get<double>() * M_PI / 180.0, weight = m * kStandardGravity;
  const double drag_force = weight * std::tan(angle);
  const double momentum_drag = std::cos(angle) * mdrag * j.at("refSpd").get<double>() * std::cos(angle) *
                               std::sqrt(weight / std::cos(angle) * 1.225 * disc_area);
  EXPECT_NEAR(momentum_drag, drag_force, 1e-12 * weight);
  EXPECT_EQ(j.at("refRotRate"), 0.0) << "SITL's rotational damping stays off";
  EXPECT_EQ(j.at("refBatRes"), 0.0);
  return out;
}

FlyingModel ReadYaml(const std::string& text) {
  const YAML::Node y = YAML::Load(text);
  FlyingModel out;
  out.parameters.mass_kg = y["mass"].as<double>();
  out.parameters.rotor = {y["kt"].as<double>(), y["kd"].as<double>()};
  for (int a = 0; a < 3; ++a) {
    out.parameters.body.first_moment[a] = y["first_moment"][a].as<double>();
    for (int b = 0; b < 3; ++b) out.parameters.body.inertia(a, b) = y["inertia"][a][b].as<double>();
  }
  for (const YAML::Node& r : y["rotors"])
    out.vehicle.rotors.push_back(
        {Eigen::Vector3d(r["position"][0].as<double>(), r["position"][1].as<double>(), r["position"][2].as<double>()),
         r["spin"].as<int>()});
  out.motor_tau_s = y["motor_tau_s"].as<double>();
  out.rotor_drag = y["rotor_drag_coefficient"].as<double>();
  out.flapping = y["flapping_moment_coefficient"].as<double>();
  return out;
}

// --- what each format carries --------------------------------------------------------------------

// The reference model reduced to what a format can hold: origin at the centre of mass (rotors
// moved by -c), first moment 0 and the inertia about the centre of mass; optionally its diagonal only.
FlyingModel AboutCentreOfMass(FlyingModel m, bool move_rotors, bool diagonal_inertia) {
  const MassProperties p = MassPropertiesOf(m.parameters.mass_kg, m.parameters.body);
  if (move_rotors)
    for (Rotor& r : m.vehicle.rotors) r.position_m -= p.centre_of_mass_m;
  m.parameters.body.first_moment.setZero();
  m.parameters.body.inertia =
      diagonal_inertia ? Eigen::Matrix3d(p.inertia_at_com.diagonal().asDiagonal()) : p.inertia_at_com;
  return m;
}

// --- flying ----------------------------------------------------------------------------------------

// 0.5 s of open-loop flight from a sideways velocity (so that rotor drag acts), each rotor's speed
// a function of where it sits and how it turns (so that the rotor order of a format does not matter).
SimState Fly(const FlyingModel& m, double hover_speed) {
  Effects effects;
  effects.Set("rotor_drag", Eigen::Vector2d(m.rotor_drag, m.flapping));
  const MultirotorDynamics dynamics(m.vehicle, m.parameters, kStandardGravity, m.motor_tau_s,
                                    ActingEffects(effects, EffectStage::kRotorWrench));
  const double arm = m.vehicle.MeanArm();
  const MultirotorDynamics::RotorCommand command = [&](double t) {
    Eigen::VectorXd w(m.vehicle.num_rotors());
    for (int i = 0; i < w.size(); ++i) {
      const Rotor& r = m.vehicle.rotors[static_cast<size_t>(i)];
      const double phase = 3.0 * r.position_m.x() / arm + 5.0 * r.position_m.y() / arm + r.spin;
      w[i] = hover_speed * (1.0 + 0.04 * std::sin(2.0 * M_PI * 3.0 * t + phase));
    }
    return w;
  };
  SimState s;
  s.velocity_w_mps = Eigen::Vector3d(2.0, -1.0, 0.5);
  s.angular_velocity_b_radps = Eigen::Vector3d(0.3, -0.2, 0.5);
  s.rotor_speed_radps = command(0.0);
  for (int k = 0; k < 250; ++k) s = dynamics.Step(k * 0.002, s, 0.002, command);
  return s;
}

void ExpectSameFlight(const FlyingModel& reference, const FlyingModel& rebuilt, double hover_speed,
                      const std::string& what) {
  ASSERT_EQ(reference.vehicle.num_rotors(), rebuilt.vehicle.num_rotors()) << what;
  const SimState a = Fly(reference, hover_speed), b = Fly(rebuilt, hover_speed);
  const auto close = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& y, const char* name) {
    EXPECT_LE((x - y).norm(), 1e-9 * std::max(x.norm(), 1e-3))
        << what << ": " << name << " " << x.transpose() << " vs " << y.transpose();
  };
  close(a.position_w_m, b.position_w_m, "position");
  close(a.velocity_w_mps, b.velocity_w_mps, "velocity");
  close(a.attitude_wb.coeffs(), b.attitude_wb.coeffs(), "attitude");
  close(a.angular_velocity_b_radps, b.angular_velocity_b_radps, "angular velocity");
  // The flight moved: the comparison is not of two resting bodies.
  EXPECT_GT(a.angular_velocity_b_radps.norm(), 0.1) << what;
}

std::string Text(const std::vector<ExportedFile>& files, const std::string& name) {
  for (const ExportedFile& f : files)
    if (f.name == name) return f.text;
  ADD_FAILURE() << "no file " << name;
  return "";
}

TEST(ExportTest, EveryFormatFliesLikeTheReportOrIsRefusedByName) {
  for (const Case& c : Cases()) {
    for (const bool refined : {false, true}) {
      const std::string what = c.vehicle.name + (refined ? " refine" : " identify");
      const IdentifiedModel identified = IdentifiedModelFromReport(Report(c, refined), "r.json", c.vehicle);
      ExportOptions options;
      if (c.max_rotor_speed_radps > 0.0) options.set["max_rotor_speed"] = c.max_rotor_speed_radps;
      const ExportModel model = ResolveExportModel(identified, options);
      // The discarded I_zz is exported with the value the model predicts with, I_xy with 0.
      EXPECT_NEAR(model.parameters.body.inertia(2, 2), c.truth.body.inertia(2, 2), 1e-15) << what;
      EXPECT_TRUE(CheckPhysicalConsistency(model.parameters.mass_kg, model.parameters.body).consistent) << what;
      EXPECT_EQ(model.motor_tau_s, refined ? 0.02 : 0.0) << what;
      const double w = model.max_rotor_speed_radps, hover = model.HoverRotorSpeedRadps();
      const FlyingModel full = FromExport(model);
      FlyingModel no_flapping = full;
      no_flapping.flapping = 0.0;

      ExpectSameFlight(full, ReadYaml(Text(ExportFiles(model, ExportFormat::kYaml), "")), hover, what + " yaml");
      for (const ExportFormat f : {ExportFormat::kGz, ExportFormat::kGazeboClassic}) {
        const std::vector<ExportedFile> files = ExportFiles(model, f);
        EXPECT_NE(Text(files, "model.config").find("<sdf version=\"1.9\">model.sdf</sdf>"), std::string::npos);
        ExpectSameFlight(no_flapping, ReadSdf(Text(files, "model.sdf"), c.vehicle.name), hover,
                         what + " " + ExportFormatName(f));
      }
      FlyingModel at_com = AboutCentreOfMass(full, true, false);
      at_com.motor_tau_s = at_com.rotor_drag = at_com.flapping = 0.0;
      // floor(w): SIM_GZ_EC_MAX is an integer, and CT is the thrust there.
      ExpectSameFlight(at_com,
                       ReadPx4(Text(ExportFiles(model, ExportFormat::kPx4), ""), at_com.parameters.body.inertia), hover,
                       what + " px4");

      FlyingModel ardupilot = AboutCentreOfMass(full, true, true);
      ardupilot.motor_tau_s = ardupilot.flapping = 0.0;
      ExpectSameFlight(ardupilot, ReadArduPilot(Text(ExportFiles(model, ExportFormat::kArduPilot), ""), w), hover,
                       what + " ardupilot");

      if (c.vehicle.name == "B") {  // a plus quad: SIH flies X only
        try {
          ExportFiles(model, ExportFormat::kPx4Sih);
          ADD_FAILURE() << what << ": px4-sih accepted a plus layout";
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("'B'"), std::string::npos) << e.what();
          EXPECT_NE(std::string(e.what()).find("plus"), std::string::npos) << e.what();
        }
        continue;
      }
      FlyingModel sih = AboutCentreOfMass(full, false, false);
      sih.rotor_drag = sih.flapping = 0.0;
      sih.motor_tau_s = refined ? 0.02 : 0.004;  // SIH's filter needs tau > 0: its step when the model has none
      ExpectSameFlight(sih, ReadSih(Text(ExportFiles(model, ExportFormat::kPx4Sih), ""), w), hover, what + " px4-sih");
    }
  }
}

std::string RefusalOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ExportTest, RefusesWhatTheReportDoesNotFixNamingItAndTheFlight) {
  const Case c = Cases()[0];
  nlohmann::json report = Report(c, false);
  report["linear"]["parameters"]["kd"] = Entry(0.0, false);  // discarded, no predicted-with value
  ExportOptions options;
  options.set["max_rotor_speed"] = 1200.0;
  const IdentifiedModel no_kd = IdentifiedModelFromReport(report, "r.json", c.vehicle);
  std::string why = RefusalOf([&] { ResolveExportModel(no_kd, options); });
  EXPECT_NE(why.find("does not fix kd"), std::string::npos) << why;
  EXPECT_NE(why.find("second configuration"), std::string::npos) << why;
  EXPECT_NE(why.find("--set kd=VALUE"), std::string::npos) << why;
  options.set["kd"] = 5e-8;
  EXPECT_DOUBLE_EQ(ResolveExportModel(no_kd, options).parameters.rotor.kd, 5e-8);

  // I_zz predicted with a value too small for the body (I_zz < |I_xx - I_yy| is no body), and
  // without any value at all.
  report["linear"]["parameters"]["B.I_zz"]["predicts_with"] = 1e-4;
  why = RefusalOf([&] { ResolveExportModel(IdentifiedModelFromReport(report, "r.json", c.vehicle), options); });
  EXPECT_NE(why.find("no physically possible body"), std::string::npos) << why;
  EXPECT_NE(why.find("B.I_zz"), std::string::npos) << why;
  report["linear"]["parameters"]["B.I_zz"].erase("predicts_with");
  why = RefusalOf([&] { ResolveExportModel(IdentifiedModelFromReport(report, "r.json", c.vehicle), options); });
  EXPECT_NE(why.find("does not fix B.I_zz"), std::string::npos) << why;
  options.set["I_zz"] = 2.9e-2;
  EXPECT_DOUBLE_EQ(
      ResolveExportModel(IdentifiedModelFromReport(report, "r.json", c.vehicle), options).parameters.body.inertia(2, 2),
      2.9e-2);
}

TEST(ExportTest, FailedChecksNeedForceAndGoIntoTheHeader) {
  const Case c = Cases()[1];
  nlohmann::json report = Report(c, true);
  report["checks"].push_back({{"name", "mass_vs_hover_thrust"}, {"status", "error"}, {"message", "off by 40 %"}});
  const IdentifiedModel model = IdentifiedModelFromReport(report, "r.json", c.vehicle);
  const std::string why = RefusalOf([&] { ResolveExportModel(model, {}); });
  EXPECT_NE(why.find("mass_vs_hover_thrust"), std::string::npos) << why;
  EXPECT_NE(why.find("--force"), std::string::npos) << why;
  ExportOptions forced;
  forced.force = true;
  for (const ExportFormat f :
       {ExportFormat::kGz, ExportFormat::kPx4Sih, ExportFormat::kArduPilot, ExportFormat::kYaml}) {
    const std::string text = ExportFiles(ResolveExportModel(model, forced), f).front().text;
    EXPECT_NE(text.find("FAILED CHECK (exported anyway: forced): mass_vs_hover_thrust: off by 40 %"), std::string::npos)
        << ExportFormatName(f);
  }
}

TEST(ExportTest, NumbersStayFiniteAndXmlStaysValid) {
  Case c = Cases()[2];
  const IdentifiedModel identified = IdentifiedModelFromReport(Report(c, true), "dir/<r&\"x\">--.json", c.vehicle);
  ExportOptions options;
  options.set["max_rotor_speed"] = 1e200;
  const ExportModel huge = ResolveExportModel(identified, options);
  for (const ExportFormat f :
       {ExportFormat::kGz, ExportFormat::kPx4, ExportFormat::kPx4Sih, ExportFormat::kArduPilot}) {
    const std::string why = RefusalOf([&] { ExportFiles(huge, f); });
    EXPECT_NE(why.find("not a finite number"), std::string::npos) << ExportFormatName(f) << ": " << why;
  }
  options.set["max_rotor_speed"] = 1e100;  // finite thrust, but no rotor's speed
  EXPECT_NE(RefusalOf([&] {
              ExportFiles(ResolveExportModel(identified, options), ExportFormat::kPx4);
            }).find("no real rotor's"),
            std::string::npos);
  options.set["max_rotor_speed"] = 100.0;  // too slow to hover
  EXPECT_NE(RefusalOf([&] {
              ExportFiles(ResolveExportModel(identified, options), ExportFormat::kGz);
            }).find("could not hover"),
            std::string::npos);
  options.set.erase("max_rotor_speed");
  EXPECT_NE(RefusalOf([&] {
              ExportFiles(ResolveExportModel(identified, options), ExportFormat::kGz);
            }).find("--max-rotor-speed"),
            std::string::npos);

  c.vehicle.name = "a<b&\"c\"";
  nlohmann::json report = Report(c, true);
  IdentifiedModel named = IdentifiedModelFromReport(report, "dir/<r&\"x\">--.json", c.vehicle);
  options.set["max_rotor_speed"] = 4000.0;
  const std::string sdf = Text(ExportFiles(ResolveExportModel(named, options), ExportFormat::kGz), "model.sdf");
  EXPECT_NE(sdf.find("<model name=\"a&lt;b&amp;&quot;c&quot;\">"), std::string::npos);
  // No "--" inside a comment, and every comment closed where it should be.
  for (size_t at = sdf.find("<!--"); at != std::string::npos; at = sdf.find("<!--", at + 4)) {
    const size_t end = sdf.find("-->", at + 4);
    ASSERT_NE(end, std::string::npos);
    EXPECT_EQ(sdf.substr(at + 4, end - at - 4).find("--"), std::string::npos) << sdf.substr(at, end - at + 3);
  }
  for (const char* bad : {">inf", ">-inf", ">nan", ">-nan", " inf ", " nan "})
    EXPECT_EQ(sdf.find(bad), std::string::npos) << bad;
}

TEST(ExportTest, FormatNamesAndSettings) {
  EXPECT_EQ(ParseExportFormat("gazebo"), ExportFormat::kGazeboClassic);  // v2's name
  EXPECT_TRUE(ExportWritesDirectory(ExportFormat::kGz));
  EXPECT_FALSE(ExportWritesDirectory(ExportFormat::kArduPilot));
  EXPECT_THROW(ParseExportFormat("urdf"), Error);
  EXPECT_EQ(ParseExportSetting("I_zz=0.03"), std::make_pair(std::string("I_zz"), 0.03));
  EXPECT_THROW(ParseExportSetting("I_zz"), Error);
  EXPECT_THROW(ParseExportSetting("I_zz=1e999"), Error);
  EXPECT_THROW(ParseExportSetting("I_zz=0.03x"), Error);
  const Case c = Cases()[0];
  ExportOptions options;
  options.set["I_ww"] = 1.0;
  EXPECT_NE(RefusalOf([&] {
              ResolveExportModel(IdentifiedModelFromReport(Report(c, true), "r", c.vehicle), options);
            }).find("--set I_ww"),
            std::string::npos);
}

}  // namespace
}  // namespace rotorid
