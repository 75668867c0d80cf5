#include "rotorid/diagnosis/diagnosis_json.h"

#include "rotorid/model/parameters.h"

namespace rotorid {

namespace {

using nlohmann::json;

json Components(const std::vector<std::optional<double>>& values) {
  json out = json::object();
  for (size_t j = 0; j < values.size() && j < kWrenchComponentNames.size(); ++j)
    out[kWrenchComponentNames[j]] = values[j] ? json(*values[j]) : json(nullptr);
  return out;
}

json Components(const ComponentVector& values) {
  json out = json::object();
  for (int j = 0; j < kNumWrenchComponents; ++j) out[kWrenchComponentNames[j]] = values[j];
  return out;
}

// A scalar effect parameter as a number, a vector one as [x, y, z].
json EffectValue(const Eigen::VectorXd& v) {
  if (v.size() == 1) return v[0];
  json out = json::array();
  for (Eigen::Index k = 0; k < v.size(); ++k) out.push_back(v[k]);
  return out;
}

// An effect's coordinates under the parameter names INTERFACE.md gives them, as refine and the
// simulator's truth write them: one key per coefficient of an effect whose coefficients it names
// apart (rotor_drag: rotor_drag_coefficient, flapping_moment_coefficient; null without a value),
// else one key with a number or an array.
json ByParameter(EffectKind kind, const Eigen::VectorXd& v) {
  const std::vector<std::string>& labels = kind->info().labels;
  json out = json::object();
  if (labels.empty()) {
    out[EffectParameterName(kind)] = EffectValue(v);
    return out;
  }
  for (size_t k = 0; k < labels.size(); ++k)
    out[labels[k]] = static_cast<Eigen::Index>(k) < v.size() ? json(v[static_cast<Eigen::Index>(k)]) : json(nullptr);
  return out;
}

// {parameter: {value, std}} of ByParameter.
json MagnitudeJson(EffectKind kind, const Eigen::VectorXd& value, const Eigen::VectorXd& std_dev) {
  const json values = ByParameter(kind, value), stds = ByParameter(kind, std_dev);
  json out = json::object();
  for (const auto& [name, x] : values.items()) out[name] = {{"value", x}, {"std", stds[name]}};
  return out;
}

json Kinds(const std::vector<EffectKind>& kinds) {
  json out = json::array();
  for (EffectKind kind : kinds) out.push_back(EffectName(kind));
  return out;
}

json GapJson(const HeldOutGap& gap) {
  return {{"relative_error_pct", Components(gap.relative_error_pct)},
          {"gap_pct", Components(gap.gap_pct)},
          {"noise_floor_pct", Components(gap.noise_floor_pct)},
          {"model_error_pct", Components(gap.model_error_pct)},
          {"residual_rms", Components(gap.residual_rms)},
          {"whitened_ssr", gap.whitened_ssr},
          {"entries", gap.entries},
          {"autocorrelation_factor", gap.autocorrelation_factor}};
}

json TestJson(const EffectTest& test) {
  return {{"shrink_pct", test.shrink_pct},
          {"f_statistic", test.f_statistic},
          {"p_value", test.p_value},
          {"added_parameters", test.added_parameters},
          {"effective_samples", test.effective_samples},
          {"significant", test.significant},
          {"screened", test.screened}};
}

json ScaleFreeJson(const ScaleFreeTest& t) {
  json values = json::object();
  for (size_t k = 0; k < t.labels.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    values[t.labels[k]] = {
        {"value", t.ratio[i]}, {"std", t.ratio_std[i]}, {"ratio", bool(t.over_rotor_coefficient[k])}};
  }
  return {{"component", kWrenchComponentNames[static_cast<size_t>(t.component)]},
          {"rotor_coefficient", t.rotor_coefficient},
          {"test", TestJson(t.test)},
          {"relative_error_before_pct", t.relative_error_before_pct},
          {"relative_error_after_pct", t.relative_error_after_pct},
          {"values", values},
          {"si_value", t.value.size() > 0 ? EffectValue(t.value) : json(nullptr)},
          {"si_std", t.std.size() > 0 ? EffectValue(t.std) : json(nullptr)},
          {"implausible", t.implausible}};
}

json LocationJson(const GapLocation& where) {
  json bands = json::array();
  for (const BandGap& b : where.bands)
    bands.push_back({{"low_hz", b.low_hz},
                     {"high_hz", b.high_hz},
                     {"residual_rms", Components(b.residual_rms)},
                     {"final_residual_rms", Components(b.final_residual_rms)},
                     {"model_rms", Components(b.model_rms)},
                     {"share_pct", Components(b.share_pct)},
                     {"residual_to_model_pct", Components(b.residual_to_model_pct)}});
  json stretches = json::array();
  for (const FlightStretch& s : where.worst_stretches)
    stretches.push_back({{"flight", s.flight},
                         {"start_s", s.start_s},
                         {"end_s", s.end_s},
                         {"mean_square_ratio", s.mean_square_ratio},
                         {"dominant_component", kWrenchComponentNames[s.dominant_component]},
                         {"relative_error_pct", Components(s.relative_error_pct)},
                         {"angular_velocity_rms", EffectValue(s.angular_velocity_rms)},
                         {"mean_vertical_acceleration_mps2", s.mean_vertical_acceleration_mps2},
                         {"activities", s.activities}});
  json signatures = json::array();
  for (const EffectSignature& s : where.signatures) {
    json parameters = json::object();
    for (size_t k = 0; k < s.labels.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      parameters[s.labels[k]] = {{"residual_correlation", s.residual_correlation[i]},
                                 {"linearized_estimate", s.linearized_estimate[i]},
                                 {"linearized_std", s.linearized_std[i]}};
    }
    signatures.push_back({{"effect", EffectName(s.kind)},
                          {"parameters", parameters},
                          {"linearized_shrink_pct", s.linearized_shrink_pct},
                          {"component_share_pct", Components(s.component_share_pct)}});
  }
  return {{"in_sample_relative_error_pct", Components(where.relative_error_pct)},
          {"bands", bands},
          {"worst_stretches", stretches},
          {"signatures", signatures}};
}

json UnexplainedJson(const std::vector<UnexplainedResidual>& unexplained) {
  json out = json::array();
  for (const UnexplainedResidual& u : unexplained) {
    json stretch = nullptr;
    if (u.stretch)
      stretch = {{"flight", u.stretch->flight}, {"start_s", u.stretch->start_s}, {"end_s", u.stretch->end_s}};
    out.push_back({{"component", kWrenchComponentNames[u.component]},
                   {"gap_pct", u.gap_pct},
                   {"noise_floor_pct", u.noise_floor_pct},
                   {"share_pct", u.share_pct},
                   {"band", {{"low_hz", u.band_low_hz}, {"high_hz", u.band_high_hz}, {"share_pct", u.band_share_pct}}},
                   {"stretch", stretch},
                   {"note", u.note}});
  }
  return out;
}

}  // namespace

json DiagnosisOptionsJson(const DiagnosisOptions& o) {
  json bands = json::array();
  for (const auto& [low, high] : o.location.bands) bands.push_back({low, high});
  return {{"candidates", Kinds(o.candidates)},
          {"folds", o.folds},
          {"guard_s", o.guard_s},
          {"alpha", o.alpha},
          {"min_shrink_pct", o.min_shrink_pct},
          {"max_effects", o.max_effects},
          {"screen_fraction", o.screen_fraction},
          {"rival_fraction", o.rival_fraction},
          {"max_component_growth_pct", o.max_component_growth_pct},
          {"component_growth_alpha", o.component_growth_alpha},
          {"delay_search_s", {o.delay_search.min_s, o.delay_search.max_s, o.delay_search.step_s}},
          {"refine_max_iterations", o.refine_max_iterations},
          {"reselect_essential", o.reselect_essential},
          {"bands_hz", bands},
          {"window_s", o.location.window_s},
          {"window_step_s", o.location.window_step_s},
          {"unexplained_floor_ratio", o.unexplained_floor_ratio},
          {"unexplained_min_pct", o.unexplained_min_pct},
          {"num_threads", o.num_threads}};
}

json DiagnosisJson(const Diagnosis& d) {
  json ranking = json::array();
  for (const EffectVerdict& v : d.ranking) {
    json entry = {{"effect", EffectName(v.kind)},
                  {"status", v.status},
                  {"significant", v.significant},
                  {"shrink_pct", v.test.shrink_pct},
                  {"magnitude", MagnitudeJson(v.kind, v.value, v.std)},
                  {"detectable_above", ByParameter(v.kind, v.detectable_above)},
                  {"step", v.step},
                  {"tested_on_top_of", Kinds(v.tested_on_top_of)},
                  {"test", TestJson(v.test)},
                  {"screening", TestJson(v.screening)},
                  {"relative_error_pct", Components(v.relative_error_pct)},
                  {"confounded_with", Kinds(v.confounded_with)},
                  {"dropped_as_redundant", v.dropped_as_redundant},
                  {"note", v.note}};
    if (const std::vector<std::string> held = v.kind->HeldLabels(static_cast<int>(v.value.size())); !held.empty())
      for (auto& [name, magnitude] : entry["magnitude"].items()) magnitude["held"] = held;
    entry["alone"] = v.alone_test ? TestJson(*v.alone_test) : json(nullptr);
    if (v.scale_free) entry["scale_free"] = ScaleFreeJson(*v.scale_free);
    // Selected by a scale-free test whose rotor coefficient no fit fixes: no value in SI.
    if (v.selected && v.scale_free && v.value.size() == 0)
      for (auto& [name, magnitude] : entry["magnitude"].items()) magnitude = {{"value", nullptr}, {"std", nullptr}};
    ranking.push_back(entry);
  }
  json steps = json::array();
  for (const SelectionStep& s : d.steps)
    steps.push_back({{"added", EffectName(s.added)},
                     {"shrink_pct", s.test.shrink_pct},
                     {"test", TestJson(s.test)},
                     {"before",
                      {{"relative_error_pct", Components(s.before.relative_error_pct)},
                       {"gap_pct", Components(s.before.gap_pct)},
                       {"residual_rms", Components(s.before.residual_rms)}}},
                     {"after",
                      {{"relative_error_pct", Components(s.after.relative_error_pct)},
                       {"gap_pct", Components(s.after.gap_pct)},
                       {"residual_rms", Components(s.after.residual_rms)}}}});
  json confounded = json::array();
  for (const ConfoundedEffects& c : d.confounded)
    confounded.push_back({{"effects", {EffectName(c.selected), EffectName(c.other)}},
                          {"correlation", c.correlation ? json(*c.correlation) : json(nullptr)},
                          {"correlated_parameters", c.correlated_labels},
                          {"shrink_pct", {c.selected_shrink_pct, c.other_shrink_pct}},
                          {"t_statistic", c.t_statistic},
                          {"p_value", c.p_value},
                          {"distinguishable", c.distinguishable},
                          {"note", c.note}});
  json final_effects = json::object();
  for (EffectKind kind : d.final_model)
    final_effects.update(MagnitudeJson(kind, d.final_effects.Get(kind), d.final_effects_std.Get(kind)));
  json where = LocationJson(d.where);
  where["component"] = kWrenchComponentNames[d.where_component];
  where["gap_pct"] = Components(d.baseline.gap_pct);
  where["model_error_pct"] = Components(d.baseline.model_error_pct);
  json final_block = GapJson(d.final_gap);
  final_block["effects"] = final_effects;
  final_block["parameters"] = d.final_parameters;
  json baseline = GapJson(d.baseline);
  baseline["parameters"] = d.linear_parameters;
  return {{"validation", d.validation},
          {"held_out_row_samples", d.held_out_row_samples},
          {"candidates", Kinds(d.candidates)},
          {"baseline", baseline},
          {"where", where},
          {"ranking", ranking},
          {"selected", Kinds(d.selected)},
          {"steps", steps},
          {"confounded", confounded},
          {"final", final_block},
          {"unexplained", UnexplainedJson(d.unexplained)},
          {"initial_delay_s", d.initial_delay_s},
          {"refinements", d.refinements},
          {"seconds", d.seconds},
          {"phase_seconds", d.phase_seconds},
          {"warnings", d.warnings},
          {"verdict", DiagnosisVerdict(d)}};
}

}  // namespace rotorid
