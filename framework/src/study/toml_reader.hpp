#pragma once
// Study file -> JSON document + source lines. Keys keep the order they were written in (toml++
// tables are sorted maps; the grid order depends on the written order).
#include <filesystem>
#include <memory>

#include "chatterlab/params.hpp"
#include "study/source_map.hpp"

namespace chatterlab {

struct TomlDocument {
  Json document;
  std::shared_ptr<const LineSourceMap> sources;
};

// Reads and parses `file`. The [grid] table comes out flat: a dotted grid key, quoted
// ("model.modes.0.damping_ratio" = ...) or not (model.modes.0.damping_ratio = ...), is one key
// holding its value; only inline tables ({ from, to, steps }) stay tables there.
// Throws InputError for an unreadable file, a TOML syntax error (with line and column), and
// nan/inf anywhere ("must be finite": no parameter accepts them).
TomlDocument read_toml_study(const std::filesystem::path& file);

}  // namespace chatterlab
