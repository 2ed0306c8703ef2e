#include "models/measured_frf/measured_frf.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <mutex>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// ---------------------------------------------------------------- the machine, read and fitted once

std::string cache_key(const MeasuredFrfParameters& p) {
  std::string key = fmt::format("{}|{}|", static_cast<int>(p.machine_compliance), p.frf_dataset);
  if (p.frf_file) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(*p.frf_file, ec);
    const auto time = std::filesystem::last_write_time(*p.frf_file, ec).time_since_epoch().count();
    key += fmt::format("file:{}|{}|{}", *p.frf_file, size, time);
  } else {
    key += Json{*p.frf_frequency_hz, *p.frf_real_m_per_n, *p.frf_imag_m_per_n}.dump();
  }
  return key + "|" + modal_fit_settings_table().write(p.fit).dump();
}

MeasuredFrf inline_frf(const MeasuredFrfParameters& p) {
  const auto& f = *p.frf_frequency_hz;
  const auto& re = *p.frf_real_m_per_n;
  const auto& im = *p.frf_imag_m_per_n;
  if (re.size() != f.size() || im.size() != f.size())
    throw InputError(fmt::format("model.frf_frequency_hz, model.frf_real_m_per_n and model.frf_imag_m_per_n have {}, "
                                 "{} and {} entries: one per frequency line",
                                 f.size(), re.size(), im.size()));
  MeasuredFrf frf;
  frf.source = "model.frf_frequency_hz";
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (i > 0 && !(f[i] > f[i - 1]))
      throw InputError(fmt::format("model.frf_frequency_hz.{} = {}: not above the previous line's {} Hz", i, f[i],
                                   f[i - 1]));
    frf.frequency_hz.push_back(f[i]);
    frf.receptance_m_per_n.emplace_back(re[i], im[i]);
  }
  return frf;
}

std::shared_ptr<const MeasuredMachineData> load_machine(const MeasuredFrfParameters& p) {
  static std::mutex mutex;
  static std::deque<std::pair<std::string, std::shared_ptr<const MeasuredMachineData>>> cache;
  constexpr std::size_t capacity = 16;
  const std::string key = cache_key(p);
  {
    std::lock_guard lock(mutex);
    for (const auto& [k, machine] : cache)
      if (k == key) return machine;
  }
  auto machine = std::make_shared<MeasuredMachineData>();
  machine->frf = p.frf_file ? read_frf(*p.frf_file, p.frf_dataset) : inline_frf(p);
  if (p.machine_compliance == MachineCompliance::fitted_modes) machine->fit = fit_modes(machine->frf, p.fit);
  std::lock_guard lock(mutex);
  cache.emplace_back(key, machine);
  if (cache.size() > capacity) cache.pop_front();
  return machine;
}

// ---------------------------------------------------------------- parameters

MeasuredFrfParameters read_parameters(const ParamValues& values) {
  MeasuredFrfParameters p = measured_frf_table().read(values);
  const bool inline_given = p.frf_frequency_hz || p.frf_real_m_per_n || p.frf_imag_m_per_n;
  if (p.frf_file.has_value() == inline_given)
    throw InputError(p.frf_file ? "model: give the FRF either as frf_file or inline (frf_frequency_hz, ...), not both"
                                : "model: missing FRF: give frf_file, or frf_frequency_hz, frf_real_m_per_n and "
                                  "frf_imag_m_per_n");
  if (inline_given && !(p.frf_frequency_hz && p.frf_real_m_per_n && p.frf_imag_m_per_n))
    throw InputError("model: an inline FRF needs all three of frf_frequency_hz, frf_real_m_per_n and frf_imag_m_per_n");
  if (p.grinding_width_mm.has_value() != p.reference_width_mm.has_value())
    throw InputError(fmt::format("model.{}: grinding_width_mm and reference_width_mm go together (the stiffnesses are "
                                 "given at reference_width_mm and scale with grinding_width_mm)",
                                 p.grinding_width_mm ? "reference_width_mm is missing" : "grinding_width_mm is missing"));
  return p;
}

G1Process process_of(const MeasuredFrfParameters& p) {
  // Contact, wear and removal stiffness all grow with the engaged width.
  const double scale = p.grinding_width_mm ? *p.grinding_width_mm / *p.reference_width_mm : 1.0;
  G1Process g;
  g.contact_stiffness_n_per_m = scale * p.contact_stiffness_n_per_m;
  g.wheel_wear_stiffness_n_per_m = scale * p.wheel_wear_stiffness_n_per_m;
  g.work_removal_stiffness_n_per_m = scale * p.work_removal_stiffness_n_per_m;
  g.wheel_period_s = 60.0 / p.wheel_speed_rpm;
  g.work_period_s = 60.0 / p.work_speed_rpm;
  g.wheel_regeneration = p.wheel_regeneration;
  g.work_regeneration = p.work_regeneration;
  return g;
}

// plunge_regenerative (G1) with the fitted modes, through the model registry.
std::unique_ptr<Model> fitted_g1(const G1Process& g, const MeasuredFrfParameters& p, const ModalFit& fit,
                                 const std::string& source) {
  Json modes = Json::array();
  for (const FittedMode& m : fit.modes) {
    if (!(m.stiffness_n_per_m > 0.0))
      throw InputError(fmt::format("{}: the fitted mode at {:.4g} Hz has a negative modal stiffness ({:.4g} N/m): G1 "
                                   "needs the drive-point receptance at the wheel-work contact, whose modes all have "
                                   "positive stiffness (check the FRF's response and reference points, or the fit band)",
                                   source, m.frequency_hz, m.stiffness_n_per_m));
    modes.push_back({{"frequency_hz", m.frequency_hz},
                     {"damping_ratio", m.damping_ratio},
                     {"stiffness_n_per_m", m.stiffness_n_per_m}});
  }
  const Json table = {{"wheel_speed_rpm", p.wheel_speed_rpm},
                      {"work_speed_rpm", p.work_speed_rpm},
                      {"contact_stiffness_n_per_m", g.contact_stiffness_n_per_m},
                      {"wheel_wear_stiffness_n_per_m", g.wheel_wear_stiffness_n_per_m},
                      {"work_removal_stiffness_n_per_m", g.work_removal_stiffness_n_per_m},
                      {"modes", modes},
                      {"wheel_regeneration", p.wheel_regeneration},
                      {"work_regeneration", p.work_regeneration}};
  const auto* g1 = model_registry().find("plunge_regenerative");
  if (!g1) throw std::logic_error("measured_frf: the plunge_regenerative model (G1) is not registered");
  return g1->create(ParamValues(table));
}

// Where the measured route's count may stop: above the last line with kc |H| >= 0.9 x the process
// margin, |F - 1| < 1 (with room for the spline between lines). Beyond the measured band H is
// assumed to keep falling, as a structure's compliance does above its modes.
double measured_winding_limit(const MeasuredFrf& frf, const G1Process& g) {
  const double threshold = 0.9 * g.process_margin() / g.contact_stiffness_n_per_m;
  const std::size_t n = frf.frequency_hz.size();
  for (std::size_t i = n; i-- > 0;) {
    if (std::abs(frf.receptance_m_per_n[i]) < threshold) continue;
    if (i + 1 == n)
      throw PointFailure(fmt::format("the measured FRF ends at {:g} Hz where kc |H| = {:.3g} is still above the process "
                                     "margin {:.3g}: the Nyquist count needs the FRF up to where kc |H| falls below it "
                                     "(measure a wider band, or use machine_compliance = \"fitted_modes\")",
                                     frf.frequency_hz[i], g.contact_stiffness_n_per_m * std::abs(frf.receptance_m_per_n[i]),
                                     g.process_margin()));
    return kTwoPi * frf.frequency_hz[i + 1];
  }
  return 0.0;
}

// The same for fitted modes, from a bound valid on the axis and on the arc |s| = R in Re s >= 0:
// |s^2 + 2 zeta w s + w^2| >= R^2 - 2 zeta w R - w^2.
double modal_winding_limit(const std::vector<FittedMode>& modes, const G1Process& g) {
  double r = 0.0;
  for (const FittedMode& m : modes) {
    const double w = kTwoPi * m.frequency_hz;
    r = std::max(r, 1.5 * w * (m.damping_ratio + std::sqrt(m.damping_ratio * m.damping_ratio + 1.0)));
  }
  auto bound = [&](double radius) {
    double h = 0.0;
    for (const FittedMode& m : modes) {
      const double w = kTwoPi * m.frequency_hz;
      h += w * w / std::abs(m.stiffness_n_per_m) / (radius * radius - 2.0 * m.damping_ratio * w * radius - w * w);
    }
    return g.contact_stiffness_n_per_m * h;
  };
  for (int i = 0; i < 60 && bound(r) > 0.9 * g.process_margin(); ++i) r *= 1.25;
  return r;
}

// The structural frequency scale of a measurement: the highest local maximum of |H| that reaches
// 1/20 of the largest (the highest mode that matters).
double highest_peak_hz(const MeasuredFrf& frf) {
  const auto& h = frf.receptance_m_per_n;
  double largest = 0.0;
  for (const Complex& v : h) largest = std::max(largest, std::abs(v));
  double highest = frf.frequency_hz.back();
  for (std::size_t i = 1; i + 1 < h.size(); ++i)
    if (std::abs(h[i]) >= 0.05 * largest && std::abs(h[i]) >= std::abs(h[i - 1]) && std::abs(h[i]) >= std::abs(h[i + 1]))
      highest = frf.frequency_hz[i];
  return highest;
}

// H below the lowest measured line: the lowest line's real part plus its imaginary part falling
// linearly to 0 at 0 Hz (continuous, and real at 0 Hz as a compliance is).
G1ReturnDifference::ComplianceValue measured_compliance(const FrfInterpolant& h, const MeasuredFrf& frf, double f) {
  if (f < h.min_frequency_hz()) {
    const Complex low = frf.receptance_m_per_n.front();
    const double f0 = h.min_frequency_hz();
    return {Complex(low.real(), low.imag() * f / f0), Complex(0.0, low.imag() / f0)};
  }
  if (const auto v = h.at(f)) return {v->receptance_m_per_n, v->derivative_m_per_n_hz};
  // Above the band (only reached beyond the winding limit by the lobe scan): the top line.
  return {frf.receptance_m_per_n.back(), 0.0};
}

// An example FRF for `chatterlab describe` and the conformance test: two modes (184 and 306 Hz
// of the G8 machine) on lines 40..600 Hz every 2 Hz, as a tap test would give them.
Json example_parameters() {
  std::vector<FittedMode> modes(2);
  modes[0].frequency_hz = 184.08, modes[0].damping_ratio = 0.05, modes[0].stiffness_n_per_m = 5e7;
  modes[1].frequency_hz = 305.6, modes[1].damping_ratio = 0.04, modes[1].stiffness_n_per_m = 8e7;
  Json f = Json::array(), re = Json::array(), im = Json::array();
  for (int i = 20; i <= 300; ++i) {
    const Complex h = modes_receptance(modes, 2.0 * i);
    f.push_back(2.0 * i);
    re.push_back(h.real());
    im.push_back(h.imag());
  }
  return {{"frf_frequency_hz", f},  {"frf_real_m_per_n", re}, {"frf_imag_m_per_n", im},
          {"wheel_speed_rpm", 1450}, {"work_speed_rpm", 55},    {"contact_stiffness_n_per_m", 1e8},
          {"wheel_wear_stiffness_n_per_m", 5e9}, {"work_removal_stiffness_n_per_m", 5e7}};
}

}  // namespace

const ParamTable<MeasuredFrfParameters>& measured_frf_table() {
  static const ParamTable<MeasuredFrfParameters> table = [] {
    using P = MeasuredFrfParameters;
    ParamTable<P> t;
    t.add(&P::frf_file, "frf_file", "", "measured FRF at the wheel-work contact: CSV with units in the header, or UFF dataset 58 (relative to the study file)").data_file();
    t.add(&P::frf_dataset, "frf_dataset", "1", "which FRF of a file holding several (counted from 1; 0: the file's only one)").at_least(0);
    t.add(&P::frf_frequency_hz, "frf_frequency_hz", "Hz", "an inline FRF instead of frf_file: its frequency lines").positive().min_items(4);
    t.add(&P::frf_real_m_per_n, "frf_real_m_per_n", "m/N", "an inline FRF: real part of the receptance at each line");
    t.add(&P::frf_imag_m_per_n, "frf_imag_m_per_n", "m/N", "an inline FRF: imaginary part of the receptance at each line");
    t.add_choice(&P::machine_compliance, "machine_compliance",
                 "fitted_modes: the FRF's fitted modes in G1 (roots, simulation); measured: the FRF itself (Nyquist count only)",
                 {{"fitted_modes", MachineCompliance::fitted_modes}, {"measured", MachineCompliance::measured}});
    t.add_table(&P::fit, "fit", "modal fit of the FRF (LSCF, stabilisation diagram, refinement)", modal_fit_settings_table());
    t.add(&P::wheel_speed_rpm, "wheel_speed_rpm", "rpm", "wheel speed n_g; wheel period Tg = 60/n_g").positive().required();
    t.add(&P::work_speed_rpm, "work_speed_rpm", "rpm", "workpiece speed n_w; work period Tw = 60/n_w").positive().required();
    t.add(&P::contact_stiffness_n_per_m, "contact_stiffness_n_per_m", "N/m", "wheel-work contact stiffness kc (at reference_width_mm when given)").positive().required();
    t.add(&P::wheel_wear_stiffness_n_per_m, "wheel_wear_stiffness_n_per_m", "N/m", "wheel wear stiffness kg (at reference_width_mm when given)").positive().required();
    t.add(&P::work_removal_stiffness_n_per_m, "work_removal_stiffness_n_per_m", "N/m", "workpiece removal stiffness kw (at reference_width_mm when given)").positive().required();
    t.add(&P::wheel_regeneration, "wheel_regeneration", "1", "wheel surface regeneration on (false: kg -> infinity)");
    t.add(&P::work_regeneration, "work_regeneration", "1", "workpiece regeneration on (false: kw -> infinity)");
    t.add(&P::grinding_width_mm, "grinding_width_mm", "mm", "engaged grinding width; kc, kg and kw scale with grinding_width_mm/reference_width_mm").positive();
    t.add(&P::reference_width_mm, "reference_width_mm", "mm", "the width at which kc, kg and kw are given (with grinding_width_mm)").positive();
    return t;
  }();
  return table;
}

MeasuredFrfModel::MeasuredFrfModel(const ParamValues& values)
    : parameters_(read_parameters(values)), machine_(load_machine(parameters_)), process_(process_of(parameters_)) {
  if (machine_->fit) fitted_g1_ = fitted_g1(process_, parameters_, *machine_->fit, machine_->frf.source);
}

PluginInfo MeasuredFrfModel::info() {
  return plugin_info("measured_frf", "G1, G8",
                     measured_frf_table().specs(),
                     example_parameters(),
                     "Plunge grinding (G1 eq 2-16) with the machine compliance from a measured FRF: its fitted modes, or the FRF itself",
                     ThreadSafety::shareable);
}

std::unique_ptr<CharacteristicFunction> MeasuredFrfModel::characteristic() const {
  return fitted_g1_ ? fitted_g1_->characteristic() : nullptr;
}

std::unique_ptr<ReturnDifference> MeasuredFrfModel::return_difference() const {
  double scale_hz = 0.0;
  if (const ModalFit* fit = modal_fit()) {
    for (const FittedMode& m : fit->modes) scale_hz = std::max(scale_hz, m.frequency_hz);
    const std::vector<FittedMode> modes = fit->modes;
    return std::make_unique<G1ReturnDifference>(
        process_,
        [modes](double f) {
          const double step = 1e-6 * std::max(f, 1.0);
          return G1ReturnDifference::ComplianceValue{
              modes_receptance(modes, f), (modes_receptance(modes, f + step) - modes_receptance(modes, f - step)) / (2 * step)};
        },
        modal_winding_limit(modes, process_), scale_hz);
  }
  const MeasuredFrf& frf = machine_->frf;
  auto interpolant = std::make_shared<const FrfInterpolant>(frf);
  auto data = machine_;
  return std::make_unique<G1ReturnDifference>(
      process_, [interpolant, data](double f) { return measured_compliance(*interpolant, data->frf, f); },
      measured_winding_limit(frf, process_), highest_peak_hz(frf));
}

std::optional<double> MeasuredFrfModel::wheel_period_s() const { return process_.wheel_period_s; }

std::unique_ptr<TimeDomainModel> MeasuredFrfModel::time_domain() const {
  return fitted_g1_ ? fitted_g1_->time_domain() : nullptr;
}

std::optional<StiffnessChain> MeasuredFrfModel::stiffness_chain() const {
  return fitted_g1_ ? fitted_g1_->stiffness_chain() : std::nullopt;
}

CHATTERLAB_REGISTER_MODEL(MeasuredFrfModel);

}  // namespace chatterlab
