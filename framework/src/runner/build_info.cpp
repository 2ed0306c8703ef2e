#include "runner/build_info.hpp"

#include <fftw3.h>
#include <fmt/format.h>
#include <mpi.h>
#include <sundials/sundials_config.h>
#include <toml++/impl/version.h>

#include <Eigen/Core>
#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

namespace chatterlab::runner {

namespace {

namespace fs = std::filesystem;

std::string first_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  return line;
}

bool is_commit_id(const std::string& text) {
  return text.size() == 40 && std::all_of(text.begin(), text.end(), [](char c) {
           return std::isxdigit(static_cast<unsigned char>(c)) != 0;
         });
}

// A branch ref: loose file first (newest), then packed-refs.
std::string resolve_ref(const fs::path& git_dir, const fs::path& common_dir,
                        const std::string& ref) {
  for (const fs::path& dir : {git_dir, common_dir}) {
    std::string id = first_line(dir / ref);
    if (is_commit_id(id)) return id;
  }
  std::ifstream packed(common_dir / "packed-refs");
  std::string line;
  while (std::getline(packed, line)) {
    std::istringstream fields(line);
    std::string id, name;
    if (fields >> id >> name && name == ref && is_commit_id(id)) return id;
  }
  return "unknown";
}

std::string compiler() {
#if defined(__clang__)
  return fmt::format("clang {}", __clang_version__);
#elif defined(__GNUC__)
  return fmt::format("GCC {}", __VERSION__);
#else
  return "unknown";
#endif
}

std::string mpi_library() {
#if defined(OMPI_MAJOR_VERSION)
  return fmt::format("Open MPI {}.{}.{}", OMPI_MAJOR_VERSION, OMPI_MINOR_VERSION,
                     OMPI_RELEASE_VERSION);
#else
  return fmt::format("MPI {}.{}", MPI_VERSION, MPI_SUBVERSION);
#endif
}

}  // namespace

std::string git_revision(const fs::path& source_dir) {
  fs::path git_dir = source_dir / ".git";
  std::error_code ec;
  if (fs::is_regular_file(git_dir, ec)) {  // worktree or submodule: "gitdir: <path>"
    std::string line = first_line(git_dir);
    if (line.rfind("gitdir: ", 0) != 0) return "unknown";
    fs::path target = line.substr(8);
    git_dir = target.is_absolute() ? target : source_dir / target;
  }
  if (!fs::is_directory(git_dir, ec)) return "unknown";
  fs::path common_dir = git_dir;
  if (std::string common = first_line(git_dir / "commondir"); !common.empty())
    common_dir = fs::path(common).is_absolute() ? fs::path(common) : git_dir / common;
  std::string head = first_line(git_dir / "HEAD");
  if (is_commit_id(head)) return head;  // detached HEAD
  if (head.rfind("ref: ", 0) == 0) return resolve_ref(git_dir, common_dir, head.substr(5));
  return "unknown";
}

Json build_info() {
  Json deps = Json::object();
  deps["sundials"] = SUNDIALS_VERSION;
  deps["eigen"] =
      fmt::format("{}.{}.{}", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
  deps["fmt"] =
      fmt::format("{}.{}.{}", FMT_VERSION / 10000, FMT_VERSION / 100 % 100, FMT_VERSION % 100);
  deps["tomlplusplus"] = fmt::format("{}.{}.{}", TOML_LIB_MAJOR, TOML_LIB_MINOR, TOML_LIB_PATCH);
  deps["nlohmann_json"] = fmt::format("{}.{}.{}", NLOHMANN_JSON_VERSION_MAJOR,
                                      NLOHMANN_JSON_VERSION_MINOR, NLOHMANN_JSON_VERSION_PATCH);
  deps["fftw"] = std::string(fftw_version);
  deps["mpi"] = mpi_library();
  deps["openmp"] = fmt::format("{} (_OPENMP)", _OPENMP);
  Json info = Json::object();
  info["chatterlab"] = CHATTERLAB_VERSION;
  info["compiler"] = compiler();
#if defined(NDEBUG)
  info["assertions"] = false;
#else
  info["assertions"] = true;
#endif
  info["dependencies"] = std::move(deps);
  info["source_dir"] = CHATTERLAB_SOURCE_DIR;
  info["git_revision"] = git_revision(CHATTERLAB_SOURCE_DIR);
  return info;
}

}  // namespace chatterlab::runner
