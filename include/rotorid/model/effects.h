#pragma once

// The unmodelled effects (INTERFACE.md section 1 and "Effects of real vehicles (v2)") as open,
// self-describing blocks. Each effect is one EffectDescriptor, defined in its own source file
// (src/model/effect_<name>.cc) together with its models, and listed by one line in the registry
// (src/model/effect_registry.cc). Nothing else in the library names a specific effect: the
// simulator, the refinement, the diagnosis and the reports loop over the descriptors.
// docs/adding_an_effect.md walks through adding one.
//
// Conventions every effect follows:
//   - an all-zero value means "absent" (the rows are then exactly the effect-free ones);
//   - its models are templated on the scalar (double and ceres::Jet) and live in its file; the
//     library calls them through the virtual hooks of its stage below.

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace ceres {
template <typename T, int N>
struct Jet;
}  // namespace ceres

namespace rotorid {

struct Vehicle;
struct CommandToSpeed;

// What a rotor-signal effect sees of one rotor's log besides the signal it transforms: the base time
// step and, for a command log mapped to speed, the raw command, the battery voltage and the map
// (null where the log has none).
struct RotorSignalInput {
  double dt = 0.0;
  const Eigen::VectorXd* command = nullptr;  // u of this rotor (the map's input), unfiltered
  const Eigen::VectorXd* voltage = nullptr;  // V
  const CommandToSpeed* map = nullptr;
  double reference_voltage = 0.0;  // the map's voltage (vehicle file), else the flight's mean
};

// A part of the rotors' Omega_i^2 that acts only through a first-order low-pass (the slow actuation
// component): Omega_acting^2 = (1 - fraction) Omega^2 + fraction S,  S' = rate_per_s (Omega^2 - S).
struct SlowActuation {
  double fraction = 0.0;
  double rate_per_s = 0.0;
  bool active() const { return fraction != 0.0; }
};

// Where in the chain from the true physics to the logged signals an effect acts.
enum class EffectStage {
  kRotorSignal,  // the logged rotor signal -> the rotor speeds acting (a whole time series)
  kImuSensor,    // the true body motion at O_b -> the logged gyro and accelerometer
  kRotorWrench,  // the rotors' wrench beyond the paper's kt, kd model, at one sample
};

// Flight signals an effect's model may need beyond gyro, accelerometer and rotor signal.
enum class FlightInput {
  kVelocity,            // velocity of O_d in F_d (motion capture, differentiated, or velocity columns)
  kHeight,              // height above ground
  kVoltage,             // battery voltage
  kRotorAcceleration,   // Omega_i'
  kSpecificForceRates,  // s' and s'', the accelerometer's derivatives
  kRotorCommand,        // the raw command next to the speed mapped from it
  kRotorRadius,         // the vehicle file's rotor_radius
};
// Which of them a processed flight carries.
struct FlightInputs {
  bool velocity = false, height = false, voltage = false, rotor_acceleration = false, specific_force_rates = false,
       rotor_command = false, rotor_radius = false;
  bool Has(FlightInput input) const;
};
const char* FlightInputName(FlightInput input);

// The IMU signals at one sample: gyro w, its derivative w', accelerometer s; and the first two
// derivatives of s (for effects that shift the accelerometer stream in time; zero in the
// simulator, which shifts its streams itself).
template <typename T>
struct ImuSample {
  Eigen::Matrix<T, 3, 1> angular_velocity, angular_acceleration, specific_force;
  Eigen::Matrix<T, 3, 1> specific_force_rate = Eigen::Matrix<T, 3, 1>::Zero();
  Eigen::Matrix<T, 3, 1> specific_force_rate2 = Eigen::Matrix<T, 3, 1>::Zero();
};

// What a rotor-wrench effect sees at one sample, in F_d: the rotor speeds acting (after the
// rotor-signal effects) and their rates, the body's angular velocity (corrected IMU) and the
// velocity of O_d and the rotors' heights (zero or empty when the flight has none; an effect
// needing them says so in its inputs).
template <typename T>
struct RotorSample {
  const Vehicle* vehicle = nullptr;
  Eigen::Matrix<T, Eigen::Dynamic, 1> speed, acceleration;  // |Omega_i| (rad/s), Omega_i' (rad/s^2)
  Eigen::Matrix<T, 3, 1> angular_velocity = Eigen::Matrix<T, 3, 1>::Zero();
  Eigen::Matrix<T, 3, 1> velocity = Eigen::Matrix<T, 3, 1>::Zero();
  Eigen::Matrix<T, Eigen::Dynamic, 1> height;  // h_i of each rotor above the ground; empty without a pose
};
// What rotor-wrench effects change in the rotors' wrench: rotor i gives thrust kt f_i Omega_i^2 and
// drag torque kd g_i Omega_i^2 (f = thrust_factor, g = torque_factor, 1 in the paper's model), and
// `extra` is a wrench at O_d (N, N m) that does not scale with kt or kd. Effects compose by
// multiplying factors and adding wrenches.
template <typename T>
struct RotorWrenchTerms {
  Eigen::Matrix<T, Eigen::Dynamic, 1> thrust_factor, torque_factor;
  Eigen::Matrix<T, 6, 1> extra = Eigen::Matrix<T, 6, 1>::Zero();
  explicit RotorWrenchTerms(int rotors)
      : thrust_factor(Eigen::Matrix<T, Eigen::Dynamic, 1>::Constant(rotors, T(1.0))),
        torque_factor(Eigen::Matrix<T, Eigen::Dynamic, 1>::Constant(rotors, T(1.0))) {}
};

// The scalar types the library evaluates effect models with: the derivatives of IMU effects are
// taken in passes of kImuJetSize (or kMidImuJetSize, kWideImuJetSize) coordinates, those of
// rotor-signal effects, which run over whole time series, in passes of kRotorJetSize. The middle
// size fits the pairs the diagnosis refines most (two 3-vectors; rotor drag's 2 and a 3-vector or
// four per-rotor values) at about half the cost of the wide Jet.
inline constexpr int kImuJetSize = 4;
inline constexpr int kMidImuJetSize = 6;
inline constexpr int kWideImuJetSize = 12;
inline constexpr int kRotorJetSize = 2;
using ImuJet = ceres::Jet<double, kImuJetSize>;
using MidImuJet = ceres::Jet<double, kMidImuJetSize>;
using WideImuJet = ceres::Jet<double, kWideImuJetSize>;
using RotorJet = ceres::Jet<double, kRotorJetSize>;

// How the simulator's studies draw an effect at a realistic size.
enum class DrawShape {
  kUniform,          // each coordinate uniform in [low, high]
  kSignedPerAxis,    // each coordinate: random sign times uniform in [low, high]
  kRandomDirection,  // a direction uniform on the sphere times a norm uniform in [low, high]
};
struct DrawRange {
  DrawShape shape = DrawShape::kUniform;
  double low = 0.0, high = 0.0;  // in the units the range is written in
  double to_si = 1.0;            // factor from those units to SI
};

// What the simulator accepts (beyond it its controller cannot fly the pilot's references).
struct SimulatorLimit {
  bool per_coordinate = true;  // [low, high] per coordinate, else the norm <= high
  double low = 0.0, high = 0.0;
};

// The vehicle size a physical range scales with.
enum class PlausibleScale {
  kNone,            // the range is in SI as written
  kArmLength,       // times the rotors' mean distance from the z axis (m)
  kMassArmSquared,  // times mass x that arm length squared (kg m^2), the size of the body's inertia
};
// What the physics allows an estimate to be (MODEL.md 8), apart from the refinement's bounds, which
// only keep the solver finite: an estimate beyond it absorbs something else (an IMU lever arm of
// 30 cm standing in for a first moment, thrust scales of +-30 % for a geometry error).
struct PlausibleRange {
  bool per_coordinate = true;               // [low, high] per coordinate, else the norm <= high
  double low = -HUGE_VAL, high = HUGE_VAL;  // SI, times the vehicle's scale
  PlausibleScale scale = PlausibleScale::kNone;
  std::string why;  // the physics, for the note: "an IMU sits on the frame, within an arm of O_d"
};
// Sizes too small to matter: an estimate below it (SI, not scaled; per coordinate or the norm, as
// its PlausibleRange says), 3 std included, is negligible however significant, because a value that
// small is what the data's own small misfits look like through this effect (a sub-millimetre lever
// arm is the first moment the force rows see less the one the moment rows see). Set where such
// selections were measured, with the reason; 0 for none.
struct NegligibleSize {
  double below = 0.0;
  std::string why;
};

class EffectDescriptor {
 public:
  struct Info {
    std::string name;            // "delay", as --effects takes it
    std::string parameter_name;  // "delay_s", as reports and --effect name=value write it
    std::string unit;            // SI unit of the parameter, "s"
    // Names of the scalar parameters when each has its own (rotor_drag's two coefficients); else
    // parameter_name with axis ("_x") or rotor ("_1") suffixes.
    std::vector<std::string> labels;
    EffectStage stage = EffectStage::kImuSensor;
    // Place in the chain of its stage, from the physics (0) towards the log: the simulator applies
    // the stage's effects in increasing order, the model's correction in decreasing order.
    int chain_position = 0;
    int dimension = 1;       // scalar parameters
    bool per_rotor = false;  // one value per rotor instead ("_1" .. "_N"), dimension unused
    // Physical bounds per coordinate kept by the refinement; an estimate ending on a non-zero
    // bound is reported as such.
    double lower_bound = 0.0, upper_bound = 0.0;
    // Whether the refinement starts it from a global grid search of the criterion (over the
    // options' search range, which then also bounds it).
    bool grid_searched = false;
    // Values the diagnosis screens a strongly nonlinear scalar effect over (empty: linear enough
    // for the first-order screening alone; a grid-searched effect uses its search range).
    std::vector<double> screening_grid;
    DrawRange draw;
    SimulatorLimit simulator_limit;
    PlausibleRange plausible;
    NegligibleSize negligible;
    // Change between refinement passes below which it has settled when no std is computed: a
    // hundredth of the smallest sizes a 90 s flight reveals (refinement study).
    double settle_tolerance = 0.0;
    // Reporting: value * display_scale in display_unit ("ms", "deg").
    double display_scale = 1.0;
    std::string display_unit;
    // The flight signals its model needs (beyond gyro, accelerometer, rotor signal).
    std::vector<FlightInput> inputs;
    // The values sum to zero (a per-rotor spread around a mean that a linear parameter already
    // carries): the refinement pins the sum, and the simulator's draws are centred.
    bool zero_sum = false;
    // Coordinates the refinement and the diagnosis hold at their start value (the vehicle file's
    // known value, else 0) because a parameter of the linear model has the same columns in every
    // row these flights give (an IMU lever arm along z is the first moment ms_z), and why: estimated,
    // such a coordinate only takes that parameter's place (MODEL.md 8); held_why says it in the report.
    std::vector<int> held_coordinates;
    std::string held_why;
    // Whether "all" (refine's and ablate's default, the diagnosis's candidates) includes it: false
    // for an effect that a parameter of the linear model mimics so closely that, on ordinary
    // flights, it runs to its bound or takes that parameter's value (used when named).
    bool default_candidate = true;
    // The vehicle file key that gives a known value of an IMU-sensor effect ("imu_position"), or
    // empty: processing corrects the IMU data by it, and the effect then estimates what is left.
    std::string vehicle_key;
    // A timing effect (it shifts or smooths one side of the rows against the other): the controller's
    // reply to sensor noise correlates the rotor signal with the measurement noise above the pilot's
    // band, which biases such an estimate more the higher the cut-off (1 ms of delay on a clean
    // take-off flight at 10 Hz, 12 ms at 20 Hz). The diagnosis keeps it only if it holds at half the
    // cut-off.
    bool checked_at_half_cutoff = false;
    // A per-rotor effect whose rotors' spin pattern (sum_i spin_i value_i) changes no thrust and, at
    // equal rotor speeds, no roll or pitch moment: only the yaw torque shows it first-hand (elsewhere
    // it is a roll-pitch coupling on an X quad, what I_xy does, or a gain on roll against pitch on a
    // + quad, what I_xx / I_yy do). Without kd among the free parameters it is held at 0
    // (HeldDirections).
    bool spin_pattern_needs_kd = false;
    // A known value of another effect (its name: "imu_lever_arm", given by its vehicle_key) that the
    // estimate is relative to, and what the estimate reads when the vehicle file does not give it:
    // rotor_drag's flapping coefficient is measured about the IMU's height, because the force rows
    // see only ms_z - m r_z and the drag force's moment about the centre of mass follows that ms_z.
    // A flight cannot tell them apart (docs/adding_an_effect.md, "Why r_z is hard").
    std::string relative_to_known;
    std::function<std::string(const Eigen::VectorXd& value)> reads_without_it;
  };

  explicit EffectDescriptor(Info info) : info_(std::move(info)) {}
  virtual ~EffectDescriptor() = default;
  EffectDescriptor(const EffectDescriptor&) = delete;
  EffectDescriptor& operator=(const EffectDescriptor&) = delete;

  const Info& info() const { return info_; }
  const std::string& name() const { return info_.name; }
  const std::string& parameter_name() const { return info_.parameter_name; }
  EffectStage stage() const { return info_.stage; }
  // Position in the registry (report order, simulator draw streams, bit masks).
  int index() const { return index_; }
  // Number of scalar parameters for this vehicle.
  virtual int Dimension(const Vehicle& vehicle) const;
  // Parameters it adds to a model for this vehicle: Dimension less one for a zero-sum effect (the
  // refinement pins its sum) and less its held coordinates.
  int FreeDimension(const Vehicle& vehicle) const {
    return Dimension(vehicle) - (info_.zero_sum ? 1 : 0) - static_cast<int>(info_.held_coordinates.size());
  }
  bool Held(int coordinate) const;
  // Labels of the held coordinates for this dimension: {"imu_position_m_z"}.
  std::vector<std::string> HeldLabels(int dimension) const;
  // Dimension without a vehicle, or -1 when it depends on one.
  virtual int FixedDimension() const { return info_.per_rotor ? -1 : info_.dimension; }
  // Labels of the scalar parameters: {"delay_s"} or {"acc_bias_x", "acc_bias_y", "acc_bias_z"}.
  std::vector<std::string> Labels(int dimension) const;
  // The value formatted for people: "12.3 +- 0.4 ms", "(1, 2, 3) deg".
  std::string Format(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) const;
  // Empty when the simulator accepts the value, else the reason.
  std::string CheckSimulatable(const Eigen::VectorXd& value) const;
  // Empty when a flight with these inputs can carry the effect, else why it is unavailable
  // ("needs the velocity (motion capture or velocity columns), which this log lacks").
  std::string Unavailable(const FlightInputs& available) const;
  // Empty when an estimate (value +- std_dev, std_dev may be empty) is within the physical range for
  // this vehicle, allowing 3 std beyond it; else which value lies outside which range, and why.
  std::string Implausible(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev, const Vehicle& vehicle) const;
  // Empty unless the estimate's free coordinates, 3 std included, lie below the size that matters
  // (Info::negligible); else the value, that size, and why.
  std::string Negligible(const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) const;
  // Empty unless Info::relative_to_known is set and `vehicle`'s file does not give that effect's
  // value; else what `value` then reads (Info::reads_without_it).
  std::string UnstatedReference(const Eigen::VectorXd& value, const Vehicle& vehicle) const;
  // Clamps a value into the physical bounds.
  Eigen::VectorXd Clamp(const Eigen::VectorXd& value) const;

  // kImuSensor: the model's correction (logged -> body at O_b) with parameters p, and the
  // simulator's forward sensor model (body -> logged, before the noise).
  virtual void CorrectImu(const double* p, ImuSample<double>* sample) const;
  virtual void CorrectImu(const ImuJet* p, ImuSample<ImuJet>* sample) const;
  virtual void CorrectImu(const MidImuJet* p, ImuSample<MidImuJet>* sample) const;
  virtual void CorrectImu(const WideImuJet* p, ImuSample<WideImuJet>* sample) const;
  virtual void ApplyToSensor(const double* p, ImuSample<double>* sample) const;

  // kRotorWrench: adds the effect's terms at one sample, for the model and the simulator alike.
  virtual void AddRotorWrench(const double* p, const RotorSample<double>& sample,
                              RotorWrenchTerms<double>* terms) const;
  virtual void AddRotorWrench(const ImuJet* p, const RotorSample<ImuJet>& sample,
                              RotorWrenchTerms<ImuJet>* terms) const;
  virtual void AddRotorWrench(const MidImuJet* p, const RotorSample<MidImuJet>& sample,
                              RotorWrenchTerms<MidImuJet>* terms) const;
  virtual void AddRotorWrench(const WideImuJet* p, const RotorSample<WideImuJet>& sample,
                              RotorWrenchTerms<WideImuJet>* terms) const;

  // kRotorSignal: one rotor's signal at the base rate -> what acts after this effect, for the
  // model; and the simulator's view of it: the delay it adds to the command and the time constant
  // of the first-order lag it adds between command and rotor.
  virtual void TransformRotorSignal(const double* p, const RotorSignalInput& input, const Eigen::VectorXd& in,
                                    Eigen::VectorXd* out) const;
  virtual void TransformRotorSignal(const RotorJet* p, const RotorSignalInput& input,
                                    const Eigen::Matrix<RotorJet, -1, 1>& in,
                                    Eigen::Matrix<RotorJet, -1, 1>* out) const;
  virtual double SimulatedCommandDelay(const Eigen::VectorXd& /*value*/) const { return 0.0; }
  // kImuSensor: the delay of the accelerometer stream behind the gyro's that the simulator applies
  // to the whole series (its per-sample ApplyToSensor leaves the sample alone).
  virtual double SimulatedAccelerometerDelay(const Eigen::VectorXd& /*value*/) const { return 0.0; }
  virtual double SimulatedMotorTimeConstant(const Eigen::VectorXd& /*value*/) const { return 0.0; }
  // The slow part of the actuation the simulator adds after the lag: the fraction of Omega^2 that acts
  // through a first-order low-pass, and that low-pass's rate (1 / time constant, 1/s; 0 holds it).
  virtual SlowActuation SimulatedSlowActuation(const Eigen::VectorXd& /*value*/) const { return {}; }
  // The value that gives a rotor-signal effect about this delay of the rotor signal (the
  // diagnosis starts it from the coarse delay search), clamped into its bounds.
  virtual Eigen::VectorXd FromEquivalentDelay(double delay_s) const;

 private:
  friend const std::vector<const EffectDescriptor*>& AllEffects();
  Info info_;
  mutable int index_ = -1;  // set once by the registry
};

// An effect is named by its descriptor.
using EffectKind = const EffectDescriptor*;

// Orders effects as the registry lists them (for maps and sets with a reproducible order).
struct EffectOrder {
  bool operator()(EffectKind a, EffectKind b) const { return a->index() < b->index(); }
};

// Every registered effect, in report order.
const std::vector<EffectKind>& AllEffects();
// Registered effects that "all" stands for (EffectDescriptor::Info::default_candidate).
std::vector<EffectKind> DefaultCandidates();
// Registered effects acting on `stage`, in chain order.
std::vector<EffectKind> EffectsOfStage(EffectStage stage);

inline const char* EffectName(EffectKind kind) { return kind->name().c_str(); }
inline const char* EffectParameterName(EffectKind kind) { return kind->parameter_name().c_str(); }
// Dimension without a vehicle (the fixed-size effects).
int EffectDimension(EffectKind kind);
// Unit directions of `kind`'s values (one column each, Dimension(vehicle) rows) that the refinement
// and the diagnosis hold at 0 for this vehicle: the rotors' spin pattern, centred, of an effect with
// Info::spin_pattern_needs_kd when kd is not free; else none (0 columns).
Eigen::MatrixXd HeldDirections(EffectKind kind, const Vehicle& vehicle, bool kd_free);
// Parses an effect name (either form above); throws rotorid::Error listing the valid names.
EffectKind ParseEffectKind(const std::string& name);
// Parses "a,b,c" effect lists ("all" for DefaultCandidates(), "every" for AllEffects()); throws
// rotorid::Error on unknown names.
std::vector<EffectKind> ParseEffectList(const std::string& list);

// The value of a double or of a ceres::Jet (its .a), for decisions that carry no derivative.
template <typename T>
double ScalarPart(const T& x) {
  if constexpr (std::is_arithmetic_v<T>) {
    return static_cast<double>(x);
  } else {
    return x.a;
  }
}

// Values of effects, keyed by descriptor; an effect without a value is absent (zero).
class Effects {
 public:
  // The value (size EffectDimension(kind)), zeros when not set.
  Eigen::VectorXd Get(EffectKind kind) const;
  // The value, zeros of the vehicle's dimension when not set (per-rotor effects too).
  Eigen::VectorXd Get(EffectKind kind, const Vehicle& vehicle) const;
  // By name (either form), for tests and tools.
  Eigen::VectorXd Get(const std::string& name) const { return Get(ParseEffectKind(name)); }
  double Scalar(EffectKind kind) const { return Get(kind)[0]; }
  double Scalar(const std::string& name) const { return Get(name)[0]; }
  void Set(EffectKind kind, const Eigen::Ref<const Eigen::VectorXd>& value);
  void Set(EffectKind kind, double value) { Set(kind, Eigen::VectorXd::Constant(1, value)); }
  void Set(const std::string& name, const Eigen::Ref<const Eigen::VectorXd>& value) {
    Set(ParseEffectKind(name), value);
  }
  void Set(const std::string& name, double value) { Set(ParseEffectKind(name), value); }
  // True when the effect has no non-zero value.
  bool IsZero(EffectKind kind) const;
  // True when every effect of the stage is absent.
  bool StageIsZero(EffectStage stage) const;
  // True when every effect is absent.
  bool AllZero() const;
  // Applies "name=value" or "name=x,y,z" (name in either form above). Throws rotorid::Error.
  void Assign(const std::string& assignment);

 private:
  std::vector<Eigen::VectorXd> values_;  // by registry index; empty: absent
};

// The effects of one stage that act, in chain order, with their values.
struct EffectChain {
  std::vector<EffectKind> kinds;
  std::vector<Eigen::VectorXd> values;
  // Pointers to the values, as the stage hooks take them (valid while the chain lives).
  std::vector<const double*> Parameters() const;
};
// The effects of `stage` that are non-zero in `effects` or listed in `also` (free ones, whose
// derivative is wanted even at zero).
EffectChain ActingEffects(const Effects& effects, EffectStage stage, const std::vector<EffectKind>& also = {});

// Corrects an IMU sample from the log to the body at O_b: parameters[j] are those of chain[j]
// (IMU effects in increasing chain order; the corrections run backwards).
template <typename T>
void CorrectImu(const std::vector<EffectKind>& chain, const std::vector<const T*>& parameters, ImuSample<T>* s) {
  for (size_t j = chain.size(); j-- > 0;) chain[j]->CorrectImu(parameters[j], s);
}

// The effects a vehicle file gives known values of (EffectDescriptor::Info::vehicle_key).
Effects KnownEffects(const Vehicle& vehicle);

// The rotor-wrench effects' terms at one sample: parameters[j] are those of chain[j].
template <typename T>
void AddRotorWrench(const std::vector<EffectKind>& chain, const std::vector<const T*>& parameters,
                    const RotorSample<T>& sample, RotorWrenchTerms<T>* terms) {
  for (size_t j = 0; j < chain.size(); ++j) chain[j]->AddRotorWrench(parameters[j], sample, terms);
}

}  // namespace rotorid
