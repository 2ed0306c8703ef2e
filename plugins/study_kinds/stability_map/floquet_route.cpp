#include "study_kinds/stability_map/floquet_route.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/linearised_model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::stability_floquet {

namespace {

[[noreturn]] void refuse(const SourceMap& sources, const std::string& path, const std::string& what) {
  throw InputError(fmt::format("{}: {}", sources.locate(path).str(), what));
}

std::unique_ptr<Suppression> build(const Json& table) {
  Json params = table;
  params.erase("type");
  return suppression_registry().at(table.at("type").get<std::string>()).create(ParamValues(std::move(params)));
}

// The rotor a speed target modulates; nullopt for the feed.
std::optional<Rotor> rotor_of(SuppressionTarget target) {
  switch (target) {
    case SuppressionTarget::wheel_speed: return Rotor::wheel;
    case SuppressionTarget::work_speed: return Rotor::work;
    case SuppressionTarget::feed: return std::nullopt;
  }
  return std::nullopt;
}

// The periodic process of the suppression: the target rotor's speed law (installed the way a
// simulation installs it, apply_modulation), the other rotor constant. Without modulation the
// period is one revolution of the target rotor (any period is one of a constant process).
PeriodicProcess process_of(const Model& model, const Suppression& plugin, double& period_s) {
  const Rotor rotor = *rotor_of(plugin.target());
  auto td = model.time_domain();
  period_s = plugin.modulation_period_s();
  if (!(period_s > 0.0)) period_s = 60.0 / td->nominal_speed_rpm(rotor);
  SimulationSettings installed;
  apply_modulation(plugin.target(), plugin.law(period_s), *td, installed);  // std::invalid_argument
  PeriodicProcess process;
  process.speed[static_cast<std::size_t>(rotor)] = installed.speed[static_cast<std::size_t>(rotor)];
  process.period_s = period_s;
  return process;
}

// Why the first level's monodromy is beyond the discretisation's limit, or nullopt.
std::optional<std::string> dimension_problem(const PeriodicDelaySystem& system) {
  const FloquetSettings settings;
  const FloquetLevel first = first_floquet_level(system, settings);
  if (first.dimension <= settings.max_dimension) return std::nullopt;
  return fmt::format("the longest revolution ({:.4g} s) at the step that resolves {:.4g} Hz gives a monodromy of "
                     "dimension {} > {} (the discretisation's limit: its eigenvalues cost n^3)",
                     system.max_delay_s(), system.frequency_scale_hz(), first.dimension, settings.max_dimension);
}

// The process of a model with periodic coefficients: its nominal constant speeds, one period.
PeriodicProcess nominal_process(double period_s) {
  PeriodicProcess process;
  process.period_s = period_s;
  return process;
}

}  // namespace

void validate(Json& document, const Model& model, const SourceMap& sources) {
  Json table = validate_component(document, "suppression", suppression_registry(), sources);
  const std::string model_type = document.at("model").at("type").get<std::string>();
  const LinearisedModel* linearised = model.linearised();
  if (!linearised || !model.time_domain())
    refuse(sources, "model.type",
           fmt::format("model.type = \"{}\": a stability_map with [suppression] takes the Floquet route, "
                       "which needs the model's linearisation (a model written once, "
                       "chatterlab/derived_model.hpp, or a LinearisedModel); this model has none",
                       model_type));
  std::unique_ptr<Suppression> plugin;
  try {
    plugin = build(table);
  } catch (const std::invalid_argument& e) {
    refuse(sources, "suppression", fmt::format("[suppression]: {}", e.what()));
  }
  if (!rotor_of(plugin->target()))
    refuse(sources, "suppression.target",
           fmt::format("suppression.target = \"{}\": the Floquet route takes periodic rotor speeds "
                       "(wheel_speed, work_speed); the infeed enters the linearisation as a forcing, "
                       "not a coefficient, so its modulation needs the simulated suppression_map",
                       to_string(plugin->target())));
  // A random law has no period: Floquet theory does not apply (suppression_map simulates it).
  if (table.value("shape", std::string()) == "random")
    refuse(sources, "suppression.shape",
           "suppression.shape = \"random\": a random modulation is not periodic, so it has no Floquet "
           "multipliers (valid here: sinusoidal, triangular, square); suppression_map simulates it");
  double period_s = 0.0;
  std::unique_ptr<PeriodicDelaySystem> system;
  try {
    const PeriodicProcess process = process_of(model, *plugin, period_s);
    system = periodic_surface_system(*linearised, process);
  } catch (const std::invalid_argument& e) {
    refuse(sources, "suppression.target",
           fmt::format("suppression.target = \"{}\": {}", to_string(plugin->target()), e.what()));
  } catch (const PointFailure& e) {
    refuse(sources, "suppression", fmt::format("[suppression]: {}", e.what()));
  }
  if (const auto problem = dimension_problem(*system))
    refuse(sources, "suppression.target",
           fmt::format("suppression.target = \"{}\": {}; a faster modulated rotor or suppression_map",
                       to_string(plugin->target()), *problem));
  document["suppression"] = std::move(table);
}

FloquetPoint growth_rate(const Model& model, const Json& suppression_table, const FloquetSettings& settings) {
  const LinearisedModel* linearised = model.linearised();
  if (!linearised) throw PointFailure("Floquet: the model has no linearisation");
  const std::unique_ptr<Suppression> plugin = build(suppression_table);
  FloquetPoint out;
  out.target = to_string(plugin->target());
  PeriodicProcess process;
  try {
    process = process_of(model, *plugin, out.period_s);
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
  out.floquet = floquet_growth_rate(*periodic_surface_system(*linearised, process), settings);
  return out;
}

}  // namespace chatterlab::stability_floquet

namespace chatterlab::stability_floquet {

std::optional<double> coefficient_period_s(const Model& model) {
  const LinearisedModel* linearised = model.linearised();
  return linearised ? linearised->coefficient_period_s() : std::nullopt;
}

void validate_periodic_model(const Json& document, const Model& model, const SourceMap& sources) {
  const std::string model_type = document.at("model").at("type").get<std::string>();
  if (document.contains("suppression"))
    refuse(sources, "suppression",
           fmt::format("[suppression]: model.type = \"{}\" has coefficients that repeat once per {:.4g} s at "
                       "constant speeds (its Floquet route needs no [suppression]); a speed modulation on top "
                       "has in general no common period with them, so it has no Floquet multipliers: remove "
                       "[suppression], or simulate the modulation (suppression_map)",
                       model_type, *coefficient_period_s(model)));
  std::unique_ptr<PeriodicDelaySystem> system;
  try {
    system = periodic_surface_system(*model.linearised(), nominal_process(*coefficient_period_s(model)));
  } catch (const PointFailure& e) {
    refuse(sources, "model.type", fmt::format("model.type = \"{}\": {}", model_type, e.what()));
  }
  if (const auto problem = dimension_problem(*system))
    refuse(sources, "model.type",
           fmt::format("model.type = \"{}\": its Floquet route over one coefficient period: {}; a faster wheel "
                       "or simulate",
                       model_type, *problem));
}

FloquetPoint periodic_model_growth_rate(const Model& model, const FloquetSettings& settings) {
  const std::optional<double> period = coefficient_period_s(model);
  if (!period) throw PointFailure("Floquet: the model's coefficients are not periodic");
  FloquetPoint out;
  out.period_s = *period;
  out.target = "coefficients";
  out.floquet = floquet_growth_rate(*periodic_surface_system(*model.linearised(), nominal_process(*period)), settings);
  return out;
}

}  // namespace chatterlab::stability_floquet
