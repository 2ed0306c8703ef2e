#include "study_kinds/suppression_map/suppression_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <tuple>

#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_info.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/suppression.hpp"
#include "study_kinds/suppression_map/suppression_measures.hpp"

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

// ------------------------------------------------------------------ settings

struct Settings {
  double revolutions = 40.0;
  double sample_rate_hz = 10000.0;
  double initial_displacement_m = 1e-6;
  double initial_waviness_m = 0.0;
  std::uint64_t seed = 1;
  double infeed_rate_m_per_s = 0.0;
  bool one_sided_contact = false;
  double relative_tolerance = 1e-4;
  double divergence_limit_m = 1.0;
  double thickness_exponent = 0.6;
};

const ParamTable<Settings>& settings_table() {
  static const ParamTable<Settings> table = [] {
    ParamTable<Settings> t;
    t.add(&Settings::revolutions, "revolutions", "1", "wheel revolutions n simulated (A_n of 5-37)")
        .positive()
        .at_most(1e5);
    t.add(&Settings::sample_rate_hz, "sample_rate_hz", "Hz", "output sample rate of the simulations").positive();
    t.add(&Settings::initial_displacement_m, "initial_displacement_m", "m",
          "initial structural displacement (the disturbance)")
        .non_negative();
    t.add(&Settings::initial_waviness_m, "initial_waviness_m", "m",
          "random initial waviness of wheel and work surfaces (+/-, uniform, seeded): starts the "
          "regeneration of a chain from its first revolution")
        .non_negative();
    t.add(&Settings::seed, "seed", "1", "seed of the initial waviness").non_negative();
    t.add(&Settings::infeed_rate_m_per_s, "infeed_rate_m_per_s", "m/s",
          "mean plunge infeed rate (> 0 for feed modulation)")
        .non_negative();
    t.add(&Settings::one_sided_contact, "one_sided_contact", "1",
          "the wheel may leave the work (false: bilateral, linear contact, the setting 5-37 describes)");
    t.add(&Settings::relative_tolerance, "relative_tolerance", "1",
          "relative tolerance of the adaptive ARKODE route only (the simulations run the fixed-step "
          "engine, which has none)")
        .positive()
        .at_most(1e-3);
    t.add(&Settings::divergence_limit_m, "divergence_limit_m", "m",
          "|displacement| beyond this stops a run as diverged")
        .positive();
    t.add(&Settings::thickness_exponent, "thickness_exponent", "1",
          "eps of k = k0 (1 - eps/2 da/a) for kc and kg (5-29); eps = 2 (1 - beta) with F ~ a^beta "
          "(5-43); used by feed modulation")
        .non_negative()
        .at_most(4.0);
    return t;
  }();
  return table;
}

Settings settings_of(const Json& document) {
  return kit::read_settings(document, "suppression_map", settings_table());
}

std::unique_ptr<Suppression> build_suppression(const Json& table) {
  Json params = table;
  params.erase("type");
  return suppression_registry().at(table.at("type").get<std::string>()).create(ParamValues(std::move(params)));
}

double wheel_rpm(const Model& model) { return model.time_domain()->nominal_speed_rpm(Rotor::wheel); }

double run_duration(const Settings& s, double wheel_speed_rpm) { return s.revolutions * 60.0 / wheel_speed_rpm; }

// ------------------------------------------------------------------ feed-dependent stiffness

// S1 (5-29): contact and wheel wear stiffness follow the relative thickness change,
// k = k0 (1 - eps/2 da/a), with da/a = rate(t)/mean rate - 1 for a modulated feed (the depth per
// revolution is proportional to the infeed rate). A model of the G1 family (one that reports its
// stiffness chain) has the force law F = interference/(1/kc + 1/kg + 1/kw) with constant
// stiffnesses, so this wrapper rescales its force and removal exactly: with kc, kg scaled by s,
// F becomes F * g, g = C0/(C_scaled/s + 1/kw), C0 the original series compliance; wheel removal
// F/kg scales by g/s, work removal F/kw by g. A chain switched off has an infinite stiffness.
class FeedDependentStiffness final : public TimeDomainModel {
 public:
  FeedDependentStiffness(std::unique_ptr<TimeDomainModel> inner, const StiffnessChain& k, double mean_rate,
                         double exponent)
      : inner_(std::move(inner)),
        scaled_compliance_(1.0 / k.contact_stiffness_n_per_m + 1.0 / k.wheel_wear_stiffness_n_per_m),
        work_compliance_(1.0 / k.work_removal_stiffness_n_per_m),
        mean_rate_(mean_rate),
        exponent_(exponent) {}
  std::size_t state_size() const override { return inner_->state_size(); }
  void initial_state(const Disturbance& d, std::span<double> x) const override { inner_->initial_state(d, x); }
  void state_scales(double d, std::span<double> s) const override { inner_->state_scales(d, s); }
  double highest_frequency_hz() const override { return inner_->highest_frequency_hz(); }
  bool regenerates(Rotor r) const override { return inner_->regenerates(r); }
  double nominal_speed_rpm(Rotor r) const override { return inner_->nominal_speed_rpm(r); }
  void contact(const ContactInput& in, ContactOutput& out) const override {
    inner_->contact(in, out);
    const double s = 1.0 - 0.5 * exponent_ * (in.infeed_rate_m_per_s / mean_rate_ - 1.0);
    const double g = (scaled_compliance_ + work_compliance_) / (scaled_compliance_ / s + work_compliance_);
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
  double scaled_compliance_, work_compliance_;
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
// the level grid; one per (model, target, exponent). The frozen conditions come from the model's
// process-conditions capability, so any model that declares it can be modulated.
class GrowthTable {
 public:
  GrowthTable(Json model_table, SuppressionTarget target, double exponent)
      : model_table_(std::move(model_table)), model_(kit::build_model(model_table_)), target_(target),
        exponent_(exponent) {}

  std::pair<double, double> root(double level) {  // (growth rate [1/s], frequency [Hz])
    const double x = (level - 1.0) / level_step;
    const long lo = static_cast<long>(std::floor(x));
    const double u = x - static_cast<double>(lo);
    const auto a = node(lo);
    if (u < 1e-12) return a;
    const auto b = node(lo + 1);
    return {a.first + u * (b.first - a.first), a.second + u * (b.second - a.second)};
  }

  // The model at modulation level q/q_mean: the frozen conditions of that level (a speed scaled,
  // or the depth of cut per revolution scaled by the feed). The stiffnesses do not follow the
  // speeds here (the study compares modulation at one set of process stiffnesses).
  std::unique_ptr<Model> at_level(double level) const {
    const ProcessConditionsModel& process = *model_->process_conditions();
    const ProcessConditions nominal = process.nominal_conditions();
    ProcessConditions at = nominal;
    switch (target_) {
      case SuppressionTarget::wheel_speed: at.wheel_speed_rpm = level * nominal.wheel_speed_rpm; break;
      case SuppressionTarget::work_speed: at.work_speed_rpm = level * nominal.work_speed_rpm; break;
      case SuppressionTarget::feed: at.depth_of_cut_ratio = level; break;
    }
    ProcessScaling scaling;
    scaling.speed_dependent_stiffness = false;
    scaling.thickness_exponent = target_ == SuppressionTarget::feed ? exponent_ : 0.0;
    Json table = {{"type", model_table_.at("type")}};
    table.update(process.parameters_at(nominal, at, scaling));
    return kit::build_model(table);
  }

 private:
  std::pair<double, double> node(long index) {
    {
      std::lock_guard lock(mutex_);
      auto it = nodes_.find(index);
      if (it != nodes_.end()) return it->second;
    }
    const double level = 1.0 + static_cast<double>(index) * level_step;
    auto fn = at_level(level)->characteristic();
    RootSearchOptions options;
    options.max_frequency_hz = kit::default_band_multiple * fn->natural_frequency_scale_hz();
    const RightmostRoot r = find_rightmost_root(*fn, options);
    const std::pair<double, double> value{r.root.real(), std::abs(r.root.imag()) / kTwoPi};
    std::lock_guard lock(mutex_);
    nodes_.emplace(index, value);
    return value;
  }

  Json model_table_;
  std::unique_ptr<Model> model_;
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

// ------------------------------------------------------------------ simulation

SimulationSettings base_settings(const Settings& t, double duration_s) {
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = t.sample_rate_hz;
  s.disturbance.displacement_m = t.initial_displacement_m;
  s.initial_waviness_m = t.initial_waviness_m;
  s.seed = t.seed;
  s.infeed_rate_m_per_s = t.infeed_rate_m_per_s;
  s.one_sided_contact = t.one_sided_contact;
  s.relative_tolerance = t.relative_tolerance;
  s.divergence_limit_m = t.divergence_limit_m;
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

// Without feed modulation the stiffness scale is 1: the plain model (the constant run's, so a zero
// amplitude reproduces it exactly with the same integration).
std::unique_ptr<TimeDomainModel> time_domain(const Model& model, const Settings& s, SuppressionTarget target,
                                             bool modulated) {
  auto td = model.time_domain();
  if (target != SuppressionTarget::feed || s.thickness_exponent == 0.0 || !modulated) return td;
  return std::make_unique<FeedDependentStiffness>(std::move(td), *model.stiffness_chain(),
                                                  s.infeed_rate_m_per_s, s.thickness_exponent);
}

SimulationResult run_simulation(const TimeDomainModel& model, const SimulationSettings& settings) {
  try {
    return simulate(model, settings);
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
}

std::shared_ptr<GrowthTable> growth_table(const Json& document, SuppressionTarget target) {
  const double exponent = settings_of(document).thickness_exponent;
  const std::string key = fmt::format("{}|{}|{}", document.at("model").dump(), to_string(target), exponent);
  return table_cache().get(key, [&] {
    return std::make_shared<GrowthTable>(document.at("model"), target, exponent);
  });
}

Reference reference(const Json& document, GrowthTable& table) {
  const std::string key = document.at("model").dump() + "|" + document.at("suppression_map").dump();
  return reference_cache().get(key, [&] {
    Reference ref;
    auto model = kit::build_model(document.at("model"));
    auto td = model->time_domain();
    ref.wheel_rpm = td->nominal_speed_rpm(Rotor::wheel);
    ref.work_rpm = td->nominal_speed_rpm(Rotor::work);
    const Settings s = settings_of(document);
    const SimulationResult r = run_simulation(*td, base_settings(s, run_duration(s, ref.wheel_rpm)));
    ref.diverged = r.diverged;
    ref.amplitude_m = final_amplitude(r, 60.0 / ref.wheel_rpm);
    std::tie(ref.growth_rate_per_s, ref.chatter_frequency_hz) = table.root(1.0);
    return ref;
  });
}

// The feed-model parameters of 5.3.1 from the model's G1 stiffness chain: the structural mode
// nearest the chatter frequency as the single sensitive mode (m = k/wn^2).
std::optional<sm::FeedChatterModel> feed_model(const Model& model, double chatter_hz, double exponent) {
  const std::optional<StiffnessChain> chain = model.stiffness_chain();
  if (!chain || chain->modes.empty()) return std::nullopt;
  const ModeView* nearest = &chain->modes.front();
  for (const ModeView& m : chain->modes)
    if (std::abs(m.frequency_hz - chatter_hz) < std::abs(nearest->frequency_hz - chatter_hz)) nearest = &m;
  const double wn = kTwoPi * nearest->frequency_hz;
  return sm::FeedChatterModel{nearest->stiffness_n_per_m / (wn * wn), nearest->stiffness_n_per_m,
                              chain->contact_stiffness_n_per_m, chain->wheel_wear_stiffness_n_per_m,
                              chain->work_removal_stiffness_n_per_m, exponent};
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

// ------------------------------------------------------------------ one point

// Everything the measures of one grid point share.
struct PointSetup {
  Settings settings;
  std::unique_ptr<Suppression> plugin;
  SuppressionTarget target = SuppressionTarget::wheel_speed;
  std::shared_ptr<GrowthTable> table;
  Reference ref;
  double duration_s = 0.0;
  std::shared_ptr<const ModulationLaw> law;
  std::shared_ptr<const ModulationLaw> constant = std::make_shared<const ConstantLevel>();
  std::vector<double> boundaries;  // wheel revolutions
  bool modulated = false;          // a non-zero modulation amplitude
};

PointSetup setup(const Json& document) {
  PointSetup p;
  p.settings = settings_of(document);
  p.plugin = build_suppression(document.at("suppression"));
  p.target = p.plugin->target();
  p.modulated = document.at("suppression").value("amplitude_ratio", 0.0) != 0.0;
  p.table = growth_table(document, p.target);
  p.ref = reference(document, *p.table);
  p.duration_s = run_duration(p.settings, p.ref.wheel_rpm);
  p.law = p.plugin->law(p.duration_s);
  // The wheel's own law when it is the target, else constant: S2 sums over wheel revolutions.
  const ModulationLaw& wheel_law = p.target == SuppressionTarget::wheel_speed ? *p.law : *p.constant;
  p.boundaries = sm::revolution_boundaries(wheel_law, p.ref.wheel_rpm, p.duration_s);
  return p;
}

// Simulated: log10(A_n modulated / A_n constant); null when either run diverged.
std::pair<Json, bool> simulated_log_ratio(const Model& model, const PointSetup& p) {
  auto td = time_domain(model, p.settings, p.target, p.modulated);
  SimulationSettings settings = base_settings(p.settings, p.duration_s);
  try {
    apply_modulation(p.target, p.law, *td, settings);
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
  const SimulationResult r = run_simulation(*td, settings);
  Json ratio;
  if (!r.diverged && !p.ref.diverged && p.ref.amplitude_m > 0.0)
    ratio = std::log10(final_amplitude(r, 60.0 / p.ref.wheel_rpm) / p.ref.amplitude_m);
  return {ratio, r.diverged};
}

// S2: growth-rate averaging over the wheel revolutions, modulated minus constant (5-39 over 5-38).
double s2_averaging(const PointSetup& p) {
  auto sigma = [&](double level) { return p.table->root(level).first; };
  const double modulated = sm::growth_averaging_log_amplification(*p.law, p.boundaries, sigma);
  const double constant = sm::growth_averaging_log_amplification(*p.constant, p.boundaries, sigma);
  return (modulated - constant) / std::numbers::ln10;
}

// S2 with the nominal chatter root continued through the revolutions (wave count kept) instead
// of the rightmost root; null when the continued root was lost.
Json s2_locked(const PointSetup& p) {
  auto at_level = [&](double level) { return p.table->at_level(level)->characteristic(); };
  const Complex start{p.ref.growth_rate_per_s, kTwoPi * p.ref.chatter_frequency_hz};
  const bool wheel = p.target == SuppressionTarget::wheel_speed;
  try {
    return (sm::continued_root_log_amplification(at_level, *p.law, p.boundaries, start, wheel) -
            sm::continued_root_log_amplification(at_level, *p.constant, p.boundaries, start, wheel)) /
           std::numbers::ln10;
  } catch (const std::runtime_error&) {
    return Json();
  }
}

// The approximation's phase drift per revolution: the speed change from one revolution to the
// next (speed targets) or, for feed, the chatter-frequency change of the frozen roots.
double phase_drift(const PointSetup& p) {
  const double revolution_s = 60.0 / p.ref.wheel_rpm;
  double drift = 0.0, previous_level = 1.0, previous_frequency = p.ref.chatter_frequency_hz;
  for (std::size_t i = 0; i + 1 < p.boundaries.size(); ++i) {
    const double d = p.boundaries[i + 1] - p.boundaries[i];
    const double level = (p.law->level_integral(p.boundaries[i + 1]) - p.law->level_integral(p.boundaries[i])) / d;
    if (p.target == SuppressionTarget::feed) {
      const double f = p.table->root(level).second;
      drift = std::max(drift, kTwoPi * std::abs(f - previous_frequency) * revolution_s);
      previous_frequency = f;
    } else {
      drift = std::max(drift, sm::quasi_static_phase_drift_rad(
                                  p.ref.chatter_frequency_hz, p.ref.wheel_rpm,
                                  std::abs(level - previous_level) / std::min(level, previous_level)));
    }
    previous_level = level;
  }
  return drift;
}

// S3: the phase lag of the constant-speed chatter frequency on the modulated rotor (the wheel for
// wheel speed, the work otherwise), against the same at constant speed; averaged over the whole
// modulation periods inside the run (one period's balance for a periodic law), or over the run
// when a period is longer than it. Returns (change of mean sin phi, exciting fraction).
std::pair<double, double> s3_energy(const PointSetup& p) {
  const double nominal = p.target == SuppressionTarget::wheel_speed ? p.ref.wheel_rpm : p.ref.work_rpm;
  const bool speed_target = p.target != SuppressionTarget::feed;
  auto speed = [&](double t) { return speed_target ? nominal * p.law->level(t) : nominal; };
  const double period = p.plugin->modulation_period_s();
  const double window = period > 0.0 && period <= p.duration_s ? std::floor(p.duration_s / period) * period
                                                                : p.duration_s;
  const sm::EnergyBalance modulated = sm::energy_balance(p.ref.chatter_frequency_hz, speed, 0.0, window);
  const double constant_energy = std::sin(sm::phase_lag_rad(p.ref.chatter_frequency_hz, nominal));
  return {modulated.mean_normalised_energy - constant_energy, modulated.exciting_fraction};
}

// S1: range of the corrected 5-29 frequency over the run; null for a model without a G1
// stiffness chain.
Json s1_swing(const Model& model, const PointSetup& p) {
  auto fm = feed_model(model, p.ref.chatter_frequency_hz, p.settings.thickness_exponent);
  if (!fm) return Json();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  constexpr int samples = 2000;
  for (int i = 0; i < samples; ++i) {
    const double t = (i + 0.5) * p.duration_s / samples;
    const double f = sm::feed_chatter_frequency_hz(*fm, thickness_change(p.target, p.law->level(t)));
    lo = std::min(lo, f);
    hi = std::max(hi, f);
  }
  return hi - lo;
}

// ------------------------------------------------------------------ validation

[[noreturn]] void refuse(const SourceMap& sources, const std::string& path, const std::string& what) {
  throw InputError(fmt::format("{}: {}", sources.locate(path).str(), what));
}

// The joint checks of [model], [suppression] and [suppression_map].
void check_combination(const Model& model, const Json& model_table, const Suppression& plugin,
                       const Json& suppression_table, const Settings& s, const SourceMap& sources) {
  const std::string type = model_table.at("type").get<std::string>();
  const SuppressionTarget target = plugin.target();
  if (!model.process_conditions())
    refuse(sources, "model.type",
           fmt::format("model.type = \"{}\": this model does not declare process conditions "
                       "(chatterlab/process_conditions.hpp), which the suppression_map study needs to "
                       "freeze the modulated speeds or feed",
                       type));
  if (target != SuppressionTarget::feed) {
    // A model that integrates a rotor's speed as a state (G5's torsion) has no speed law to modulate.
    const Rotor rotor = target == SuppressionTarget::wheel_speed ? Rotor::wheel : Rotor::work;
    if (auto td = model.time_domain(); td && td->angle_state(rotor))
      refuse(sources, "suppression.target",
             fmt::format("suppression.target = \"{}\": model.type = \"{}\" integrates the {} speed as a "
                         "state (its torsional motion), so a speed law cannot modulate it; modulate the "
                         "feed (target = \"feed\") or use a model whose speeds are laws",
                         to_string(target), type, to_string(rotor)));
  }
  if (target == SuppressionTarget::feed && !(s.infeed_rate_m_per_s > 0.0))
    refuse(sources, "suppression_map.infeed_rate_m_per_s",
           fmt::format("suppression_map.infeed_rate_m_per_s = {}: feed modulation needs a mean infeed "
                       "rate > 0 (suppression.target = \"feed\")",
                       s.infeed_rate_m_per_s));
  if (target != SuppressionTarget::feed || s.thickness_exponent == 0.0) return;
  if (!model.stiffness_chain())
    refuse(sources, "suppression_map.thickness_exponent",
           fmt::format("suppression_map.thickness_exponent = {}: the feed-dependent stiffness of 5-29 "
                       "rescales the G1 force law and needs a model with a G1 stiffness chain "
                       "(model.type = \"{}\" has none); set thickness_exponent = 0 for this model",
                       s.thickness_exponent, type));
  const double a = suppression_table.value("amplitude_ratio", 0.0), eps = s.thickness_exponent;
  if (!(1.0 - 0.5 * eps * a > 0.0))
    refuse(sources, "suppression.amplitude_ratio",
           fmt::format("suppression.amplitude_ratio = {}: with thickness_exponent = {} the stiffness "
                       "factor 1 - eps/2 da/a reaches {} (must stay > 0)",
                       a, eps, 1.0 - 0.5 * eps * a));
}

// ------------------------------------------------------------------ plots

struct MapSpec {
  const char* column;
  const char* what;
  const char* z_label;
};
constexpr MapSpec maps[] = {
    {col_ratio, "simulated log10(A_n mod / A_n const)", "log10 amplitude ratio"},
    {col_s2, "S2 growth-rate averaging (5-37)", "predicted log10 amplitude ratio"},
    {col_s2_locked, "S2 continued root (5-37)", "predicted log10 amplitude ratio"},
    {col_s3, "S3 energy per cycle (5-45)", "change of mean sin(phi) [pi C' X^2]"},
};

// One map of a column over the two numeric axes, for the rows of one value of the string axis
// (every row without one). Diverging and symmetric about "no effect" (0): a factor of 2 up or
// down looks alike, and a 0.02 % change stays pale.
plot::Heatmap ratio_map(const std::vector<kit::PlotAxis>& axes, const ResultTable& results,
                        const MapSpec& spec, std::optional<std::size_t> group_column, const Json& group) {
  plot::Heatmap h;
  const kit::PlotAxis& x = axes[1];
  const kit::PlotAxis& y = axes[0];
  h.x_label = x.label;
  h.y_label = y.label;
  h.z_label = spec.z_label;
  h.x = x.values;
  h.y = y.values;
  h.log_x = x.log;
  h.log_y = y.log;
  h.z.assign(h.x.size() * h.y.size(), std::numeric_limits<double>::quiet_NaN());
  const std::size_t c = kit::column_index(results, spec.column);
  for (const auto& row : results.rows) {
    if (group_column && row[*group_column] != group) continue;
    const auto ix = std::find(x.values.begin(), x.values.end(), row[x.grid_index].get<double>()) - x.values.begin();
    const auto iy = std::find(y.values.begin(), y.values.end(), row[y.grid_index].get<double>()) - y.values.begin();
    if (row[c].is_number())
      h.z[static_cast<std::size_t>(iy) * h.x.size() + static_cast<std::size_t>(ix)] = row[c].get<double>();
  }
  h.contour_level = 0.0;
  h.contour_label = "no effect";
  h.diverging = true;
  h.symmetric = true;
  h.low_label = "modulation helps";
  h.high_label = "modulation hurts";
  return h;
}

void write_reference(const Study& study, const fs::path& out_dir) {
  const Json& doc = study.document;
  const SuppressionTarget target = parse_suppression_target(doc.at("suppression").at("target").get<std::string>());
  auto table = growth_table(doc, target);
  const Reference ref = reference(doc, *table);
  write_json_file(out_dir / "reference.json",
                  Json{{"description", "constant-speed reference of every grid point (MODELS.md S2: A_n "
                                       "of 5-38), and the rightmost root at the nominal conditions"},
                       {"revolutions", doc.at("suppression_map").at("revolutions")},
                       {"duration_s", run_duration(settings_of(doc), ref.wheel_rpm)},
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

}  // namespace

// ------------------------------------------------------------------ the kind

PluginInfo SuppressionMap::info() {
  return plugin_info("suppression_map", "S1, S2, S3, G3",
                     settings_table().specs(),
                     {{"revolutions", 10.0}, {"sample_rate_hz", 5000.0}},
                     "variable-speed/feed chatter suppression over a modulation grid: simulated "
                     "amplitude ratio vs constant speed, growth-rate averaging, energy balance (S1-S3)");
}

void SuppressionMap::validate(Json& document, const SourceMap& sources) const {
  auto model = kit::validate_model(document, kit::ModelNeeds::characteristic | kit::ModelNeeds::time_domain,
                                   "suppression_map", sources);
  Json suppression = validate_component(document, "suppression", suppression_registry(), sources);
  const Settings s = kit::validate_settings(document, "suppression_map", settings_table(), sources);
  std::unique_ptr<Suppression> plugin;
  try {
    plugin = build_suppression(suppression);
  } catch (const std::invalid_argument& e) {
    refuse(sources, "suppression", fmt::format("[suppression]: {}", e.what()));
  }
  check_combination(*model, document.at("model"), *plugin, suppression, s, sources);
  const double samples = run_duration(s, wheel_rpm(*model)) * s.sample_rate_hz;
  if (samples > max_output_samples)
    refuse(sources, "suppression_map.revolutions",
           fmt::format("suppression_map.revolutions = {}: {:.4g} output samples exceed the limit of {:.4g} "
                       "(fewer revolutions or a lower sample_rate_hz)",
                       document["suppression_map"]["revolutions"].dump(), samples, max_output_samples));
  document["suppression"] = std::move(suppression);
}

std::vector<std::string> SuppressionMap::output_columns(const Json&) const {
  return {col_ratio, col_s2, col_s2_locked, col_drift, col_s3, col_s3_fraction, col_s1, col_outcome};
}

std::vector<Json> SuppressionMap::run_point(const Json& document, const PointContext& /*context*/) const {
  const PointSetup p = setup(document);
  auto model = kit::build_model(document.at("model"));
  const auto [ratio, diverged] = simulated_log_ratio(*model, p);
  const auto [s3_change, s3_fraction] = s3_energy(p);
  return {ratio,     s2_averaging(p), s2_locked(p),       phase_drift(p),
          s3_change, s3_fraction,     s1_swing(*model, p), diverged ? "diverged" : "completed"};
}

void SuppressionMap::write_artifacts(const Study& study, const ResultTable& results, const fs::path& out_dir) const {
  // The constant-speed reference of the study's own model and settings (grid values that change
  // the model give one reference per point; this file records the nominal one).
  write_reference(study, out_dir);
  // Maps need two numeric varying axes; a varying string axis (e.g. suppression.shape) gives one
  // set of maps per value. Other grids: results.csv has every number (documented).
  std::vector<std::size_t> labels;
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    if (study.grid[a].values.size() > 1 && !study.grid[a].values.front().is_number()) labels.push_back(a);
  Study numeric_only = study;
  for (std::size_t a : labels) numeric_only.grid[a].values.resize(1);
  const std::vector<kit::PlotAxis> axes = kit::varying_axes(numeric_only);
  if (axes.size() != 2 || labels.size() > 1) return;
  std::optional<std::size_t> group_column;
  std::vector<Json> groups{Json()};
  if (!labels.empty()) {
    group_column = labels[0];
    groups = study.grid[labels[0]].values;
  }
  const std::string title = kit::study_title(study);
  const std::string target = study.document.at("suppression").at("target").get<std::string>();
  kit::Figures figures;
  for (const Json& group : groups)
    for (const MapSpec& spec : maps) {
      const std::size_t c = kit::column_index(results, spec.column);
      if (std::none_of(results.rows.begin(), results.rows.end(), [&](const auto& row) { return row[c].is_number(); }))
        continue;  // a prediction that does not apply to this model (e.g. the locked lobe)
      plot::Heatmap h = ratio_map(axes, results, spec, group_column, group);
      const std::string group_name = group.is_string() ? group.get<std::string>() : group.dump();
      // Short enough for the figure width: which modulation, then what is drawn.
      h.title = group.is_null() ? fmt::format("{}: {}", title, spec.what)
                                : fmt::format("{} {}: {}", group_name, target, spec.what);
      figures.render(h, out_dir, fmt::format("{}_{}{}", spec.column, target, group.is_null() ? "" : "_" + group_name));
    }
  figures.finish();
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::SuppressionMap);
