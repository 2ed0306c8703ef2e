#include "suppression/suppression_map/suppression_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <tuple>

#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/suppression.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "suppression/suppression_map/suppression_measures.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;
namespace sm = suppression_measures;

constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr const char* col_ratio = "log10_amplitude_ratio";
constexpr const char* col_s2 = "s2_predicted_log10_ratio";
constexpr const char* col_s2_locked = "s2_locked_lobe_log10_ratio";
constexpr const char* col_drift = "s2_phase_drift_rad";
constexpr const char* col_s3 = "s3_energy_change";
constexpr const char* col_s3_fraction = "s3_exciting_fraction";
constexpr const char* col_s1 = "s1_frequency_swing_hz";
constexpr const char* col_outcome = "simulation_outcome";

// Level grid of the cached growth-rate table: sigma(level) is computed at multiples of this and
// interpolated linearly (the rightmost root moves smoothly inside a lobe; 1e-3 of the mean speed
// is ~1/50 of a lobe at G8 wave counts).
constexpr double level_step = 1e-3;

// The plugin named by a component table's `type`, built from its other keys.
template <class Product>
std::unique_ptr<Product> build_component(const Registry<Product>& registry, const Json& table) {
  Json params = table;
  params.erase("type");
  return registry.at(table.at("type").get<std::string>()).create(ParamValues(std::move(params)));
}
std::unique_ptr<Model> build_model(const Json& table) { return build_component(model_registry(), table); }
std::unique_ptr<Suppression> build_suppression(const Json& table) {
  return build_component(suppression_registry(), table);
}

ParamSpec real_spec(std::string key, std::string unit, std::string description, double default_value,
                    double min, bool min_exclusive) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.default_value = default_value;
  spec.min = min;
  spec.min_exclusive = min_exclusive;
  return spec;
}

// ------------------------------------------------------------------ feed-dependent stiffness

// S1 (5-29): contact and wheel wear stiffness follow the relative thickness change,
// k = k0 (1 - eps/2 da/a), with da/a = rate(t)/mean rate - 1 for a modulated feed (the depth per
// revolution is proportional to the infeed rate). The G1 time-domain model has constant
// stiffnesses, so this wrapper rescales its force and removal exactly: F = interference/(1/kc +
// 1/kg + 1/kw) with kc, kg scaled by s becomes F * g, g = C0/(C_scaled/s + 1/kw), C0 the
// original series compliance; wheel removal F/kg scales by g/s, work removal F/kw by g.
struct PlungeStiffnesses {
  double kc = 0, kg = 0, kw = 0;
  bool wheel_on = true, work_on = true;
};

class FeedDependentStiffness final : public TimeDomainModel {
 public:
  FeedDependentStiffness(std::unique_ptr<TimeDomainModel> inner, PlungeStiffnesses k, double mean_rate,
                         double exponent)
      : inner_(std::move(inner)), k_(k), mean_rate_(mean_rate), exponent_(exponent) {}
  std::size_t state_size() const override { return inner_->state_size(); }
  void initial_state(const Disturbance& d, std::span<double> x) const override { inner_->initial_state(d, x); }
  void state_scales(double d, std::span<double> s) const override { inner_->state_scales(d, s); }
  double highest_frequency_hz() const override { return inner_->highest_frequency_hz(); }
  bool regenerates(Rotor r) const override { return inner_->regenerates(r); }
  double nominal_speed_rpm(Rotor r) const override { return inner_->nominal_speed_rpm(r); }
  void contact(const ContactInput& in, ContactOutput& out) const override {
    inner_->contact(in, out);
    const double s = 1.0 - 0.5 * exponent_ * (in.infeed_rate_m_per_s / mean_rate_ - 1.0);
    const double scaled = 1.0 / k_.kc + (k_.wheel_on ? 1.0 / k_.kg : 0.0);
    const double work = k_.work_on ? 1.0 / k_.kw : 0.0;
    const double g = (scaled + work) / (scaled / s + work);
    out.normal_force_n *= g;
    out.tangential_force_n *= g;
    out.removed_m[static_cast<std::size_t>(Rotor::wheel)] *= g / s;
    out.removed_m[static_cast<std::size_t>(Rotor::work)] *= g;
    out.depth_of_cut_m *= g;
  }
  void derivatives(const ContactInput& in, const ContactOutput& c, std::span<double> dx) const override {
    inner_->derivatives(in, c, dx);
  }
  double displacement_m(std::span<const double> state) const override { return inner_->displacement_m(state); }

 private:
  std::unique_ptr<TimeDomainModel> inner_;
  PlungeStiffnesses k_;
  double mean_rate_, exponent_;
};

// The unmodulated law (level 1): the reference of every comparison.
class ConstantLevel final : public ModulationLaw {
 public:
  double level(double) const override { return 1.0; }
  double level_integral(double t) const override { return t; }
  double min_level() const override { return 1.0; }
  double max_level() const override { return 1.0; }
};

// ------------------------------------------------------------------ per-study caches

// Results that depend only on the model and the settings, not on the modulation: the constant
// reference run and the growth-rate table. Kept process-wide (a kind holds no per-study state)
// and keyed by the JSON they depend on, each computed once even when threads ask together.
template <class Value>
class OnceCache {
 public:
  template <class Compute>
  Value get(const std::string& key, Compute compute) {
    std::shared_future<Value> future;
    std::promise<Value> promise;
    bool owner = false;
    {
      std::lock_guard lock(mutex_);
      auto it = entries_.find(key);
      if (it == entries_.end()) {
        future = promise.get_future().share();
        entries_.emplace(key, future);
        owner = true;
      } else {
        future = it->second;
      }
    }
    if (owner) {
      try {
        promise.set_value(compute());
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
    }
    return future.get();
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::shared_future<Value>> entries_;
};

struct Reference {
  double amplitude_m = 0.0;      // A_n at constant conditions (last wheel revolution)
  bool diverged = false;
  double growth_rate_per_s = 0;  // rightmost root at the nominal conditions
  double chatter_frequency_hz = 0;
  double wheel_rpm = 0, work_rpm = 0;
};

// sigma(level) and f(level) of the rightmost root at frozen modulated conditions, filled lazily on
// the level grid; one per (model, target, exponent).
class GrowthTable {
 public:
  GrowthTable(Json model, SuppressionTarget target, double exponent)
      : model_(std::move(model)), target_(target), exponent_(exponent) {}
  std::pair<double, double> root(double level) {  // (growth rate [1/s], frequency [Hz])
    const double x = (level - 1.0) / level_step;
    const long lo = static_cast<long>(std::floor(x));
    const double u = x - static_cast<double>(lo);
    const auto a = node(lo);
    if (u < 1e-12) return a;
    const auto b = node(lo + 1);
    return {a.first + u * (b.first - a.first), a.second + u * (b.second - a.second)};
  }

  // The [model] table at modulation level q/q_mean: the frozen conditions of that level.
  Json conditions(double level) const {
    Json m = model_;
    switch (target_) {
      case SuppressionTarget::wheel_speed: m["wheel_speed_rpm"] = level * m["wheel_speed_rpm"].get<double>(); break;
      case SuppressionTarget::work_speed: m["work_speed_rpm"] = level * m["work_speed_rpm"].get<double>(); break;
      case SuppressionTarget::feed: {
        const double s = 1.0 - 0.5 * exponent_ * (level - 1.0);
        for (const char* key : {"contact_stiffness_n_per_m", "wheel_wear_stiffness_n_per_m"})
          m[key] = s * m[key].get<double>();
        break;
      }
    }
    return m;
  }

 private:
  std::pair<double, double> node(long index) {
    {
      std::lock_guard lock(mutex_);
      auto it = nodes_.find(index);
      if (it != nodes_.end()) return it->second;
    }
    const double level = 1.0 + static_cast<double>(index) * level_step;
    auto fn = build_model(conditions(level))->characteristic();
    RootSearchOptions options;
    options.max_frequency_hz = 4.0 * fn->natural_frequency_scale_hz();
    const RightmostRoot r = find_rightmost_root(*fn, options);
    const std::pair<double, double> value{r.root.real(), std::abs(r.root.imag()) / kTwoPi};
    std::lock_guard lock(mutex_);
    nodes_.emplace(index, value);
    return value;
  }

 private:
  Json model_;
  SuppressionTarget target_;
  double exponent_;
  std::mutex mutex_;
  std::map<long, std::pair<double, double>> nodes_;
};

OnceCache<Reference>& reference_cache() {
  static OnceCache<Reference> cache;
  return cache;
}
OnceCache<std::shared_ptr<GrowthTable>>& table_cache() {
  static OnceCache<std::shared_ptr<GrowthTable>> cache;
  return cache;
}

// ------------------------------------------------------------------ one point

double wheel_rpm(const Json& model) { return model.at("wheel_speed_rpm").get<double>(); }

double run_duration(const Json& document) {
  return document.at("suppression_map").at("revolutions").get<double>() * 60.0 / wheel_rpm(document.at("model"));
}

SimulationSettings base_settings(const Json& document) {
  const Json& t = document.at("suppression_map");
  SimulationSettings s;
  s.duration_s = run_duration(document);
  s.sample_rate_hz = t.at("sample_rate_hz").get<double>();
  s.disturbance.displacement_m = t.at("initial_displacement_m").get<double>();
  s.initial_waviness_m = t.at("initial_waviness_m").get<double>();
  s.seed = t.at("seed").get<std::uint64_t>();
  s.infeed_rate_m_per_s = t.at("infeed_rate_m_per_s").get<double>();
  s.one_sided_contact = t.at("one_sided_contact").get<bool>();
  s.relative_tolerance = t.at("relative_tolerance").get<double>();
  s.divergence_limit_m = t.at("divergence_limit_m").get<double>();
  s.snapshot_times_s.clear();
  return s;
}

// Half the peak-to-peak swing of x about its least-squares line over the last wheel revolution
// at the mean speed: the vibration amplitude A_n after n revolutions (the line removes the static
// deflection that grows with the infeed).
double final_amplitude(const SimulationResult& r, double revolution_s) {
  const double end = r.t_s.empty() ? 0.0 : r.t_s.back();
  std::vector<double> t, x;
  for (std::size_t i = 0; i < r.t_s.size(); ++i)
    if (r.t_s[i] >= end - revolution_s) {
      t.push_back(r.t_s[i]);
      x.push_back(r.displacement_m[i]);
    }
  if (t.size() < 8) throw PointFailure("fewer than 8 output samples in the last wheel revolution");
  const double n = static_cast<double>(t.size());
  double st = 0, sx = 0, stt = 0, stx = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double ti = t[i] - t.front();
    st += ti; sx += x[i]; stt += ti * ti; stx += ti * x[i];
  }
  const double slope = (n * stx - st * sx) / (n * stt - st * st), offset = (sx - slope * st) / n;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double d = x[i] - offset - slope * (t[i] - t.front());
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return 0.5 * (hi - lo);
}

std::unique_ptr<TimeDomainModel> time_domain(const Json& document, SuppressionTarget target) {
  const Json& model = document.at("model");
  auto td = build_model(model)->time_domain();
  const double exponent = document.at("suppression_map").at("thickness_exponent").get<double>();
  // Without feed modulation the stiffness scale is 1: the plain model (the constant run's, so a
  // zero amplitude reproduces it exactly with the same integration).
  const bool modulated = document.at("suppression").value("amplitude_ratio", 0.0) != 0.0;
  if (target != SuppressionTarget::feed || exponent == 0.0 || !modulated) return td;
  PlungeStiffnesses k{model.at("contact_stiffness_n_per_m").get<double>(),
                      model.at("wheel_wear_stiffness_n_per_m").get<double>(),
                      model.at("work_removal_stiffness_n_per_m").get<double>(),
                      model.value("wheel_regeneration", true), model.value("work_regeneration", true)};
  return std::make_unique<FeedDependentStiffness>(
      std::move(td), k, document.at("suppression_map").at("infeed_rate_m_per_s").get<double>(), exponent);
}

SimulationResult run_simulation(const TimeDomainModel& model, const SimulationSettings& settings) {
  try {
    return simulate(model, settings);
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
}

std::string reference_key(const Json& document) {
  return document.at("model").dump() + "|" + document.at("suppression_map").dump();
}

Reference reference(const Json& document, GrowthTable& table) {
  return reference_cache().get(reference_key(document), [&] {
    Reference ref;
    auto model = build_model(document.at("model"))->time_domain();
    const SimulationResult r = run_simulation(*model, base_settings(document));
    ref.diverged = r.diverged;
    ref.amplitude_m = final_amplitude(r, 60.0 / wheel_rpm(document.at("model")));
    std::tie(ref.growth_rate_per_s, ref.chatter_frequency_hz) = table.root(1.0);
    ref.wheel_rpm = wheel_rpm(document.at("model"));
    ref.work_rpm = model->nominal_speed_rpm(Rotor::work);
    return ref;
  });
}

std::shared_ptr<GrowthTable> growth_table(const Json& document, SuppressionTarget target) {
  const double exponent = document.at("suppression_map").at("thickness_exponent").get<double>();
  const std::string key = fmt::format("{}|{}|{}", document.at("model").dump(), to_string(target), exponent);
  return table_cache().get(key, [&] {
    return std::make_shared<GrowthTable>(document.at("model"), target, exponent);
  });
}

// The feed-model parameters of 5.3.1 from a plunge_regenerative model: the structural mode
// nearest the chatter frequency as the single sensitive mode (m = k/wn^2).
std::optional<sm::FeedChatterModel> feed_model(const Model& model, double chatter_hz, double exponent) {
  const auto* plunge = dynamic_cast<const PlungeRegenerative*>(&model);
  if (!plunge || plunge->parameters().modes.empty()) return std::nullopt;
  const PlungeRegenerativeParameters& p = plunge->parameters();
  const StructuralMode* nearest = &p.modes.front();
  for (const StructuralMode& m : p.modes)
    if (std::abs(m.frequency_hz - chatter_hz) < std::abs(nearest->frequency_hz - chatter_hz)) nearest = &m;
  const double wn = kTwoPi * nearest->frequency_hz;
  const double inf = std::numeric_limits<double>::infinity();
  return sm::FeedChatterModel{nearest->stiffness_n_per_m / (wn * wn), nearest->stiffness_n_per_m,
                              p.contact_stiffness_n_per_m,
                              p.wheel_regeneration ? p.wheel_wear_stiffness_n_per_m : inf,
                              p.work_regeneration ? p.work_removal_stiffness_n_per_m : inf, exponent};
}

// Relative thickness change da/a at modulation level q/q_mean: the depth per work revolution is
// proportional to infeed rate / work speed.
double thickness_change(SuppressionTarget target, double level) {
  switch (target) {
    case SuppressionTarget::feed: return level - 1.0;
    case SuppressionTarget::work_speed: return 1.0 / level - 1.0;
    case SuppressionTarget::wheel_speed: return 0.0;
  }
  return 0.0;
}

// ------------------------------------------------------------------ plots

std::size_t column_index(const ResultTable& results, const std::string& name) {
  for (std::size_t c = 0; c < results.output_columns.size(); ++c)
    if (results.output_columns[c] == name) return results.grid_columns.size() + c;
  throw std::logic_error("suppression_map: no column " + name);
}

std::string study_title(const Study& study) {
  auto it = study.document.find("study");
  if (it != study.document.end() && it->is_object() && it->value("name", Json()).is_string())
    return (*it)["name"].get<std::string>();
  return study.file.stem().string();
}

std::string axis_label(const std::string& key) {
  if (key == "suppression.amplitude_ratio") return "modulation amplitude ratio a [1]";
  if (key == "suppression.frequency_hz") return "modulation frequency f [Hz]";
  return key;
}

bool log_axis(const Study& study, const GridAxis& axis) {
  auto grid = study.document.find("grid");
  if (grid == study.document.end() || !grid->is_object()) return false;
  auto range = grid->find(axis.key);
  return range != grid->end() && range->is_object() && range->value("log", false);
}

}  // namespace

// ------------------------------------------------------------------ the kind

PluginInfo SuppressionMap::info() {
  PluginInfo info;
  info.name = "suppression_map";
  info.description = "variable-speed/feed chatter suppression over a modulation grid: simulated "
                     "amplitude ratio vs constant speed, growth-rate averaging, energy balance (S1-S3)";
  info.models_md_ids = "S1, S2, S3, G3";
  ParamSpec revolutions = real_spec("revolutions", "1", "wheel revolutions n simulated (A_n of 5-37)", 40.0, 0.0, true);
  revolutions.max = 1e5;
  ParamSpec one_sided = param_spec("one_sided_contact", ValueKind::boolean, "1",
                                   "the wheel may leave the work (false: bilateral, linear contact, "
                                   "the setting 5-37 describes)");
  one_sided.default_value = false;
  ParamSpec tolerance = real_spec("relative_tolerance", "1", "integrator relative tolerance", 1e-4, 0.0, true);
  tolerance.max = 1e-3;
  ParamSpec exponent = real_spec("thickness_exponent", "1",
                                 "eps of k = k0 (1 - eps/2 da/a) for kc and kg (5-29); eps = 2 (1 - beta) "
                                 "with F ~ a^beta (5-43); used by feed modulation", 0.6, 0.0, false);
  exponent.max = 4.0;
  ParamSpec seed = param_spec("seed", ValueKind::integer, "1", "seed of the initial waviness");
  seed.default_value = 1;
  seed.min = 0;
  info.params = {
      revolutions,
      real_spec("sample_rate_hz", "Hz", "output sample rate of the simulations", 10000.0, 0.0, true),
      real_spec("initial_displacement_m", "m", "initial structural displacement (the disturbance)", 1e-6, 0.0, false),
      real_spec("initial_waviness_m", "m",
                "random initial waviness of wheel and work surfaces (+/-, uniform, seeded): starts the "
                "regeneration of a chain from its first revolution", 0.0, 0.0, false),
      seed,
      real_spec("infeed_rate_m_per_s", "m/s", "mean plunge infeed rate (> 0 for feed modulation)", 0.0, 0.0, false),
      one_sided,
      tolerance,
      real_spec("divergence_limit_m", "m", "|displacement| beyond this stops a run as diverged", 1.0, 0.0, true),
      exponent,
  };
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"revolutions", 10.0}, {"sample_rate_hz", 5000.0}};
  return info;
}

void SuppressionMap::validate(Json& document, const SourceMap& sources) const {
  Json model = validate_component(document, "model", model_registry(), sources);
  Json suppression = validate_component(document, "suppression", suppression_registry(), sources);
  Json table = document.contains("suppression_map") ? document["suppression_map"] : Json::object();
  if (!table.is_object())
    throw InputError(fmt::format("{}: suppression_map = {}: expected a table [suppression_map]",
                                 sources.locate("suppression_map").str(), table.dump()));
  table = validate_params(table, info().params, "suppression_map", sources);

  std::unique_ptr<Suppression> plugin;
  try {
    plugin = build_suppression(suppression);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: [suppression]: {}", sources.locate("suppression").str(), e.what()));
  }
  const std::string type = model["type"].get<std::string>();
  auto built = build_model(model);
  if (!built->time_domain() || !built->characteristic())
    throw InputError(fmt::format("{}: model.type = \"{}\": the suppression_map study needs a model with "
                                 "a time-domain form and a characteristic function",
                                 sources.locate("model.type").str(), type));
  const SuppressionTarget target = plugin->target();
  std::vector<std::string> needed{"wheel_speed_rpm"};
  if (target == SuppressionTarget::work_speed) needed.push_back("work_speed_rpm");
  if (target == SuppressionTarget::feed)
    for (const char* k : {"contact_stiffness_n_per_m", "wheel_wear_stiffness_n_per_m", "work_removal_stiffness_n_per_m"})
      needed.push_back(k);
  for (const std::string& key : needed)
    if (!model[key].is_number())
      throw InputError(fmt::format("{}: model.type = \"{}\": suppression.target = \"{}\" needs the model "
                                   "parameter '{}' (the conditions it modulates)",
                                   sources.locate("suppression.target").str(), type, to_string(target), key));
  const double rate = table["infeed_rate_m_per_s"].get<double>();
  if (target == SuppressionTarget::feed && !(rate > 0.0))
    throw InputError(fmt::format("{}: suppression_map.infeed_rate_m_per_s = {}: feed modulation needs a "
                                 "mean infeed rate > 0 (suppression.target = \"feed\")",
                                 sources.locate("suppression_map.infeed_rate_m_per_s").str(), rate));
  if (target == SuppressionTarget::feed && table["thickness_exponent"].get<double>() > 0.0 &&
      type != PlungeRegenerative::info().name)
    throw InputError(fmt::format("{}: suppression_map.thickness_exponent = {}: the feed-dependent stiffness "
                                 "of 5-29 rescales the G1 force law and needs model.type = \"{}\" (got \"{}\"); "
                                 "set thickness_exponent = 0 for other models",
                                 sources.locate("suppression_map.thickness_exponent").str(),
                                 table["thickness_exponent"].dump(), PlungeRegenerative::info().name, type));
  if (target == SuppressionTarget::feed && table["thickness_exponent"].get<double>() > 0.0) {
    const double a = suppression.value("amplitude_ratio", 0.0), eps = table["thickness_exponent"].get<double>();
    if (!(1.0 - 0.5 * eps * a > 0.0))
      throw InputError(fmt::format("{}: suppression.amplitude_ratio = {}: with thickness_exponent = {} the "
                                   "stiffness factor 1 - eps/2 da/a reaches {} (must stay > 0)",
                                   sources.locate("suppression.amplitude_ratio").str(), a, eps, 1.0 - 0.5 * eps * a));
  }
  const double samples = table["revolutions"].get<double>() * 60.0 / model["wheel_speed_rpm"].get<double>() *
                         table["sample_rate_hz"].get<double>();
  if (samples > max_output_samples)
    throw InputError(fmt::format("{}: suppression_map.revolutions = {}: {:.4g} output samples exceed the "
                                 "limit of {:.4g} (fewer revolutions or a lower sample_rate_hz)",
                                 sources.locate("suppression_map.revolutions").str(),
                                 table["revolutions"].dump(), samples, max_output_samples));
  document["model"] = std::move(model);
  document["suppression"] = std::move(suppression);
  document["suppression_map"] = std::move(table);
}

std::vector<std::string> SuppressionMap::output_columns(const Json&) const {
  return {col_ratio, col_s2, col_s2_locked, col_drift, col_s3, col_s3_fraction, col_s1, col_outcome};
}

std::vector<Json> SuppressionMap::run_point(const Json& document, const PointContext& /*context*/) const {
  auto plugin = build_suppression(document.at("suppression"));
  const SuppressionTarget target = plugin->target();
  auto table = growth_table(document, target);
  const Reference ref = reference(document, *table);
  const double duration = run_duration(document);
  const double revolution_s = 60.0 / ref.wheel_rpm;

  // Simulated: A_n modulated over A_n constant.
  auto law = plugin->law(duration);
  auto model = time_domain(document, target);
  SimulationSettings settings = base_settings(document);
  try {
    apply_modulation(target, law, *model, settings);
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
  const SimulationResult r = run_simulation(*model, settings);
  Json ratio;
  if (!r.diverged && !ref.diverged && ref.amplitude_m > 0.0)
    ratio = std::log10(final_amplitude(r, revolution_s) / ref.amplitude_m);

  // S2: growth-rate averaging over the wheel revolutions (the wheel's own law when it is the
  // target, else constant), modulated minus constant (5-39 over 5-38).
  const auto constant = std::make_shared<const ConstantLevel>();
  const ModulationLaw& wheel_law = target == SuppressionTarget::wheel_speed ? *law : *constant;
  const std::vector<double> boundaries = sm::revolution_boundaries(wheel_law, ref.wheel_rpm, duration);
  auto sigma = [&](double level) { return table->root(level).first; };
  const double log_modulated = sm::growth_averaging_log_amplification(*law, boundaries, sigma);
  const double log_constant = sm::growth_averaging_log_amplification(*constant, boundaries, sigma);
  const double s2 = (log_modulated - log_constant) / std::numbers::ln10;

  // S2 with the nominal chatter root continued through the revolutions (wave count kept) instead
  // of the rightmost root.
  Json s2_locked;
  {
    auto at_level = [&](double level) { return build_model(table->conditions(level))->characteristic(); };
    const Complex start{ref.growth_rate_per_s, kTwoPi * ref.chatter_frequency_hz};
    const bool wheel = target == SuppressionTarget::wheel_speed;
    try {
      s2_locked = (sm::continued_root_log_amplification(at_level, *law, boundaries, start, wheel) -
                   sm::continued_root_log_amplification(at_level, *constant, boundaries, start, wheel)) /
                  std::numbers::ln10;
    } catch (const std::runtime_error&) {
      // left empty: the continued root was lost (reported as a blank cell)
    }
  }

  // The approximation's phase drift per revolution: the speed change from one revolution to the
  // next (speed targets) or, for feed, the chatter-frequency change of the frozen roots.
  double drift = 0.0;
  double previous_level = 1.0;
  double previous_frequency = ref.chatter_frequency_hz;
  for (std::size_t i = 0; i + 1 < boundaries.size(); ++i) {
    const double d = boundaries[i + 1] - boundaries[i];
    const double level = (law->level_integral(boundaries[i + 1]) - law->level_integral(boundaries[i])) / d;
    if (target == SuppressionTarget::feed) {
      const double f = table->root(level).second;
      drift = std::max(drift, kTwoPi * std::abs(f - previous_frequency) * revolution_s);
      previous_frequency = f;
    } else {
      drift = std::max(drift, sm::quasi_static_phase_drift_rad(
                                  ref.chatter_frequency_hz, ref.wheel_rpm,
                                  std::abs(level - previous_level) / std::min(level, previous_level)));
    }
    previous_level = level;
  }

  // S3: the phase lag of the constant-speed chatter frequency on the modulated rotor (the wheel
  // for wheel speed, the work otherwise), against the same at constant speed.
  const bool on_wheel = target == SuppressionTarget::wheel_speed;
  const double nominal = on_wheel ? ref.wheel_rpm : ref.work_rpm;
  const bool speed_target = target != SuppressionTarget::feed;
  auto speed = [&](double t) { return speed_target ? nominal * law->level(t) : nominal; };
  // Averaged over the whole modulation periods inside the run (one period's balance for a periodic
  // law), or over the run when a period is longer than it.
  const double period = plugin->modulation_period_s();
  const double window = period > 0.0 && period <= duration ? std::floor(duration / period) * period : duration;
  const sm::EnergyBalance modulated = sm::energy_balance(ref.chatter_frequency_hz, speed, 0.0, window);
  const double constant_energy = std::sin(sm::phase_lag_rad(ref.chatter_frequency_hz, nominal));

  // S1: range of the corrected 5-29 frequency over the run.
  Json s1;
  if (auto fm = feed_model(*build_model(document.at("model")), ref.chatter_frequency_hz,
                           document.at("suppression_map").at("thickness_exponent").get<double>())) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    constexpr int samples = 2000;
    for (int i = 0; i < samples; ++i) {
      const double t = (i + 0.5) * duration / samples;
      const double f = sm::feed_chatter_frequency_hz(*fm, thickness_change(target, law->level(t)));
      lo = std::min(lo, f);
      hi = std::max(hi, f);
    }
    s1 = hi - lo;
  }
  return {ratio, s2, s2_locked, drift, modulated.mean_normalised_energy - constant_energy, modulated.exciting_fraction,
          s1, r.diverged ? std::string("diverged") : std::string("completed")};
}

void SuppressionMap::write_artifacts(const Study& study, const ResultTable& results, const fs::path& out_dir) const {
  // The constant-speed reference of the study's own model and settings (grid values that change
  // the model give one reference per point; this file records the nominal one).
  {
    const Json& doc = study.document;
    const SuppressionTarget target = parse_suppression_target(doc.at("suppression").at("target").get<std::string>());
    auto table = growth_table(doc, target);
    const Reference ref = reference(doc, *table);
    write_json_file(out_dir / "reference.json",
                    Json{{"description", "constant-speed reference of every grid point (MODELS.md S2: A_n "
                                         "of 5-38), and the rightmost root at the nominal conditions"},
                         {"revolutions", doc.at("suppression_map").at("revolutions")},
                         {"duration_s", run_duration(doc)},
                         {"amplitude_after_n_revolutions_m", ref.amplitude_m},
                         {"diverged", ref.diverged},
                         {"growth_rate_per_s", ref.growth_rate_per_s},
                         {"growth_rate_per_wheel_rev", ref.growth_rate_per_s * 60.0 / ref.wheel_rpm / kTwoPi},
                         {"chatter_frequency_hz", ref.chatter_frequency_hz},
                         {"wheel_speed_rpm", ref.wheel_rpm},
                         {"work_speed_rpm", ref.work_rpm},
                         {"s3_sin_phi_wheel", std::sin(sm::phase_lag_rad(ref.chatter_frequency_hz, ref.wheel_rpm))},
                         {"s3_sin_phi_work", std::sin(sm::phase_lag_rad(ref.chatter_frequency_hz, ref.work_rpm))}});
  }
  // Maps need two numeric varying axes; a varying string axis (e.g. suppression.shape) gives one
  // set of maps per value.
  std::vector<std::size_t> numeric, labels;
  for (std::size_t a = 0; a < study.grid.size(); ++a) {
    if (study.grid[a].values.size() < 2) continue;
    const bool is_number = std::all_of(study.grid[a].values.begin(), study.grid[a].values.end(),
                                       [](const Json& v) { return v.is_number(); });
    (is_number ? numeric : labels).push_back(a);
  }
  if (numeric.size() != 2 || labels.size() > 1) return;  // documented: results.csv has every number
  const GridAxis& y_axis = study.grid[numeric[0]];
  const GridAxis& x_axis = study.grid[numeric[1]];
  std::vector<Json> groups{Json()};
  if (!labels.empty()) groups = study.grid[labels[0]].values;
  const std::string title = study_title(study);
  const std::string target = study.document.at("suppression").at("target").get<std::string>();
  std::string errors;
  struct MapSpec {
    const char* column;
    const char* what;
    const char* z_label;
  };
  const MapSpec maps[] = {
      {col_ratio, "simulated log10(A_n mod / A_n const)", "log10 amplitude ratio"},
      {col_s2, "S2 growth-rate averaging (5-37)", "predicted log10 amplitude ratio"},
      {col_s2_locked, "S2 continued root (5-37)", "predicted log10 amplitude ratio"},
      {col_s3, "S3 energy per cycle (5-45)", "change of mean sin(phi) [pi C' X^2]"},
  };
  for (const Json& group : groups) {
    for (const MapSpec& spec : maps) {
      plot::Heatmap h;
      const std::string group_name = group.is_string() ? group.get<std::string>() : group.dump();
      // Short enough for the figure width: which modulation, then what is drawn.
      h.title = group.is_null() ? fmt::format("{}: {}", title, spec.what)
                                : fmt::format("{} {}: {}", group_name, target, spec.what);
      h.x_label = axis_label(x_axis.key);
      h.y_label = axis_label(y_axis.key);
      h.z_label = spec.z_label;
      for (const Json& v : x_axis.values) h.x.push_back(v.get<double>());
      for (const Json& v : y_axis.values) h.y.push_back(v.get<double>());
      h.log_x = log_axis(study, x_axis);
      h.log_y = log_axis(study, y_axis);
      h.z.assign(h.x.size() * h.y.size(), std::numeric_limits<double>::quiet_NaN());
      const std::size_t c = column_index(results, spec.column);
      if (std::none_of(results.rows.begin(), results.rows.end(), [&](const auto& row) { return row[c].is_number(); }))
        continue;  // a prediction that does not apply to this model (e.g. the locked lobe)
      for (std::size_t r = 0; r < results.rows.size(); ++r) {
        const auto& row = results.rows[r];
        if (!labels.empty() && row[labels[0]] != group) continue;
        const auto ix = std::find(x_axis.values.begin(), x_axis.values.end(), row[numeric[1]]) - x_axis.values.begin();
        const auto iy = std::find(y_axis.values.begin(), y_axis.values.end(), row[numeric[0]]) - y_axis.values.begin();
        if (row[c].is_number())
          h.z[static_cast<std::size_t>(iy) * h.x.size() + static_cast<std::size_t>(ix)] = row[c].get<double>();
      }
      h.contour_level = 0.0;
      h.contour_label = "no effect";
      h.diverging = true;
      h.low_label = "modulation helps";
      h.high_label = "modulation hurts";
      const std::string stem = fmt::format("{}_{}{}", spec.column, target, group.is_null() ? "" : "_" + group_name);
      try {
        plot::render(h, out_dir, stem);
      } catch (const std::exception& e) {
        errors += fmt::format("{}{}: {}", errors.empty() ? "" : "; ", stem, e.what());
      }
    }
  }
  if (!errors.empty()) throw plot::PlotError(errors);
}

bool SuppressionMap::requires_serial(const Json& document) const {
  return model_is_serial(document.at("model"));
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::SuppressionMap);
