#!/usr/bin/env bash
# chatterlab quick start. Idempotent: installs only what is missing (Debian 12 packages), then
#   quickstart.sh run   builds Release and runs the default study (studies/default.toml)
#   quickstart.sh test  builds with warnings as errors and runs the whole test suite through CTest
#                       (Release, then the ASan+UBSan preset)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
mode="${1:-}"
case "$mode" in
  run|test) ;;
  *) echo "usage: $0 run|test" >&2; exit 2 ;;
esac

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libsundials-dev libfftw3-dev libopenmpi-dev openmpi-bin
  libhdf5-openmpi-dev libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libfmt-dev libmuparser-dev libnanoflann-dev
  libgtest-dev libgmock-dev libbenchmark-dev gnuplot-nox
  file  # cpack's Debian generator (the sdk test packages chatterlab) inspects binaries with it
  hdf5-tools  # h5dump/h5ls: tests/cli/hdf5_output.cli.sh reads results.h5 with them
  # The Python module (docs/python.md), built for Debian's /usr/bin/python3, and its tests
  python3-dev pybind11-dev python3-numpy python3-pandas python3-matplotlib python3-pytest
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "chatterlab: installing missing Debian packages: ${missing[*]}" >&2
  if [ "$(id -u)" -eq 0 ]; then
    as_root=()
  elif command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    echo "chatterlab: these packages are missing and I am neither root nor able to use sudo." >&2
    echo "Ask an administrator to run:" >&2
    echo "  apt-get update && apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  "${as_root[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Debian's SUNDIALS is compiled without optimisation: build the same source package optimised
# into build/deps/sundials (used by CMakeLists.txt when present; else the packaged one).
"$root/framework/scripts/optimised_sundials.sh"

# OpenMPI refuses to start as root unless told it is deliberate (the MPI tests run mpirun).
if [ "$(id -u)" -eq 0 ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi

cd "$root"
jobs="$(nproc)"
if [ "$mode" = run ]; then
  cmake --preset release >/dev/null
  cmake --build --preset release -j "$jobs"
  ./build/release/framework/chatterlab run studies/default.toml --out out/default
  echo "chatterlab: default study written to $root/out/default (results.csv, summary.json, lobe_diagram.png/.svg)"
  # The Python module, self-contained (its own libchatterlab), into /usr/bin/python3's user
  # site-packages: `/usr/bin/python3 -c "import chatterlab"` works from any directory.
  if [ -d build/release/python/chatterlab ]; then
    user_site="$(/usr/bin/python3 -m site --user-site)"
    cmake --install build/release --component python --prefix "$user_site" >/dev/null
    echo "chatterlab: Python module installed in $user_site/chatterlab (docs/python.md)"
  fi
else
  for preset in ci asan; do
    echo "chatterlab: === test preset '$preset' ===" >&2
    cmake --preset "$preset" >/dev/null
    cmake --build --preset "$preset" -j "$jobs"
    # Tests labelled `accuracy` (long known-answer suites) and `regression` (every shipped study
    # against its references) run once, optimised; under the sanitizers they would take most of
    # CI's time without exercising code the shorter tests of the same routines do not reach.
    # The Python tests (`python`) run once too: the interpreter itself is not instrumented, and
    # the C++ they call is the code the sanitized C++ tests cover.
    if [ "$preset" = asan ]; then
      ctest --preset "$preset" -j "$jobs" -LE "accuracy|regression|python"
    else
      ctest --preset "$preset" -j "$jobs"
    fi
  done
fi
