#include "study/toml_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "study/messages.hpp"

namespace chatterlab {
namespace {

int line_of(const toml::source_region& region) { return static_cast<int>(region.begin.line); }

bool written_before(const toml::source_region& a, const toml::source_region& b) {
  return std::pair(a.begin.line, a.begin.column) < std::pair(b.begin.line, b.begin.column);
}

std::string join_path(const std::string& prefix, std::string_view key) {
  return prefix.empty() ? std::string(key) : prefix + "." + std::string(key);
}

struct Entry {
  const toml::key* key;
  const toml::node* node;
};

// A table's entries in the order they were written.
std::vector<Entry> in_written_order(const toml::table& table) {
  std::vector<Entry> entries;
  for (const auto& [key, node] : table) entries.push_back({&key, &node});
  std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return written_before(a.key->source(), b.key->source());
  });
  return entries;
}

class Converter {
 public:
  explicit Converter(LineSourceMap& sources) : sources_(sources) {}

  Json table(const toml::table& table, const std::string& path) {
    Json out = Json::object();
    for (const auto& [key, node] : in_written_order(table)) {
      std::string child = join_path(path, key->str());
      sources_.add(child, line_of(key->source()));
      out[std::string(key->str())] =
          path.empty() && key->str() == "grid" && node->is_table() ? grid(*node->as_table(), child)
                                                                   : value(*node, child);
    }
    return out;
  }

 private:
  Json value(const toml::node& node, const std::string& path) {
    if (const auto* t = node.as_table()) return table(*t, path);
    if (const auto* a = node.as_array()) {
      Json out = Json::array();
      for (std::size_t i = 0; i < a->size(); ++i) {
        std::string item = join_path(path, std::to_string(i));
        sources_.add(item, line_of((*a)[i].source()));
        out.push_back(value((*a)[i], item));
      }
      return out;
    }
    if (const auto* s = node.as_string()) return s->get();
    if (const auto* i = node.as_integer()) return i->get();
    if (const auto* b = node.as_boolean()) return b->get();
    if (const auto* f = node.as_floating_point()) {
      double d = f->get();
      if (!std::isfinite(d))
        throw InputError(fmt::format("{}: {} = {}: must be finite (nan and inf are not accepted)",
                                     sources_.locate(path).str(), path, messages::show(d)));
      return d;
    }
    // Dates and times: no parameter takes one; as text they fail type checks with a clear message.
    std::ostringstream text;
    node.visit([&](const auto& leaf) { text << leaf; });
    return text.str();
  }

  // Flattens the dotted keys of [grid] (non-inline tables) into one key each, in written order.
  Json grid(const toml::table& table, const std::string& path) {
    struct Leaf {
      std::string key;
      const toml::node* node;
      toml::source_region where;
    };
    std::vector<Leaf> leaves;
    auto collect = [&](auto&& self, const toml::table& t, const std::string& prefix) -> void {
      for (const auto& [key, node] : t) {
        std::string joined = join_path(prefix, key.str());
        const auto* nested = node.as_table();
        if (nested != nullptr && !nested->is_inline())
          self(self, *nested, joined);
        else
          leaves.push_back({joined, &node, key.source()});
      }
    };
    collect(collect, table, "");
    std::stable_sort(leaves.begin(), leaves.end(), [](const Leaf& a, const Leaf& b) {
      return written_before(a.where, b.where);
    });
    Json out = Json::object();
    for (const auto& leaf : leaves) {
      std::string child = join_path(path, leaf.key);
      // `"a.b" = ...` and `a.b = ...` are different TOML keys but the same grid key.
      if (out.contains(leaf.key))
        throw InputError(fmt::format("{}: [grid] key '{}' is written twice (also on line {})",
                                     SourceLocation{sources_.file(), line_of(leaf.where)}.str(),
                                     leaf.key, sources_.locate(child).line));
      sources_.add(child, line_of(leaf.where));
      out[leaf.key] = value(*leaf.node, child);
    }
    return out;
  }

  LineSourceMap& sources_;
};

std::string read_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw InputError(fmt::format("{}: cannot read the study file: it is a directory", file.string()));
  // Through the input snapshot: meta.json records the hash of exactly the text that was parsed.
  std::shared_ptr<const std::string> text = try_read_input_file(file, InputRole::study);
  if (!text)
    throw InputError(fmt::format("{}: cannot read the study file: {}", file.string(),
                                 std::strerror(errno)));
  return *text;
}

}  // namespace

TomlDocument read_toml_study(const std::filesystem::path& file) {
  std::string text = read_file(file);
  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: invalid TOML: {}", file.string(), e.source().begin.line,
                                 e.source().begin.column, e.description()));
  }
  auto sources = std::make_shared<LineSourceMap>(file.string());
  Json document = Converter(*sources).table(root, "");
  return {std::move(document), std::move(sources)};
}

}  // namespace chatterlab
