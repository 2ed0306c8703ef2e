#pragma once
// Template definitions for Registry<Product>; header-only so out-of-tree plugins compiled against
// these headers manipulate the host's registries with the same code.
#include <algorithm>
#include <stdexcept>

#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace detail {
std::string join_names(const std::vector<std::string>& names);
}

template <class Product>
void Registry<Product>::add(PluginInfo info, Factory create, std::string origin) {
  if (info.name.empty())
    throw std::logic_error("chatterlab: a plugin in the " + kind_ + " registry has no name");
  if (auto it = entries_.find(info.name); it != entries_.end()) {
    throw std::logic_error("chatterlab: duplicate " + kind_ + " plugin name '" + info.name +
                           "' (registered by " + it->second.origin + " and by " + origin + ")");
  }
  std::string name = info.name;
  entries_.emplace(std::move(name), Entry{std::move(info), std::move(create), std::move(origin)});
}

template <class Product>
const typename Registry<Product>::Entry* Registry<Product>::find(std::string_view name) const {
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : &it->second;
}

template <class Product>
const typename Registry<Product>::Entry& Registry<Product>::at(std::string_view name) const {
  if (const Entry* e = find(name)) return *e;
  std::vector<std::string> names;
  for (const auto& [n, e] : entries_) names.push_back(n);
  throw InputError("unknown " + kind_ + " '" + std::string(name) +
                   "'; valid names: " + detail::join_names(names));
}

template <class Product>
std::vector<const typename Registry<Product>::Entry*> Registry<Product>::sorted() const {
  std::vector<const Entry*> out;
  for (const auto& [n, e] : entries_) out.push_back(&e);  // std::map: already sorted by name
  return out;
}

}  // namespace chatterlab
