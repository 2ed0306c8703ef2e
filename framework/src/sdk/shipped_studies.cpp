// The studies shipped with chatterlab (chatterlab/study_template.hpp), found relative to this
// library: installed, libchatterlab is <prefix>/<libdir>/libchatterlab.so and the studies are in
// <prefix>/<datadir>/chatterlab/studies; the build tree mirrors that layout with a link to the
// source tree's studies/ (framework/CMakeLists.txt), so nothing compiled in names a tree.
#include <dlfcn.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/study_template.hpp"
#include "study/toml_reader.hpp"

#ifndef CHATTERLAB_DATA_FROM_LIBDIR
#error "CHATTERLAB_DATA_FROM_LIBDIR (the install datadir relative to the libdir) is set by framework/CMakeLists.txt"
#endif

namespace chatterlab {

namespace fs = std::filesystem;

std::optional<fs::path> shipped_studies_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&shipped_studies_dir), &info) == 0 || info.dli_fname == nullptr)
    return std::nullopt;
  std::error_code ec;
  const fs::path library = fs::canonical(info.dli_fname, ec);
  if (ec) return std::nullopt;
  // The installed layout, then the library's private directory (the self-contained copy the
  // Python package installs: python/CMakeLists.txt).
  for (const fs::path& dir : {library.parent_path() / CHATTERLAB_DATA_FROM_LIBDIR / "chatterlab" / "studies",
                              library.parent_path() / "chatterlab" / "studies"}) {
    if (!fs::is_directory(dir, ec)) continue;
    fs::path resolved = fs::canonical(dir, ec);  // data paths in init's output name the real files
    if (!ec) return resolved;
  }
  return std::nullopt;
}

std::vector<ShippedStudy> shipped_studies() {
  std::vector<ShippedStudy> out;
  const auto dir = shipped_studies_dir();
  if (!dir) return out;
  std::error_code ec;
  for (const auto& item : fs::directory_iterator(*dir, ec)) {
    if (item.path().extension() != ".toml" || !item.is_regular_file(ec)) continue;
    try {
      const TomlDocument toml = read_toml_study(item.path());
      const Json& study = toml.document.value("study", Json::object());
      if (study.contains("kind") && study["kind"].is_string())
        out.push_back({item.path(), study["kind"].get<std::string>()});
    } catch (const std::exception&) {
      // Not a study this chatterlab can read: not an example of anything.
    }
  }
  std::sort(out.begin(), out.end(), [](const ShippedStudy& a, const ShippedStudy& b) { return a.file < b.file; });
  return out;
}

}  // namespace chatterlab
