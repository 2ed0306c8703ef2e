#include "runner/build_info.hpp"

#include "build_revision.hpp"  // generated: CHATTERLAB_GIT_REVISION
#include "chatterlab/version.hpp"

#include <fftw3.h>
#include <fmt/format.h>
#include <mpi.h>
#include <sundials/sundials_config.h>
#include <toml++/impl/version.h>

#include <Eigen/Core>

namespace chatterlab::runner {

namespace {

std::string mpi_library() {
#if defined(OMPI_MAJOR_VERSION)
  return fmt::format("Open MPI {}.{}.{}", OMPI_MAJOR_VERSION, OMPI_MINOR_VERSION,
                     OMPI_RELEASE_VERSION);
#else
  return fmt::format("MPI {}.{}", MPI_VERSION, MPI_SUBVERSION);
#endif
}

}  // namespace

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
  info["compiler"] = CHATTERLAB_COMPILER;
#if defined(NDEBUG)
  info["assertions"] = false;
#else
  info["assertions"] = true;
#endif
  info["dependencies"] = std::move(deps);
  // Recorded at build time (cmake/build_revision.cmake): an installed chatterlab has no source
  // tree to look at, and reading one at run time would name a commit the binary may not be.
  info["git_revision"] = CHATTERLAB_GIT_REVISION;
  return info;
}

}  // namespace chatterlab::runner
