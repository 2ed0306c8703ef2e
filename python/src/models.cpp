// Models from Python: validation, the certified rightmost root (the stability_map route through
// the study kit, so the numbers are the command line's), and the dynamics engine.
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/kit/simulation.hpp"
#include "convert.hpp"

namespace chatterlab::python {
namespace {

// The validated [model] table (type first, every default filled in) and the built model.
struct ValidatedModel {
  Json table;
  std::unique_ptr<Model> model;
};

ValidatedModel validated_model(Json document, kit::ModelNeeds needs, const std::string& function) {
  CallSourceMap sources(function);
  auto model = kit::validate_model(document, needs, function, sources);
  return {std::move(document["model"]), std::move(model)};
}

py::object validate_model(py::handle model) {
  Json document{{"model", to_json(model, "model")}};
  Json table;
  {
    py::gil_scoped_release release;
    table = validated_model(std::move(document), kit::ModelNeeds::nothing, "validate_model").table;
  }
  return to_python(table);
}

py::dict rightmost_root(py::handle model, std::optional<double> max_frequency_hz, py::handle stability) {
  Json document{{"model", to_json(model, "model")}};
  Json settings_table = stability.is_none() ? Json::object() : to_json(stability, "stability");
  if (max_frequency_hz) settings_table["max_frequency_hz"] = *max_frequency_hz;
  document["stability"] = std::move(settings_table);

  RightmostRoot root;
  kit::StabilityVerdict verdict;
  double band_hz = 0.0;
  Json model_table;
  {
    py::gil_scoped_release release;
    CallSourceMap sources("rightmost_root");
    auto model_ptr = kit::validate_model(document, kit::ModelNeeds::characteristic, "rightmost_root", sources);
    const kit::StabilitySettings settings = kit::validate_stability(document, *model_ptr, sources);
    band_hz = kit::root_search_options(settings, *model_ptr->characteristic()).max_frequency_hz;
    root = kit::rightmost_root(*model_ptr, settings);
    verdict = kit::verdict(root, *model_ptr);
    model_table = document["model"];
  }
  py::dict out;
  out["root"] = py::cast(root.root);
  out["growth_rate_per_s"] = verdict.growth_rate_per_s;
  out["chatter_frequency_hz"] = verdict.chatter_frequency_hz;
  out["growth_rate_per_wheel_rev"] = py::cast(verdict.growth_rate_per_wheel_rev);
  out["stable"] = verdict.stable;
  out["certified"] = root.certified;
  out["certified_real_part_per_s"] = root.certified_real_part;
  out["certificate"] = root.certificate;
  out["zeros_right_of_contour"] = root.zeros_right_of_contour;
  out["roots_found"] = root.roots_found;
  out["repaired_roots"] = root.repaired_roots;
  out["neutral_roots_excluded"] = root.neutral_roots_excluded;
  out["function_evaluations"] = root.function_evaluations;
  out["max_frequency_hz"] = band_hz;
  out["model"] = to_python(model_table);
  return out;
}

// A speed law from Python: None (the model's nominal speed), {"modulation": "sinusoidal",
// "amplitude_ratio": 0.1, "frequency_hz": 2.0[, "mean_rpm": ...]} or {"schedule": [[t_s, rpm], ...]}.
std::shared_ptr<const SpeedLaw> speed_law(py::handle law, double nominal_rpm, const std::string& where) {
  if (law.is_none()) return nullptr;
  const Json spec = to_json(law, where);
  if (!spec.is_object()) throw py::type_error(where + ": expected None or a dict (docs/python.md, simulate)");
  for (const auto& [key, value] : spec.items())
    if (key != "modulation" && key != "amplitude_ratio" && key != "frequency_hz" && key != "mean_rpm" &&
        key != "schedule")
      throw InputError(where + ": unknown key '" + key +
                       "'; valid: amplitude_ratio, frequency_hz, mean_rpm, modulation, schedule");
  if (spec.contains("schedule")) {
    std::vector<double> times, rpm;
    for (const Json& row : spec["schedule"]) {
      if (!row.is_array() || row.size() != 2 || !row[0].is_number() || !row[1].is_number())
        throw InputError(where + ".schedule: expected rows [t_s, rpm], got " + row.dump());
      times.push_back(row[0].get<double>());
      rpm.push_back(row[1].get<double>());
    }
    return make_scheduled_speed(std::move(times), std::move(rpm));
  }
  const double mean = spec.contains("mean_rpm") ? spec["mean_rpm"].get<double>() : nominal_rpm;
  return make_modulated_speed(mean, parse_speed_modulation(spec.value("modulation", std::string("constant"))),
                              spec.value("amplitude_ratio", 0.0), spec.value("frequency_hz", 0.0));
}

// simulate()'s settings checked as the `simulate` kind checks its [simulation] table: every key
// against its limits, then across keys for this model (output samples, snapshot times within the
// duration ...), so that a bad setting raises InputError with the command line's message
// ("simulate: simulation.duration_s = -1 [s]: out of range, must be > 0 ...").
void check_simulation(py::handle model, py::handle simulation) {
  Json document{{"model", to_json(model, "model")}, {"simulation", to_json(simulation, "simulation")}};
  py::gil_scoped_release release;
  CallSourceMap sources("simulate");
  const ValidatedModel validated = validated_model(document, kit::ModelNeeds::time_domain, "simulate");
  kit::SimulationTable table = kit::validate_settings(document, "simulation", kit::simulation_table(), sources);
  kit::check_simulation(table, *validated.model->time_domain(), "simulation", sources);
}

py::dict simulate(py::handle model, const SimulationSettings& settings_in, py::handle wheel_speed,
                  py::handle work_speed) {
  Json document{{"model", to_json(model, "model")}};
  ValidatedModel validated;
  std::unique_ptr<TimeDomainModel> time_domain;
  SimulationSettings settings = settings_in;
  {
    py::gil_scoped_release release;
    validated = validated_model(std::move(document), kit::ModelNeeds::time_domain, "simulate");
    time_domain = validated.model->time_domain();
  }
  const std::pair<Rotor, py::handle> laws[] = {{Rotor::wheel, wheel_speed}, {Rotor::work, work_speed}};
  for (const auto& [rotor, law] : laws) {
    const std::string where = std::string(to_string(rotor)) + "_speed";
    if (time_domain->angle_state(rotor) && !law.is_none())
      throw InputError(where + ": the " + to_string(rotor) +
                       " speed is a state of this model (it follows from the dynamics)");
    settings.speed[static_cast<std::size_t>(rotor)] = speed_law(law, time_domain->nominal_speed_rpm(rotor), where);
  }
  SimulationResult r;
  {
    py::gil_scoped_release release;
    r = chatterlab::simulate(*time_domain, settings);
  }
  constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel);
  constexpr auto work = static_cast<std::size_t>(Rotor::work);
  py::dict out;
  out["t_s"] = to_numpy(std::move(r.t_s));
  out["displacement_m"] = to_numpy(std::move(r.displacement_m));
  out["force_n"] = to_numpy(std::move(r.force_n));
  out["depth_of_cut_m"] = to_numpy(std::move(r.depth_of_cut_m));
  out["infeed_m"] = to_numpy(std::move(r.infeed_m));
  out["wheel_speed_rpm"] = to_numpy(std::move(r.speed_rpm[wheel]));
  out["work_speed_rpm"] = to_numpy(std::move(r.speed_rpm[work]));
  out["wheel_surface_at_contact_m"] = to_numpy(std::move(r.surface_at_contact_m[wheel]));
  out["work_surface_at_contact_m"] = to_numpy(std::move(r.surface_at_contact_m[work]));
  out["in_contact"] = to_numpy(std::move(r.in_contact));
  py::list snapshots;
  for (SurfaceSnapshot& s : r.snapshots) {
    py::dict snap;
    snap["t_s"] = s.t_s;
    snap["angle_deg"] = to_numpy(std::move(s.angle_deg));
    snap["wheel_surface_m"] = to_numpy(std::move(s.surface_m[wheel]));
    snap["work_surface_m"] = to_numpy(std::move(s.surface_m[work]));
    snapshots.append(std::move(snap));
  }
  out["snapshots"] = std::move(snapshots);
  out["contact_loss_intervals_s"] = py::cast(r.contact_loss_intervals);
  out["contact_loss_time_s"] = r.contact_loss_time_s;
  out["diverged"] = r.diverged;
  out["end_time_s"] = r.end_time_s;
  out["status"] = r.status;
  out["diagnostics"] = py::cast(r.diagnostics);
  out["steps"] = r.steps;
  out["rhs_evaluations"] = r.rhs_evaluations;
  out["contact_events"] = r.contact_events;
  out["method"] = r.method;
  out["fixed_step_s"] = r.fixed_step_s;
  out["model"] = to_python(validated.table);
  return out;
}

py::dict fit_envelope(py::handle t_s, py::handle x, double start_s, double end_s, double min_frequency_hz) {
  auto t = as_series(t_s, "fit_envelope: t_s");
  auto v = as_series(x, "fit_envelope: x");
  if (t.size() != v.size())
    throw py::value_error("fit_envelope: t_s and x differ in length (" + std::to_string(t.size()) + " and " +
                          std::to_string(v.size()) + " samples)");
  EnvelopeFit fit;
  {
    py::gil_scoped_release release;
    fit = chatterlab::fit_envelope({t.data(), static_cast<std::size_t>(t.size())},
                                   {v.data(), static_cast<std::size_t>(v.size())}, start_s, end_s,
                                   min_frequency_hz);
  }
  py::dict out;
  out["growth_rate_per_s"] = fit.growth_rate_per_s;
  out["intercept"] = fit.intercept;
  out["start_s"] = fit.start_s;
  out["end_s"] = fit.end_s;
  out["residual_rms"] = fit.residual_rms;
  out["t_s"] = to_numpy(std::move(fit.t_s));
  out["envelope"] = to_numpy(std::move(fit.envelope));
  return out;
}

// The engine's defaults (SimulationSettings' member initialisers), for the Python signature.
py::dict simulation_defaults() {
  const SimulationSettings d;
  py::dict out;
  out["sample_rate_hz"] = d.sample_rate_hz;
  out["initial_displacement_m"] = d.disturbance.displacement_m;
  out["initial_velocity_m_per_s"] = d.disturbance.velocity_m_per_s;
  out["initial_waviness_m"] = d.initial_waviness_m;
  out["seed"] = d.seed;
  out["infeed_rate_m_per_s"] = d.infeed_rate_m_per_s;
  out["one_sided_contact"] = d.one_sided_contact;
  out["wheel_contact_arc_deg"] = d.contact_arc_deg[static_cast<std::size_t>(Rotor::wheel)];
  out["work_contact_arc_deg"] = d.contact_arc_deg[static_cast<std::size_t>(Rotor::work)];
  out["relative_tolerance"] = d.relative_tolerance;
  out["integrator"] = to_string(d.integrator);
  out["fixed_steps_per_wave"] = d.fixed_steps_per_wave;
  out["samples_per_wave"] = d.samples_per_wave;
  out["max_steps_per_wave"] = d.max_steps_per_wave;
  out["divergence_limit_m"] = d.divergence_limit_m;
  return out;
}

}  // namespace

void bind_models(py::module_& m) {
  m.def("simulation_defaults", &simulation_defaults);
  m.def("validate_model", &validate_model, py::arg("model"),
        "The [model] table validated as a study validates it: `type` first, every default filled in.");
  m.def("rightmost_root", &rightmost_root, py::arg("model"), py::arg("max_frequency_hz") = py::none(),
        py::arg("stability") = py::none(),
        "Certified rightmost characteristic root (the stability_map route); a dict of results.");

  py::class_<SimulationSettings>(m, "_SimulationSettings")
      .def(py::init([](double duration_s, double sample_rate_hz, double initial_displacement_m,
                       double initial_velocity_m_per_s, double initial_waviness_m, std::uint64_t seed,
                       double infeed_rate_m_per_s, bool one_sided_contact, double wheel_contact_arc_deg,
                       double work_contact_arc_deg, std::vector<double> snapshot_times_s,
                       double relative_tolerance, const std::string& integrator, double fixed_steps_per_wave,
                       double samples_per_wave,
                       double max_steps_per_wave, double divergence_limit_m) {
             SimulationSettings s;
             s.duration_s = duration_s;
             s.sample_rate_hz = sample_rate_hz;
             s.disturbance = {initial_displacement_m, initial_velocity_m_per_s};
             s.initial_waviness_m = initial_waviness_m;
             s.seed = seed;
             s.infeed_rate_m_per_s = infeed_rate_m_per_s;
             s.one_sided_contact = one_sided_contact;
             s.contact_arc_deg[static_cast<std::size_t>(Rotor::wheel)] = wheel_contact_arc_deg;
             s.contact_arc_deg[static_cast<std::size_t>(Rotor::work)] = work_contact_arc_deg;
             s.snapshot_times_s = std::move(snapshot_times_s);
             s.relative_tolerance = relative_tolerance;
             try {
               s.integrator = parse_time_integrator(integrator);
             } catch (const std::invalid_argument& e) {
               throw InputError("simulate: integrator = \"" + integrator + "\": " + e.what());
             }
             s.fixed_steps_per_wave = fixed_steps_per_wave;
             s.samples_per_wave = samples_per_wave;
             s.max_steps_per_wave = max_steps_per_wave;
             s.divergence_limit_m = divergence_limit_m;
             return s;
           }),
           py::arg("duration_s"), py::arg("sample_rate_hz"), py::arg("initial_displacement_m"),
           py::arg("initial_velocity_m_per_s"), py::arg("initial_waviness_m"), py::arg("seed"),
           py::arg("infeed_rate_m_per_s"), py::arg("one_sided_contact"), py::arg("wheel_contact_arc_deg"),
           py::arg("work_contact_arc_deg"), py::arg("snapshot_times_s"), py::arg("relative_tolerance"),
           py::arg("integrator"), py::arg("fixed_steps_per_wave"), py::arg("samples_per_wave"), py::arg("max_steps_per_wave"),
           py::arg("divergence_limit_m"));
  m.def("check_simulation", &check_simulation, py::arg("model"), py::arg("simulation"),
        "Checks simulate()'s settings as the simulate kind's [simulation] table (InputError with its message).");
  m.def("simulate", &simulate, py::arg("model"), py::arg("settings"), py::arg("wheel_speed") = py::none(),
        py::arg("work_speed") = py::none(), "Time-domain simulation by the dynamics engine; a dict of arrays.");
  m.def("fit_envelope", &fit_envelope, py::arg("t_s"), py::arg("x"), py::arg("start_s"), py::arg("end_s"),
        py::arg("min_frequency_hz") = 0.0, "Growth rate of x(t) from its envelope over [start_s, end_s].");
}

}  // namespace chatterlab::python
