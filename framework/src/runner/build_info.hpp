#pragma once
// What produced a result: chatterlab version, compiler, dependency versions and the git revision
// of the source tree, for meta.json. Reproducing a number starts from these.
#include <filesystem>
#include <string>

#include "chatterlab/params.hpp"

namespace chatterlab::runner {

// {"chatterlab": ..., "compiler": ..., "build": ..., "dependencies": {...}, "git_revision": ...}
Json build_info();

// HEAD commit of the git checkout at `source_dir`, read from the .git files (no `git` process:
// forking inside an MPI rank is unsafe with some interconnects), or "unknown".
std::string git_revision(const std::filesystem::path& source_dir);

}  // namespace chatterlab::runner
