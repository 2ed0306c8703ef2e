#include "kinds/model_table.hpp"

#include <string>
#include <utility>

#include "chatterlab/errors.hpp"
#include "chatterlab/registry.hpp"
#include "kinds/stability_map.hpp"

namespace chatterlab::kinds_detail {

std::unique_ptr<Model> build_model(const Json& model_table) {
  Json params = model_table;
  params.erase("type");
  return model_registry()
      .at(model_table.at("type").get<std::string>())
      .create(ParamValues(std::move(params)));
}

RootSearchOptions root_search_options(const Json& stability, const CharacteristicFunction& fn) {
  RootSearchOptions options;
  const Json& band = stability.at("max_frequency_hz");
  options.max_frequency_hz =
      band.is_null() ? StabilityMap::default_band_multiple * fn.natural_frequency_scale_hz()
                     : band.get<double>();
  options.max_newton_iterations = stability.at("max_newton_iterations").get<int>();
  options.newton_relative_tolerance = stability.at("newton_relative_tolerance").get<double>();
  options.max_function_evaluations = stability.at("max_function_evaluations").get<long>();
  return options;
}

RightmostRoot rightmost_root(const Model& model, const Json& stability_table) {
  auto characteristic = model.characteristic();
  if (!characteristic) throw PointFailure("the model has no characteristic function here");
  return find_rightmost_root(*characteristic, root_search_options(stability_table, *characteristic));
}

}  // namespace chatterlab::kinds_detail
