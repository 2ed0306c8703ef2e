#include "kinds/model_table.hpp"

#include <string>
#include <utility>

#include "chatterlab/registry.hpp"

namespace chatterlab::kinds_detail {

std::unique_ptr<Model> build_model(const Json& model_table) {
  Json params = model_table;
  params.erase("type");
  return model_registry()
      .at(model_table.at("type").get<std::string>())
      .create(ParamValues(std::move(params)));
}

}  // namespace chatterlab::kinds_detail
