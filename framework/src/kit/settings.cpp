// Study kit: settings tables (chatterlab/kit/settings.hpp).
#include "chatterlab/kit/settings.hpp"

#include <fmt/format.h>

#include "chatterlab/errors.hpp"

namespace chatterlab::kit {

Json table_or_empty(const Json& document, const std::string& name, const SourceMap& sources) {
  auto it = document.find(name);
  if (it == document.end() || it->is_null()) return Json::object();
  if (!it->is_object())
    throw InputError(fmt::format("{}: {} = {}: expected a table [{}]", sources.locate(name).str(),
                                 name, it->dump(), name));
  return *it;
}

}  // namespace chatterlab::kit
