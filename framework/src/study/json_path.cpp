#include "study/json_path.hpp"

#include <charconv>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/study.hpp"
#include "study/messages.hpp"

namespace chatterlab {
namespace {

std::string_view type_name(const Json& value) {
  if (value.is_boolean()) return "boolean";
  if (value.is_number()) return "number";
  if (value.is_string()) return "string";
  if (value.is_null()) return "empty value";
  return value.is_array() ? "list" : "table";
}

// Walks one path component at a time; `where` names the part walked so far for messages.
template <class J>
J* walk(J& document, std::string_view path, std::string& problem) {
  J* node = &document;
  std::string where;
  std::size_t start = 0;
  while (true) {
    std::size_t dot = path.find('.', start);
    std::string_view part = path.substr(start, dot == std::string_view::npos ? dot : dot - start);
    if (part.empty()) {
      problem = fmt::format("'{}' is not a parameter path (empty part between dots)", path);
      return nullptr;
    }
    std::string here = where.empty() ? std::string(part) : where + "." + std::string(part);
    if (node->is_object()) {
      auto it = node->find(std::string(part));
      if (it == node->end()) {
        auto keys = messages::keys_of(*node);
        problem = where.empty()
                      ? fmt::format("the study has no table '{}'{}; it has: {}", part,
                                    messages::did_you_mean(part, keys), messages::sorted_list(keys))
                      : fmt::format("{} has no key '{}'{}; it has: {}", where, part,
                                    messages::did_you_mean(part, keys), messages::sorted_list(keys));
        return nullptr;
      }
      node = &*it;
    } else if (node->is_array()) {
      std::size_t index = 0;
      auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), index);
      bool is_index = ec == std::errc() && end == part.data() + part.size();
      if (!is_index || index >= node->size()) {
        std::string range = node->empty() ? std::string("it is empty")
                            : node->size() == 1
                                ? std::string("it has 1 entry (index 0)")
                                : fmt::format("it has {} entries (indices 0 to {})", node->size(),
                                              node->size() - 1);
        problem = is_index ? fmt::format("{} is a list and {}; there is no index {}", where, range, part)
                           : fmt::format("{} is a list: '{}' is not an index; {}", where, part, range);
        return nullptr;
      }
      node = &(*node)[index];
    } else {
      problem = fmt::format("{} is a {} ({}), it has no item '{}'", where, type_name(*node),
                            messages::show(*node), part);
      return nullptr;
    }
    if (dot == std::string_view::npos) return node;
    where = std::move(here);
    start = dot + 1;
  }
}

}  // namespace

const Json* find_at_path(const Json& document, std::string_view path, std::string& problem) {
  return walk(document, path, problem);
}
Json* find_at_path(Json& document, std::string_view path, std::string& problem) {
  return walk(document, path, problem);
}

void set_at_path(Json& document, const std::string& dotted_path, const Json& value) {
  std::string problem;
  Json* node = find_at_path(document, dotted_path, problem);
  if (node == nullptr) throw InputError(problem);
  *node = value;
}

}  // namespace chatterlab
