#!/usr/bin/env bash
# Builds an optimised copy of Debian 12's own SUNDIALS into build/deps/sundials, which the
# top-level CMakeLists.txt uses when present; without it the build uses the packaged library.
#
# Why: Debian's libsundials 6.4.1+dfsg1-3 is compiled without optimisation. Its debian/rules sets
# -DCMAKE_C_FLAGS=-fcommon, which replaces dpkg's CFLAGS (-O2) rather than adding to them, so
# every SUNDIALS routine runs at -O0 (every value spilled to the stack; checked by disassembly).
# The dynamics engine spends a third of its time inside ARKODE's step logic, which runs at about
# half speed that way (docs/performance.md, "Dynamics engine"). This script takes the very same
# Debian source package (same version as the installed libsundials-dev, Debian's patches applied)
# and builds only what chatterlab links (ARKODE, CVODE, serial vectors) optimised (CMake Release:
# -O3 -DNDEBUG, no -march flags, so the arithmetic is the same IEEE code): about 15 MB of
# download and 30 s of compilation, once per checkout.
#
# It never fails the caller: without network access to Debian's source archive (or on any other
# error) it says so and the build falls back to the packaged SUNDIALS, which gives the same
# results, only slower.
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
prefix="$root/build/deps/sundials"
work="$root/build/deps/sundials-source"

version="$(dpkg-query -W -f='${Version}' libsundials-dev 2>/dev/null)" || version=""
if [ -z "$version" ]; then
  echo "chatterlab: libsundials-dev is not installed; skipping the optimised SUNDIALS build" >&2
  exit 0
fi
stamp="$prefix/.built-from-$version"
if [ -f "$stamp" ]; then
  exit 0
fi

fallback() {
  echo "chatterlab: WARNING: could not build the optimised SUNDIALS ($1); using Debian's" \
       "packaged library (same results, the dynamics engine is slower). Log: $work/log.txt" >&2
  rm -rf "$prefix"
  exit 0
}

rm -rf "$work" "$prefix"
mkdir -p "$work/apt/lists/partial" "$work/apt/cache/archives/partial" "$work/apt/sources.d" || fallback "mkdir"
log="$work/log.txt"

# A private apt configuration with deb-src twins of the system's Debian sources, so the system's
# own apt setup is left untouched.
for f in /etc/apt/sources.list.d/*.sources; do
  [ -f "$f" ] && sed 's/^Types:.*/Types: deb-src/' "$f" > "$work/apt/sources.d/$(basename "$f")"
done
for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
  [ -f "$f" ] && sed -n 's/^deb \(.*\)$/deb-src \1/p' "$f" > "$work/apt/sources.d/$(basename "$f")"
done
apt_options=(-o "Dir::Etc::sourcelist=/dev/null" -o "Dir::Etc::sourceparts=$work/apt/sources.d"
             -o "Dir::State::Lists=$work/apt/lists" -o "Dir::Cache=$work/apt/cache"
             -o "APT::Sandbox::User=root" -o "Acquire::Retries=1" -o "Acquire::http::Timeout=30")

echo "chatterlab: building an optimised SUNDIALS $version from Debian's source package" \
     "(the packaged one is compiled without optimisation; see $0)" >&2
cd "$work" || fallback "cd"
apt-get "${apt_options[@]}" -q update >"$log" 2>&1 || fallback "apt-get update of the source index"
apt-get "${apt_options[@]}" source --download-only "sundials=$version" >>"$log" 2>&1 ||
  fallback "apt-get source sundials=$version"
dpkg-source --no-check -x ./*.dsc src >>"$log" 2>&1 || fallback "dpkg-source -x"
cmake -S src -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS="-fcommon" \
  -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib \
  -DBUILD_SHARED_LIBS=ON -DBUILD_STATIC_LIBS=OFF \
  -DBUILD_ARKODE=ON -DBUILD_CVODE=ON -DBUILD_CVODES=OFF -DBUILD_IDA=OFF -DBUILD_IDAS=OFF \
  -DBUILD_KINSOL=OFF -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF \
  >>"$log" 2>&1 || fallback "cmake configure"
cmake --build build -j "$(nproc)" >>"$log" 2>&1 || fallback "compilation"
cmake --install build >>"$log" 2>&1 || fallback "install"
touch "$stamp"
rm -rf "$work/build" "$work/src" "$work/apt" "$work"/*.tar.* "$work"/*.dsc
echo "chatterlab: optimised SUNDIALS $version installed in $prefix" >&2
