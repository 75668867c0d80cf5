#include "diagnosis/scale_free.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "diagnosis/verdicts.h"
#include "refine/effect_rows.h"
#include "rotorid/ident/identify.h"
#include "rotorid/model/parameters.h"
#include "rotorid/model/rigid_body.h"
#include "rotorid/signal/autocorrelation.h"

namespace rotorid::internal {

namespace {

constexpr int kKnownColumn = kNumIdimColumns - 1;
// A rotor coefficient whose relative std in the final fit is below this fixes an SI value.
constexpr double kKnownCoefficientRelativeStd = 0.1;
// A candidate's coordinate whose column in the row comes at least this much (in squared norm) from
// the known column, a term that does not scale with the rotor coefficient, is a ratio to that
// coefficient (a torque J sum(+-Omega') beside kd sum(+-Omega^2)).
constexpr double kMostlyKnownColumn = 0.5;

// A row whose fit without the candidate leaves a held-out relative error of this or more predicts
// its held-out rows no better than zero: a test on top of it judges nothing (jana01 and jana04 by
// RPM: 159 and 156 %), and it selects nothing there.
constexpr double kUnpredictedRowPct = 100.0;

// The rotor coefficient of a component: kd carries the yaw moment, kt the others.
int RotorCoefficientOf(int component) { return component == 5 ? 1 : 0; }

// One flight's row of the component at its row samples: the IDIM columns (row sample x column) and,
// per coordinate of the candidate, their derivatives with respect to it.
struct ComponentRows {
  Eigen::MatrixXd columns;
  std::vector<Eigen::MatrixXd> derivative;
  int config = 0;  // index of its configuration (the body columns are per configuration)
};

// The rows are summed over a sliding window of this length before they are fitted (see
// IntegrateOverWindow).
constexpr double kIntegrationWindowS = 0.5;

// Each column replaced by its sum over the last kIntegrationWindowS of contiguous row samples (rows
// whose window would reach across a gap, or before the flight's first row, are dropped). The row is
// linear in its coefficients, so the summed rows obey the same equation; but the summed derivative
// columns are differences of measured signals (w_z' becomes w_z(t) - w_z(t - T), Omega' likewise)
// instead of differentiated noise. In the yaw row the rotor torque J sum(+-Omega') and I_zz w_z' are
// nearly collinear (the rotors' reaction is what turns the body), and fitted on the raw rows that
// noise halved J / kd (rotor_inertia on rotorid's A: 451 +- 60 for 980).
void IntegrateOverWindow(const ProcessedFlight& flight, ComponentRows* rows) {
  const int n = flight.num_rows_samples();
  if (n < 2) return;
  std::vector<int> steps;
  for (int r = 1; r < n; ++r) steps.push_back(flight.row_samples[r] - flight.row_samples[r - 1]);
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  const int step = steps[steps.size() / 2];
  const int window = std::max(1, static_cast<int>(std::lround(kIntegrationWindowS / (step * flight.dt_s))));
  std::vector<int> kept;  // the last row of each full window
  for (int r = 0, run_start = 0; r < n; ++r) {
    if (r > 0 && flight.row_samples[r] - flight.row_samples[r - 1] != step) run_start = r;
    if (r - run_start + 1 >= window) kept.push_back(r);
  }
  auto sum = [&](const Eigen::MatrixXd& m) {
    Eigen::MatrixXd cumulative = Eigen::MatrixXd::Zero(n + 1, m.cols());
    for (int r = 0; r < n; ++r) cumulative.row(r + 1) = cumulative.row(r) + m.row(r);
    Eigen::MatrixXd out(static_cast<Eigen::Index>(kept.size()), m.cols());
    for (size_t k = 0; k < kept.size(); ++k)
      out.row(static_cast<Eigen::Index>(k)) = cumulative.row(kept[k] + 1) - cumulative.row(kept[k] + 1 - window);
    return out;
  };
  rows->columns = sum(rows->columns);
  for (Eigen::MatrixXd& d : rows->derivative) d = sum(d);
}

ComponentRows RowsOf(const ProcessedFlight& flight, const Effects& model, EffectKind kind, int component, int config) {
  Effects effects = model;
  effects.Set(kind, model.Get(kind, flight.vehicle));  // the Jets need a value of the free effect
  const std::vector<EffectKind> rotor_free =
      kind->stage() == EffectStage::kRotorSignal ? std::vector<EffectKind>{kind} : std::vector<EffectKind>{};
  const EffectiveRotor rotor = EffectiveRotorAtRows(flight, effects, rotor_free);
  const EffectRows rows(&flight, effects, {kind}, &rotor);
  const int samples = flight.num_rows_samples();
  const size_t coordinates = rows.coordinates().size();
  ComponentRows out;
  out.config = config;
  out.columns.resize(samples, kNumIdimColumns);
  out.derivative.assign(coordinates, Eigen::MatrixXd(samples, kNumIdimColumns));
  for (size_t first = 0; first < std::max<size_t>(coordinates, 1); first += kWideImuJetSize) {
    const EffectRows::PassValues<WideImuJet> pass = rows.Pass<WideImuJet>(first);
    for (int r = 0; r < samples; ++r) {
      const Eigen::Matrix<WideImuJet, 6, kNumIdimColumns> w = rows.Rows<WideImuJet>(r, pass);
      for (int c = 0; c < kNumIdimColumns; ++c) {
        out.columns(r, c) = w(component, c).a;
        for (size_t k = first; k < std::min(coordinates, first + kWideImuJetSize); ++k)
          out.derivative[k](r, c) = w(component, c).v[k - first];
      }
    }
  }
  IntegrateOverWindow(flight, &out);
  return out;
}

// Which IDIM columns the ratio fit estimates: every column but the rotor coefficient's that is not
// zero in the row, body columns once per configuration.
struct RowLayout {
  int target = 1;
  int configs = 1;
  std::vector<int> free_columns;  // IDIM columns
  bool known_free = false;        // the known column carries a kept effect's term in this row
  // Index of (configuration, IDIM column) in the fit's coefficients, -1 when not estimated.
  int Coefficient(int config, int column) const {
    const auto it = std::find(free_columns.begin(), free_columns.end(), column);
    if (it == free_columns.end()) return -1;
    const int position = static_cast<int>(it - free_columns.begin());
    int index = 0;
    for (int p = 0; p < position; ++p) index += PerConfig(free_columns[p]) ? configs : 1;
    return index + (PerConfig(column) ? config : 0);
  }
  int BodySize() const { return free_columns.empty() ? 0 : Coefficient(configs - 1, free_columns.back()) + 1; }
  // A constant torque per configuration follows the IDIM columns: a real vehicle's rotors differ in
  // kd and their axes tilt a little, which leaves a nearly constant yaw torque that the rotor term
  // does not carry (jana06 by RPM: held-out Mz relative error of the row 142 % without it, 99 % with).
  int Constant(int config) const { return BodySize() + config; }
  int Size() const { return BodySize() + configs; }
  static bool PerConfig(int column) { return column >= kNumRotorCoefficients && column < kKnownColumn; }
};

RowLayout LayoutOf(const std::vector<ComponentRows>& rows, int component, int configs) {
  RowLayout layout;
  layout.target = RotorCoefficientOf(component);
  layout.configs = configs;
  for (int c = 0; c < kNumIdimColumns; ++c) {
    if (c == layout.target) continue;
    bool nonzero = false;
    for (const ComponentRows& r : rows) nonzero = nonzero || r.columns.col(c).cwiseAbs().maxCoeff() > 0.0;
    if (!nonzero) continue;
    layout.free_columns.push_back(c);
    if (c == kKnownColumn) layout.known_free = true;
  }
  return layout;
}

// The stacked ratio regression of a set of rows: target (the rotor coefficient's column, its
// coefficient fixed at 1) and the estimated columns, then the candidate's when `ratios` (per
// configuration, the IDIM coefficients of a fit without it) are given: its derivative of the row at
// those coefficients.
struct RatioDesign {
  Eigen::VectorXd target;
  Eigen::MatrixXd x;
  std::vector<Eigen::Index> segment_end;  // rows of each flight, cumulative
};

RatioDesign DesignOf(const std::vector<ComponentRows>& rows, const RowLayout& layout,
                     const std::vector<Eigen::VectorXd>* ratios) {
  Eigen::Index n = 0;
  for (const ComponentRows& r : rows) n += r.columns.rows();
  const Eigen::Index coordinates = ratios && !rows.empty() ? static_cast<Eigen::Index>(rows[0].derivative.size()) : 0;
  RatioDesign design;
  design.target.resize(n);
  design.x = Eigen::MatrixXd::Zero(n, layout.Size() + coordinates);
  Eigen::Index offset = 0;
  for (const ComponentRows& r : rows) {
    const Eigen::Index m = r.columns.rows();
    design.target.segment(offset, m) = r.columns.col(layout.target);
    for (int c : layout.free_columns) design.x.block(offset, layout.Coefficient(r.config, c), m, 1) = r.columns.col(c);
    design.x.block(offset, layout.Constant(r.config), m, 1).setOnes();
    for (Eigen::Index k = 0; k < coordinates; ++k)
      design.x.block(offset, layout.Size() + k, m, 1) =
          r.derivative[static_cast<size_t>(k)] * (*ratios)[static_cast<size_t>(r.config)];
    offset += m;
    design.segment_end.push_back(offset);
  }
  return design;
}

// The least-squares solution b of x b = rhs, the columns of x equilibrated first (the rotor, inertia
// and first-moment columns differ by orders of magnitude); collinear columns (I_xx and I_yy in Mz:
// -w_x w_y and w_x w_y) get the minimum-norm split, which leaves the residual unchanged.
Eigen::MatrixXd EquilibratedLeastSquares(const Eigen::MatrixXd& x, const Eigen::MatrixXd& rhs) {
  const Eigen::VectorXd norms = x.colwise().norm().transpose();
  const Eigen::VectorXd inverse = norms.unaryExpr([](double v) { return v > 0.0 ? 1.0 / v : 0.0; });
  const Eigen::MatrixXd scaled = x * inverse.asDiagonal();
  return inverse.asDiagonal() * Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(scaled).solve(rhs);
}

// Minimises ||target + x b||.
Eigen::VectorXd SolveRow(const RatioDesign& design) { return EquilibratedLeastSquares(design.x, -design.target); }

Eigen::VectorXd RowResidual(const RatioDesign& design, const Eigen::VectorXd& b) {
  return design.target + design.x * b;
}

// Whether the candidate's own term enters the known column (a rotor-wrench effect's extra wrench,
// which does not scale with the rotor coefficient): divided by it, its coefficient there is a ratio
// to that coefficient, and its column is the term itself, whatever the fit gives the known column
// for the kept effects' terms.
bool OwnTermInKnownColumn(EffectKind kind) { return kind->stage() == EffectStage::kRotorWrench; }

// Per configuration, the IDIM coefficients of the row at which the candidate's columns are taken: 1
// for the rotor coefficient, the fitted ratios, and for the known column 1 unless the fit estimates
// it for the kept effects' terms and the candidate has none of its own there.
std::vector<Eigen::VectorXd> RatiosOf(const Eigen::VectorXd& b, const RowLayout& layout, EffectKind kind) {
  std::vector<Eigen::VectorXd> out;
  for (int config = 0; config < layout.configs; ++config) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(kNumIdimColumns);
    u[layout.target] = 1.0;
    for (int c : layout.free_columns) u[c] = b[layout.Coefficient(config, c)];
    if (!layout.known_free || OwnTermInKnownColumn(kind)) u[kKnownColumn] = 1.0;
    out.push_back(u);
  }
  return out;
}

// The row fitted without the candidate, then with its columns at that fit's ratios (one
// Gauss-Newton step from its value in the model; exact for a term linear in the candidate).
struct RowFits {
  RatioDesign without, with;
  Eigen::VectorXd b_without, b_with;
};

RowFits FitRow(const std::vector<ComponentRows>& rows, const RowLayout& layout, EffectKind kind) {
  RowFits fits;
  fits.without = DesignOf(rows, layout, nullptr);
  fits.b_without = SolveRow(fits.without);
  const std::vector<Eigen::VectorXd> ratios = RatiosOf(fits.b_without, layout, kind);
  fits.with = DesignOf(rows, layout, &ratios);
  fits.b_with = SolveRow(fits.with);
  return fits;
}

std::vector<Eigen::VectorXd> Segments(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& ends) {
  std::vector<Eigen::VectorXd> out;
  Eigen::Index start = 0;
  for (Eigen::Index end : ends) {
    out.push_back(v.segment(start, end - start));
    start = end;
  }
  return out;
}

// The held-out gap of the row's residual segments, each scaled by its flight's baseline RMS
// (`scale`), as ScoreHeldOut scales the components it weighs.
HeldOutGap RowGap(const std::vector<Eigen::VectorXd>& residual, const std::vector<int>& flight,
                  const std::vector<double>& scale) {
  HeldOutGap gap;
  std::vector<Eigen::VectorXd> whitened;
  for (size_t s = 0; s < residual.size(); ++s) {
    whitened.push_back(residual[s] / scale[static_cast<size_t>(flight[s])]);
    gap.whitened_ssr += whitened.back().squaredNorm();
    gap.entries += static_cast<int>(whitened.back().size());
  }
  gap.autocorrelation_factor = AutocorrelationFactor(whitened);
  return gap;
}

std::vector<ComponentRows> RowsOfFlights(const std::vector<ProcessedFlight>& flights, const Effects& model,
                                         EffectKind kind, int component, const std::vector<std::string>& configs) {
  std::vector<ComponentRows> rows;
  for (const ProcessedFlight& f : flights)
    rows.push_back(
        RowsOf(f, model, kind, component,
               static_cast<int>(std::find(configs.begin(), configs.end(), f.vehicle.name) - configs.begin())));
  return rows;
}

// The held-out part: per fold, fitted on its training rows, scored on its held-out rows.
void HeldOutRowTest(EffectKind kind, int component, const ScaleFreeData& data, const RowLayout& layout,
                    const std::vector<std::string>& configs, const DiagnosisOptions& options, ScaleFreeTest* out) {
  std::vector<Eigen::VectorXd> without, with;
  std::vector<int> flight;
  double rotor_sq = 0.0;
  for (size_t k = 0; k < data.folds.size(); ++k) {
    const Fold& fold = data.folds[k];
    const RowFits fits =
        FitRow(RowsOfFlights(fold.train, data.fold_effects[k], kind, component, configs), layout, kind);
    const std::vector<ComponentRows> held =
        RowsOfFlights(fold.evaluate, data.fold_effects[k], kind, component, configs);
    const std::vector<Eigen::VectorXd> ratios = RatiosOf(fits.b_without, layout, kind);
    const RatioDesign held_without = DesignOf(held, layout, nullptr), held_with = DesignOf(held, layout, &ratios);
    for (const Eigen::VectorXd& s : Segments(RowResidual(held_without, fits.b_without), held_without.segment_end))
      without.push_back(s);
    for (const Eigen::VectorXd& s : Segments(RowResidual(held_with, fits.b_with), held_with.segment_end))
      with.push_back(s);
    for (int f : fold.evaluate_flight) flight.push_back(f);
    rotor_sq += held_without.target.squaredNorm();
  }
  const int flights = flight.empty() ? 0 : *std::max_element(flight.begin(), flight.end()) + 1;
  std::vector<double> sum_sq(static_cast<size_t>(flights), 0.0), rows(static_cast<size_t>(flights), 0.0);
  double without_sq = 0.0, with_sq = 0.0;
  for (size_t s = 0; s < without.size(); ++s) {
    sum_sq[static_cast<size_t>(flight[s])] += without[s].squaredNorm();
    rows[static_cast<size_t>(flight[s])] += static_cast<double>(without[s].size());
    without_sq += without[s].squaredNorm();
    with_sq += with[s].squaredNorm();
  }
  std::vector<double> scale(static_cast<size_t>(flights), 1.0);
  for (size_t f = 0; f < scale.size(); ++f)
    if (sum_sq[f] > 0.0) scale[f] = std::sqrt(sum_sq[f] / rows[f]);
  out->test =
      TestAddedEffects(RowGap(without, flight, scale), RowGap(with, flight, scale),
                       kind->FreeDimension(data.flights.front().vehicle), options.alpha, options.min_shrink_pct);
  if (rotor_sq > 0.0) {
    out->relative_error_before_pct = 100.0 * std::sqrt(without_sq / rotor_sq);
    out->relative_error_after_pct = 100.0 * std::sqrt(with_sq / rotor_sq);
  }
}

// The candidate's value and std on all identification data: the fitted coefficients of its columns
// with the other columns profiled out, the std from the residual variance inflated for its
// autocorrelation; and whether each coordinate is a ratio to the rotor coefficient.
void ValueOnAllData(EffectKind kind, const std::vector<ComponentRows>& rows, const ScaleFreeData& data,
                    const RowLayout& layout, ScaleFreeTest* out) {
  const RowFits fits = FitRow(rows, layout, kind);
  const Eigen::Index p = layout.Size(), q = fits.with.x.cols() - p;
  const Eigen::VectorXd residual = RowResidual(fits.with, fits.b_with);
  const double sigma2 = residual.squaredNorm() / std::max<double>(1.0, static_cast<double>(residual.size() - p - q));
  const double factor = AutocorrelationFactor(Segments(residual, fits.with.segment_end));
  const Eigen::MatrixXd others = fits.with.x.leftCols(p), candidate = fits.with.x.rightCols(q);
  Eigen::MatrixXd projected = candidate;
  if (p > 0) projected -= others * EquilibratedLeastSquares(others, candidate);
  const Eigen::MatrixXd covariance =
      sigma2 * factor *
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(projected.transpose() * projected).pseudoInverse();
  out->ratio = fits.b_with.tail(q);
  out->ratio_std = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const std::vector<std::string> labels = EffectLabels(kind, data.flights.front().vehicle);
  const std::string coefficient = kRotorCoefficientNames[static_cast<size_t>(layout.target)];
  for (Eigen::Index k = 0; k < q; ++k) {
    double known_sq = 0.0, all_sq = 0.0;
    for (const ComponentRows& r : rows) {
      const Eigen::MatrixXd& d = r.derivative[static_cast<size_t>(k)];
      known_sq += d.col(kKnownColumn).squaredNorm();
      all_sq += d.squaredNorm();
    }
    const bool ratio =
        (!layout.known_free || OwnTermInKnownColumn(kind)) && all_sq > 0.0 && known_sq >= kMostlyKnownColumn * all_sq;
    out->over_rotor_coefficient.push_back(ratio);
    out->labels.push_back(labels[static_cast<size_t>(k)] + (ratio ? " / " + coefficient : ""));
  }
}

// The SI value when the final fit fixes the rotor coefficient.
void ValueInSi(const ScaleFreeData& data, ScaleFreeTest* out) {
  const auto value = data.final_parameters.find(out->rotor_coefficient);
  const auto std_dev = data.final_parameter_std.find(out->rotor_coefficient);
  if (value == data.final_parameters.end() || std_dev == data.final_parameter_std.end()) return;
  const double c = value->second, c_std = std_dev->second;
  if (!(c > 0.0) || !(c_std < kKnownCoefficientRelativeStd * c)) return;
  out->value = out->ratio;
  out->std = out->ratio_std;
  for (Eigen::Index k = 0; k < out->ratio.size(); ++k) {
    if (!out->over_rotor_coefficient[static_cast<size_t>(k)]) continue;
    out->value[k] = out->ratio[k] * c;
    out->std[k] = std::hypot(out->ratio_std[k] * c, out->ratio[k] * c_std);
  }
}

}  // namespace

bool ScaleFreeTestable(EffectKind kind, const EffectLinearization& linearization) {
  if (kind->info().zero_sum || !kind->info().held_coordinates.empty()) return false;
  const auto k = std::find(linearization.kinds.begin(), linearization.kinds.end(), kind);
  if (k == linearization.kinds.end()) return false;
  bool any = false;
  for (size_t c = 0; c < linearization.column_kind.size(); ++c) {
    if (linearization.column_kind[c] != k - linearization.kinds.begin()) continue;
    any = true;
    if (!(linearization.effect_unscored_share[static_cast<Eigen::Index>(c)] > kMostlyUnscored)) return false;
  }
  return any;
}

ScaleFreeTest TestScaleFree(EffectKind kind, int component, const ScaleFreeData& data,
                            const DiagnosisOptions& options) {
  ScaleFreeTest out;
  out.component = component;
  const std::vector<std::string> configs = ConfigurationNames(data.flights);
  const std::vector<ComponentRows> all_rows = RowsOfFlights(data.flights, data.final_effects, kind, component, configs);
  const RowLayout layout = LayoutOf(all_rows, component, static_cast<int>(configs.size()));
  out.rotor_coefficient = kRotorCoefficientNames[static_cast<size_t>(layout.target)];
  HeldOutRowTest(kind, component, data, layout, configs, options, &out);
  ValueOnAllData(kind, all_rows, data, layout, &out);
  ValueInSi(data, &out);
  // Ratios keep the sign (the rotor coefficients are positive): a sign-constrained effect (J >= 0)
  // below zero beyond 3 std absorbs something else.
  if (kind->info().lower_bound == 0.0)
    for (Eigen::Index k = 0; k < out.ratio.size() && out.implausible.empty(); ++k)
      if (out.ratio[k] + 3.0 * out.ratio_std[k] < 0.0)
        out.implausible = out.labels[static_cast<size_t>(k)] + " < 0 beyond 3 std, against its sign convention";
  return out;
}

std::vector<EffectKind> SelectInUnscoredComponents(const EffectLinearization& linearization, const ScaleFreeData& data,
                                                   const DiagnosisOptions& options, const Vehicle& vehicle,
                                                   std::vector<EffectVerdict>* verdicts) {
  std::vector<EffectKind> selected;
  for (EffectVerdict& v : *verdicts) {
    if (v.selected || v.status == "implausible" || !ScaleFreeTestable(v.kind, linearization)) continue;
    for (int component : linearization.unscored_components) {
      if (component < 2) continue;  // Fx, Fy have no rotor term to be a ratio to
      ScaleFreeTest test = TestScaleFree(v.kind, component, data, options);
      if (!v.scale_free || test.test.shrink_pct > v.scale_free->test.shrink_pct) v.scale_free = std::move(test);
    }
    if (!v.scale_free) continue;
    ScaleFreeTest& t = *v.scale_free;
    if (t.implausible.empty() && t.value.size() > 0) t.implausible = v.kind->Implausible(t.value, t.std, vehicle);
    if (!t.test.significant || !t.implausible.empty() || !(t.relative_error_before_pct < kUnpredictedRowPct)) continue;
    v.selected = v.significant = true;
    v.status = "selected";
    v.test = t.test;
    v.value = t.value;
    v.std = t.std;
    v.unscored.clear();
    selected.push_back(v.kind);
  }
  return selected;
}

}  // namespace rotorid::internal
