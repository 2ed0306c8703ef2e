#pragma once
// SourceMap implementations used while loading a study.
#include <string>
#include <string_view>
#include <unordered_map>

#include "chatterlab/params.hpp"

namespace chatterlab {

// Dotted path -> line, recorded while converting the TOML tree. A path that was never written
// (a missing key, a default) is located at its nearest written ancestor, so "missing key" errors
// point at the table header; a path outside every table gives the file alone.
class LineSourceMap final : public SourceMap {
 public:
  explicit LineSourceMap(std::string file) : file_(std::move(file)) {}
  void add(const std::string& dotted_path, int line) { lines_.emplace(dotted_path, line); }
  SourceLocation locate(std::string_view dotted_path) const override;
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::unordered_map<std::string, int> lines_;
};

// Locates `path` and everything below it at `where` (a grid key's line), and the rest through
// `base`: a grid value is validated at its parameter path but was written on the grid line.
class OverlaySourceMap final : public SourceMap {
 public:
  OverlaySourceMap(const SourceMap& base, std::string path, SourceLocation where)
      : base_(base), path_(std::move(path)), where_(std::move(where)) {}
  SourceLocation locate(std::string_view dotted_path) const override;

 private:
  const SourceMap& base_;
  std::string path_;
  SourceLocation where_;
};

// True when `path` is `prefix` or lies below it ("model.modes.0" is within "model.modes").
bool path_within(std::string_view path, std::string_view prefix);

}  // namespace chatterlab
