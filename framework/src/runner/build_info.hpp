#pragma once
// What produced a result: chatterlab version, compiler, dependency versions and the git commit
// the library was built from, for meta.json. Reproducing a number starts from these.
#include <string>

#include "chatterlab/params.hpp"

namespace chatterlab::runner {

// {"chatterlab": ..., "compiler": ..., "build": ..., "dependencies": {...}, "git_revision": ...}
Json build_info();

}  // namespace chatterlab::runner
