// The plugin conformance suite (chatterlab/conformance.hpp): one implementation for
// `chatterlab check-plugin` and tests/unit/conformance_test.cpp.
#include "chatterlab/conformance.hpp"

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "chatterlab/analysis.hpp"
#include "chatterlab/catalog.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/suppression.hpp"
#include "study/source_map.hpp"

namespace chatterlab {
namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

// What one check found wrong; empty: passed.
using Problems = std::vector<std::string>;

void expect(Problems& problems, bool condition, const std::string& message) {
  if (!condition) problems.push_back(message);
}

std::string current_exception_text() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "an exception that is not a std::exception";
  }
}

// Records one check of one plugin: its problems, or anything it threw, as the result.
class Recorder {
 public:
  Recorder(ConformanceReport& report, std::string plugin)
      : report_(report), plugin_(std::move(plugin)) {}

  // Runs `check(problems)`; it may also return a note (what was measured) for a passed check.
  void run(const std::string& name, const std::function<std::string(Problems&)>& check) {
    ConformanceResult result{plugin_, name, true, false, ""};
    Problems problems;
    try {
      result.message = check(problems);
    } catch (...) {
      problems.push_back("threw: " + current_exception_text());
    }
    if (!problems.empty()) {
      result.passed = false;
      result.message.clear();
      for (const auto& p : problems) result.message += (result.message.empty() ? "" : "; ") + p;
    }
    report_.results.push_back(std::move(result));
  }
  void skip(const std::string& name, const std::string& why) {
    report_.results.push_back({plugin_, name, true, true, why});
  }

 private:
  ConformanceReport& report_;
  std::string plugin_;
};

// ------------------------------------------------------------------ naming and specs

bool is_snake_case(const std::string& name) {
  if (name.empty() || !(name.front() >= 'a' && name.front() <= 'z')) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// Quantities carry a unit; strings, booleans and lists of tables (whose fields carry their own)
// do not.
bool needs_unit(ValueKind kind) {
  return kind == ValueKind::real || kind == ValueKind::integer || kind == ValueKind::real_list ||
         kind == ValueKind::real_matrix;
}

void check_naming(const PluginInfo& info, Problems& problems) {
  expect(problems, is_snake_case(info.name), "name '" + info.name + "' is not snake_case");
  expect(problems, !info.description.empty(), "no description");
  expect(problems, info.description.find('\n') == std::string::npos, "description is not one line");
  const std::string text = describe_plugin(info.name);
  expect(problems, text.find(info.description) != std::string::npos,
         "`chatterlab describe` does not show the description");
  for (const ParamSpec& spec : info.params)
    expect(problems, text.find(spec.key) != std::string::npos,
           "`chatterlab describe` does not show parameter " + spec.key);
}

void check_specs(const std::vector<ParamSpec>& specs, const std::string& path, Problems& problems) {
  for (const ParamSpec& spec : specs) {
    const std::string key = path + "." + spec.key;
    auto expect_spec = [&](bool condition, const std::string& what) {
      expect(problems, condition, "parameter " + key + ": " + what);
    };
    expect_spec(is_snake_case(spec.key), "key is not snake_case");
    expect_spec(!spec.description.empty(), "no description");
    expect_spec(spec.description.find('\n') == std::string::npos, "description is not one line");
    if (needs_unit(spec.kind)) expect_spec(!spec.unit.empty(), "no unit (\"1\" if dimensionless)");
    expect_spec(!std::isnan(spec.min) && !std::isnan(spec.max), "a NaN limit");
    expect_spec(!(spec.min > spec.max), "min > max");
    if (!spec.default_value.is_null()) {
      // The default must pass the spec's own checks (type and limits).
      LineSourceMap sources("default of " + key);
      try {
        validate_params(Json{{spec.key, spec.default_value}}, {spec}, path, sources);
      } catch (const InputError& e) {
        expect_spec(false, "default " + spec.default_value.dump() + " violates its own spec: " + e.what());
      }
    }
    if (spec.kind == ValueKind::table_list) {
      expect_spec(!spec.fields.empty(), "a list of tables without fields");
      check_specs(spec.fields, key + "[]", problems);
    }
    if (spec.kind == ValueKind::table) {
      expect_spec(!spec.fields.empty(), "a table without fields");
      expect_spec(spec.optional || spec.default_value.is_object(),
                  "a table is optional or defaults to its fields' defaults ({})");
      check_specs(spec.fields, key, problems);
    }
  }
}

// A NaN in place of each real parameter of the example is refused, naming the key. (TOML has
// nan; a plugin that declared a real as a string or a table would let it through.)
void check_nan_parameters(const PluginInfo& info, const std::string& path, Problems& problems) {
  LineSourceMap sources("NaN check of " + info.name);
  for (const ParamSpec& spec : info.params) {
    if (spec.kind != ValueKind::real || !info.example_params.contains(spec.key)) continue;
    Json table = info.example_params;
    table[spec.key] = std::numeric_limits<double>::quiet_NaN();
    try {
      validate_params(table, info.params, path, sources);
      problems.push_back(spec.key + " = nan was accepted");
    } catch (const InputError& e) {
      expect(problems, std::string(e.what()).find(spec.key) != std::string::npos,
             spec.key + " = nan was refused without naming the key: " + e.what());
    }
  }
}

// ------------------------------------------------------------------ models

// Relative distance between the analytic derivative and a central difference of E.
double derivative_error(const CharacteristicFunction& e, Complex s) {
  const double h = 1e-7 * std::max(1.0, std::abs(s));
  const Complex difference = (e.evaluate(s + h).value - e.evaluate(s - h).value) / (2.0 * h);
  const Complex analytic = e.evaluate(s).derivative;
  return std::abs(difference - analytic) / std::max(std::abs(analytic), 1e-300);
}

std::string show(Complex s) { return fmt::format("{:.9g}{:+.9g}i", s.real(), s.imag()); }

std::string check_characteristic(const Model& model, Problems& problems) {
  auto e = model.characteristic();
  if (!e) return "no characteristic function (time-domain only)";
  const double f = e->natural_frequency_scale_hz();
  if (!(std::isfinite(f) && f > 0)) {
    problems.push_back(fmt::format("natural_frequency_scale_hz() = {} (must be finite and > 0)", f));
    return {};
  }
  const double w = two_pi * f;
  const double bound = e->real_part_bound();
  expect(problems, std::isfinite(bound), fmt::format("real_part_bound() = {} is not finite", bound));

  for (Complex s : {Complex(-0.1 * w, 0.7 * w), Complex(0.01 * w, 1.3 * w), Complex(-0.02 * w, 0.2 * w)}) {
    const double error = derivative_error(*e, s);
    expect(problems, error < 1e-5,
           fmt::format("E'(s) disagrees with a difference of E at s = {} (relative {:.2g})", show(s), error));
  }
  for (Complex r : e->neutral_roots(2 * w)) {
    // "An exact zero": tiny next to E a little way off.
    const double nearby = std::abs(e->evaluate(r + Complex(0, 1e-3 * w)).value);
    expect(problems, std::abs(e->evaluate(r).value) <= 1e-8 * nearby,
           "neutral root " + show(r) + " is not a zero of E");
  }
  std::vector<Complex> guesses;
  e->initial_guesses(w, guesses);
  expect(problems, !guesses.empty(), "no initial guesses");

  RootSearchOptions options;
  options.max_frequency_hz = f;  // a small band: one structural frequency
  const RightmostRoot found = find_rightmost_root(*e, options);
  const Complex s = found.root;
  expect(problems, std::isfinite(s.real()) && std::isfinite(s.imag()), "the rightmost root is not finite");
  expect(problems, s.imag() >= 0.0, "the rightmost root has Im s < 0");
  expect(problems, s.real() <= bound,
         fmt::format("root {} lies right of real_part_bound() = {}", show(s), bound));
  // A root, not just a number: the Newton step there is negligible.
  const CharacteristicValue at_root = e->evaluate(s);
  expect(problems, std::abs(at_root.value / at_root.derivative) <= 1e-8 * std::max(1.0, std::abs(s)),
         "E(" + show(s) + ") is not a zero");
  // NaN goes in, NaN comes out: a characteristic function must not turn it into a number.
  const Complex nan_s(std::numeric_limits<double>::quiet_NaN(), 0.0);
  const Complex at_nan = e->evaluate(nan_s).value;
  expect(problems, !std::isfinite(at_nan.real()) || !std::isfinite(at_nan.imag()),
         "E(NaN) = " + show(at_nan) + " is a number");
  return fmt::format("rightmost root in a band of {:.4g} Hz: {} ({})", f, show(s),
                     found.certified ? "certified" : "not certified");
}

// A short simulation: consistent sizes, finite outputs.
std::string check_time_domain_form(const Model& model, Problems& problems) {
  auto td = model.time_domain();
  if (!td) return "no time-domain form";
  expect(problems, td->state_size() > 0, "state_size() = 0");
  const double f = td->highest_frequency_hz();
  if (!(std::isfinite(f) && f > 0)) {
    problems.push_back(fmt::format("highest_frequency_hz() = {} (must be finite and > 0)", f));
    return {};
  }
  for (Rotor r : {Rotor::wheel, Rotor::work})
    if (!td->angle_state(r))
      expect(problems, td->nominal_speed_rpm(r) > 0.0,
             std::string("nominal_speed_rpm(") + to_string(r) + ") <= 0");
  SimulationSettings settings;
  settings.duration_s = 0.05;
  settings.sample_rate_hz = 4000.0;
  settings.infeed_rate_m_per_s = 1e-5;
  const SimulationResult result = simulate(*td, settings);
  expect(problems, result.t_s.size() == 201u,
         fmt::format("{} output samples for 0.05 s at 4 kHz, expected 201", result.t_s.size()));
  const auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  expect(problems, finite(result.displacement_m), "a displacement is not finite");
  expect(problems, finite(result.force_n), "a force is not finite");
  return fmt::format("0.05 s simulated: {}", result.status);
}

// The distinct zeros Newton reaches from the model's own initial guesses for the band (upper half
// plane), rightmost first: the leading roots beside the certified rightmost one.
std::vector<Complex> leading_roots(const CharacteristicFunction& e, double band_rad_s) {
  std::vector<Complex> guesses, roots;
  e.initial_guesses(band_rad_s, guesses);
  for (Complex s : guesses) {
    for (int i = 0; i < 60; ++i) {
      const CharacteristicValue v = e.evaluate(s);
      const Complex step = v.value / v.derivative;
      s -= step;
      if (!(std::abs(step) > 1e-13 * std::max(1.0, std::abs(s)))) break;
    }
    const CharacteristicValue at = e.evaluate(s);
    if (!std::isfinite(s.real()) || !std::isfinite(s.imag()) || s.imag() < 0.0 ||
        std::abs(at.value / at.derivative) > 1e-9 * std::max(1.0, std::abs(s)))
      continue;
    if (std::none_of(roots.begin(), roots.end(), [&](Complex r) { return std::abs(r - s) < 1e-6 * std::max(1.0, std::abs(s)); }))
      roots.push_back(s);
  }
  std::sort(roots.begin(), roots.end(), [](Complex a, Complex b) { return a.real() > b.real(); });
  return roots;
}

// Where a model has both forms, a bilateral (linear) simulation without infeed grows like the
// leading characteristic roots. The growth rate is the least-squares slope of ln(energy) over
// blocks of one revolution of the slowest regenerated surface: roots of one delay lattice differ
// by about one revolution's frequency, so a block averages their beat out, and the estimate is a
// weighted mean of the leading roots' growth rates, dominated by the rightmost. Measured after
// two revolutions (the regeneration has taken hold) over four more. It must lie within 5 % of
// the rightmost root's growth rate plus half the gap to the second root (the two may share the
// response) plus a 5 % amplitude error over the window, and the response's frequency within 2 %
// of one of the two.
std::string check_time_domain_agreement(const Model& model, Problems& problems) {
  auto e = model.characteristic();
  auto td = model.time_domain();
  RootSearchOptions options;
  options.max_frequency_hz = 4.0 * e->natural_frequency_scale_hz();
  const Complex first = find_rightmost_root(*e, options).root;
  const double growth = first.real(), frequency = std::abs(first.imag()) / two_pi;
  if (frequency <= 0.0) return "not compared: the rightmost root is real (no oscillation to fit)";
  Complex second = first;
  for (Complex r : leading_roots(*e, two_pi * options.max_frequency_hz))
    if (std::abs(r - first) > 1e-6 * std::abs(first)) {
      second = r;
      break;
    }
  double block = 10.0 / frequency;
  for (Rotor r : {Rotor::wheel, Rotor::work})
    if (td->regenerates(r)) block = std::max(block, 60.0 / td->nominal_speed_rpm(r));
  const double settle = std::max(2.0 * block, 20.0 / frequency);
  const int blocks = std::max(4, static_cast<int>(std::ceil(40.0 / frequency / block)));
  const double window = blocks * block;
  // Either way out of range: a growth overflows, a decay from 1e-12 m underflows the block energies
  // (a forced response, G6's unbalance, would then be all that is left).
  if (std::abs(growth) * (settle + window) > 300.0)
    return fmt::format("not compared: growth {:.4g}/s over {:.3g} s leaves the range of a double", growth,
                       settle + window);
  SimulationSettings s;
  s.duration_s = settle + window;
  s.sample_rate_hz = 40.0 * frequency;
  s.one_sided_contact = false;
  s.infeed_rate_m_per_s = 0.0;
  // The roots are those of the linearisation: start where the nonlinear terms are negligible
  // over the whole run (G5: 1 um of vibration already modulates a 55 rpm work speed by ~9 %
  // through the torque, and the speed correction is quadratic in the amplitude).
  s.disturbance = {1e-12, 0.0};
  s.divergence_limit_m = 1e250;
  const SimulationResult r = simulate(*td, s);
  if (r.diverged || r.status != "completed") {
    problems.push_back("the bilateral simulation did not complete: " + r.status);
    return {};
  }
  // ln(energy) per block against the block's centre time; growth = slope / 2.
  std::vector<double> t, ln_energy;
  for (int k = 0; k < blocks; ++k) {
    const double start = settle + k * block, end = start + block;
    double energy = 0.0;
    for (std::size_t i = 0; i < r.t_s.size(); ++i)
      if (r.t_s[i] >= start && r.t_s[i] < end) energy += r.displacement_m[i] * r.displacement_m[i];
    t.push_back(start + 0.5 * block);
    ln_energy.push_back(std::log(energy));
  }
  double mt = 0.0, me = 0.0;
  for (int k = 0; k < blocks; ++k) mt += t[k] / blocks, me += ln_energy[k] / blocks;
  double sxy = 0.0, sxx = 0.0;
  for (int k = 0; k < blocks; ++k) sxy += (t[k] - mt) * (ln_energy[k] - me), sxx += (t[k] - mt) * (t[k] - mt);
  const double simulated = 0.5 * sxy / sxx;
  const EnvelopeFit fit = fit_envelope(r.t_s, r.displacement_m, settle, settle + window, 0.5 * frequency);
  const double simulated_frequency =
      fit.t_s.size() > 1 ? static_cast<double>(fit.t_s.size() - 1) / (fit.t_s.back() - fit.t_s.front()) : 0.0;
  const double second_frequency = std::abs(second.imag()) / two_pi;
  const double tolerance = 0.05 * std::abs(growth) + 0.5 * (growth - second.real()) + std::log(1.05) / window;
  const std::string measured = fmt::format(
      "roots {:.6g}/s at {:.6g} Hz and {:.6g}/s at {:.6g} Hz; simulation {:.6g}/s at {:.6g} Hz ({:.3g}..{:.3g} s)",
      growth, frequency, second.real(), second_frequency, simulated, simulated_frequency, settle, settle + window);
  expect(problems, std::abs(simulated - growth) <= tolerance,
         fmt::format("growth rates disagree by more than {:.3g}/s: {}", tolerance, measured));
  expect(problems,
         std::abs(simulated_frequency - frequency) <= 0.02 * frequency ||
             std::abs(simulated_frequency - second_frequency) <= 0.02 * second_frequency,
         "the simulated frequency is neither root's (2 %): " + measured);
  return measured;
}

// ------------------------------------------------------------------ fingerprints for the
// concurrency check: everything a product computes from a fixed input.

std::string hex(double x) { return fmt::format("{:a} ", x); }

template <class Compute>
std::string guarded(Compute&& compute) {
  try {
    return compute();
  } catch (...) {
    return "threw: " + current_exception_text();
  }
}

std::string fingerprint(const Model& model) {
  std::string out;
  if (auto e = model.characteristic()) {
    const double w = two_pi * e->natural_frequency_scale_hz();
    for (int k = 0; k < 64; ++k) {
      const CharacteristicValue v = e->evaluate(Complex(-0.2 * w + 0.4 * w * k / 63.0, 2.0 * w * k / 63.0));
      out += hex(v.value.real()) + hex(v.value.imag()) + hex(v.derivative.real()) + hex(v.derivative.imag());
    }
  }
  if (auto period = model.wheel_period_s()) out += hex(*period);
  if (auto td = model.time_domain()) {
    out += guarded([&] {
      SimulationSettings s;
      s.duration_s = std::min(0.02, 40.0 / td->highest_frequency_hz());
      s.sample_rate_hz = 200.0 / s.duration_s;
      const SimulationResult r = simulate(*td, s);
      std::string text = r.status + " ";
      for (double x : r.displacement_m) text += hex(x);
      return text;
    });
  }
  return out;
}

// A fixed test signal: two incommensurate tones and deterministic noise, 1 kHz, 2048 samples.
SampledSeries test_series() {
  SampledSeries series;
  series.sample_interval = 1e-3;
  series.name = "conformance test signal";
  std::uint64_t state = 12345;
  std::vector<double> values;
  for (int i = 0; i < 2048; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double noise = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
    values.push_back(std::sin(two_pi * 0.013 * i) + 0.5 * std::sin(two_pi * 0.0712 * i + 1.0) +
                     0.1 * noise);
  }
  series.set_samples(std::move(values));
  return series;
}

std::string fingerprint(const Analysis& analysis) {
  static const SampledSeries series = test_series();
  return guarded([&] { return analysis.analyse(series, Json::object()).dump(); });
}

std::string fingerprint(const Kinematics& machine) {
  std::string out;
  const std::vector<MotorAxis> motors = machine.motors();
  for (const MotorAxis& m : motors) out += m.name + " " + hex(m.mm_per_pulse);
  for (double x : {5.0, 20.0, 60.0}) {
    out += guarded([&] {
      std::vector<double> positions(motors.size());
      machine.inverse({x, 20.0, 1.0, 0.1}, {}, positions);
      std::string text;
      for (double p : positions) text += hex(p);
      const ToolInPart tool = machine.forward(positions, {});
      return text + hex(tool.x_mm) + hex(tool.y_mm) + hex(tool.radius_mm);
    });
  }
  return out;
}

std::string fingerprint(const Suppression& suppression) {
  std::string out = std::string(to_string(suppression.target())) + " " + hex(suppression.modulation_period_s());
  const auto law = suppression.law(1.0);
  for (int k = 0; k <= 50; ++k) out += hex(law->level(k / 50.0)) + hex(law->level_integral(k / 50.0));
  return out;
}

// ------------------------------------------------------------------ NaN handling per kind

std::string check_nan_product(const Model&, Problems&) { return {}; }  // E(NaN): model check
std::string check_nan_product(const StudyKind&, Problems&) { return {}; }
std::string check_nan_product(const Suppression&, Problems&) { return {}; }

std::string check_nan_product(const Analysis& analysis, Problems& problems) {
  SampledSeries series = test_series();
  std::vector<double> with_nan(series.values.begin(), series.values.end());
  with_nan[with_nan.size() / 2] = std::numeric_limits<double>::quiet_NaN();
  series.set_samples(std::move(with_nan));
  try {
    analysis.analyse(series, Json::object());
    problems.push_back("analyse() returned a result for a series holding NaN (it must throw InputError)");
  } catch (...) {
    return "a series holding NaN is refused: " + current_exception_text();
  }
  return {};
}

std::string check_nan_product(const Kinematics& machine, Problems& problems) {
  std::vector<double> positions(machine.motors().size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  try {
    machine.inverse({nan, 20.0, 1.0, 0.0}, {}, positions);
  } catch (...) {
    return "inverse() of a NaN target throws";
  }
  expect(problems, std::any_of(positions.begin(), positions.end(), [](double p) { return std::isnan(p); }),
         "inverse() of a NaN target returned finite positions");
  return "inverse() of a NaN target answers NaN";
}

// ------------------------------------------------------------------ the concurrency check

// Two fingerprints agree: the same text, numbers equal to 1e-9 relative. A race changes results
// grossly (or crashes); an OpenMP reduction inside a plugin may add in scheduling order and move
// the last bits, which the shipped-study regression test tolerates too (1e-12).
bool same_results(const std::string& a, const std::string& b) {
  const char* p = a.c_str();
  const char* q = b.c_str();
  while (*p != '\0' && *q != '\0') {
    auto number_start = [](char c) { return (c >= '0' && c <= '9') || c == '-' || c == '+'; };
    if (number_start(*p) && number_start(*q)) {
      char* p_end = nullptr;
      char* q_end = nullptr;
      const double x = std::strtod(p, &p_end), y = std::strtod(q, &q_end);
      if (p_end != p && q_end != q) {
        const bool equal = (std::isnan(x) && std::isnan(y)) ||
                           std::abs(x - y) <= 1e-9 * std::max(std::abs(x), std::abs(y));
        if (!equal) return false;
        p = p_end;
        q = q_end;
        continue;
      }
    }
    if (*p++ != *q++) return false;
  }
  return *p == *q;
}

template <class Product>
std::string check_threads(const typename Registry<Product>::Entry& entry, const Json& params,
                          int thread_count, Problems& problems) {
  const ParamValues values(params);
  const std::string reference = fingerprint(*entry.create(values));
  const bool shareable = entry.info.thread_safety == ThreadSafety::shareable;
  std::unique_ptr<Product> shared = shareable ? entry.create(values) : nullptr;
  std::vector<std::string> seen(static_cast<std::size_t>(thread_count));
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < thread_count; ++t) {
      threads.emplace_back([&, t] {
        std::unique_ptr<Product> own = shareable ? nullptr : entry.create(values);
        const Product& product = shareable ? *shared : *own;
        // Twice: an instance is reused for every point a thread computes.
        std::string first = fingerprint(product), second = fingerprint(product);
        seen[static_cast<std::size_t>(t)] = same_results(first, second) ? first : "differs on reuse";
      });
    }
  }
  std::size_t differing = 0;
  for (const std::string& s : seen) differing += same_results(s, reference) ? 0 : 1;
  expect(problems, differing == 0,
         fmt::format("{} of {} threads computed other results than one thread alone ({})", differing,
                     thread_count,
                     shareable ? "declared shareable: one instance used by all threads"
                               : "declared copy_per_thread: one instance per thread"));
  return fmt::format("{} threads, {}", thread_count, to_string(entry.info.thread_safety));
}

// ------------------------------------------------------------------ one registry

void check_product(const Model& model, const ConformanceOptions& options, Recorder& record) {
  record.run("model", [&](Problems& p) {
    std::string note = check_characteristic(model, p);
    const std::string td = check_time_domain_form(model, p);
    if (auto period = model.wheel_period_s()) expect(p, *period > 0.0, "wheel_period_s() <= 0");
    return note + "; " + td;
  });
  if (!model.characteristic() || !model.time_domain())
    record.skip("time domain", "the model does not have both a characteristic function and a time-domain form");
  else if (!options.time_domain)
    record.skip("time domain", "left out (ConformanceOptions::time_domain)");
  else
    record.run("time domain", [&](Problems& p) { return check_time_domain_agreement(model, p); });
}

void check_product(const StudyKind& kind, const ConformanceOptions&, Recorder& record) {
  record.run("study kind", [&](Problems& p) {
    expect(p, !kind.tables().empty(), "a study kind reads no table");
    return std::string();
  });
}

template <class Product>
void check_product(const Product&, const ConformanceOptions&, Recorder&) {}

template <class Product>
constexpr bool has_fingerprint = !std::is_same_v<Product, StudyKind>;

template <class Product>
void check_registry(const Registry<Product>& registry, const ConformanceOptions& options,
                    ConformanceReport& report) {
  if (!options.registry_kind.empty() && options.registry_kind != registry.kind()) return;
  for (const auto* entry : registry.sorted()) {
    if (!options.origin.empty() && entry->origin != options.origin) continue;
    ++report.plugins;
    const PluginInfo& info = entry->info;
    Recorder record(report, fmt::format("{} '{}'", registry.kind(), info.name));
    record.run("naming", [&](Problems& p) { check_naming(info, p); return std::string(); });
    record.run("specs", [&](Problems& p) { check_specs(info.params, registry.kind(), p); return std::string(); });

    Json validated;
    std::unique_ptr<Product> product;
    record.run("example", [&](Problems& p) {
      LineSourceMap sources("example_params of " + info.name);
      try {
        validated = validate_params(info.example_params, info.params, registry.kind(), sources);
      } catch (const InputError& e) {
        p.push_back("example_params " + info.example_params.dump() + " fail the plugin's own specs: " + e.what());
        return std::string();
      }
      product = entry->create(ParamValues(validated));
      expect(p, product != nullptr, "the factory returned null");
      return std::string();
    });
    if (!product) continue;  // nothing further can be checked

    record.run("NaN", [&](Problems& p) {
      check_nan_parameters(info, registry.kind(), p);
      return check_nan_product(*product, p);
    });
    check_product(*product, options, record);
    if constexpr (has_fingerprint<Product>) {
      if (info.thread_safety == ThreadSafety::serial)
        record.skip("threads", "declared serial: never run concurrently");
      else if (!options.threads)
        record.skip("threads", "left out (ConformanceOptions::threads)");
      else
        record.run("threads", [&](Problems& p) {
          return check_threads<Product>(*entry, validated, options.thread_count, p);
        });
    } else {
      record.skip("threads", "a study kind's points run concurrently in every run (--threads)");
    }
  }
}

}  // namespace

std::size_t ConformanceReport::failures() const {
  return static_cast<std::size_t>(
      std::count_if(results.begin(), results.end(), [](const auto& r) { return !r.passed; }));
}

std::string ConformanceReport::text() const {
  std::string out;
  std::size_t skipped = 0;
  for (const ConformanceResult& r : results) {
    const char* verdict = !r.passed ? "FAIL" : r.skipped ? "skip" : "ok  ";
    skipped += r.skipped ? 1 : 0;
    out += fmt::format("{} {}: {}{}{}\n", verdict, r.plugin, r.check, r.message.empty() ? "" : ": ", r.message);
  }
  out += fmt::format("{} plugin{} checked: {} checks passed, {} failed, {} did not apply\n", plugins,
                     plugins == 1 ? "" : "s", results.size() - failures() - skipped, failures(), skipped);
  return out;
}

ConformanceReport check_conformance(const ConformanceOptions& options) {
  ConformanceReport report;
  check_registry(study_kind_registry(), options, report);
  check_registry(model_registry(), options, report);
  check_registry(kinematics_registry(), options, report);
  check_registry(suppression_registry(), options, report);
  check_registry(analysis_registry(), options, report);
  return report;
}

}  // namespace chatterlab
