#!/usr/bin/env bash
# The SDK end to end, as a researcher uses it (CTest sdk.install_skeletons):
#   1. `cmake --install` into a temporary prefix; nothing installed names the source tree;
#   2. for each plugin kind: `chatterlab new-plugin`, configure the project against the installed
#      prefix only, build it, run its tests (ctest), validate and run its study with the
#      installed `chatterlab`;
#   3. the out-of-tree study kind is listed and runs its grid under mpirun with 2 ranks, giving
#      the same results.csv as one process;
#   4. the installed completion scripts complete plugin names; `cpack -G DEB` makes a package.
# Usage: install_skeletons.sh BUILD_DIR SOURCE_DIR MPIEXEC WORK_DIR
source "$(dirname "${BASH_SOURCE[0]}")/../cli/lib.sh"
build=$1 source_dir=$2 mpiexec=$3 work=$4
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix

# ---- 1. install
expect_exit 0 "$work/install" cmake --install "$build" --prefix "$prefix"
chatterlab=$prefix/bin/chatterlab
[ -x "$chatterlab" ] || { fail "no $chatterlab"; finish; }
for f in include/chatterlab/plugin_api.hpp include/chatterlab/version.hpp include/chatterlab/kit.hpp \
         share/bash-completion/completions/chatterlab share/zsh/vendor-completions/_chatterlab; do
  [ -f "$prefix/$f" ] || fail "not installed: $f"
done
config=$(find "$prefix" -name chatterlabConfig.cmake | head -1)
[ -n "$config" ] || fail "no chatterlabConfig.cmake installed"
[ -z "$(find "$prefix/include" -path '*framework/src*' -o -name '*.cpp' | head -1)" ] || fail "internal files installed"
# No installed file (binaries included) names the source or build tree.
leaks=$(grep -rl --binary-files=text -F "$source_dir" "$prefix" || true)
[ -z "$leaks" ] || fail "installed files name the source tree $source_dir: $leaks"
expect_exit 0 "$work/version" "$chatterlab" --version
grep -q "^chatterlab " "$work/version.out" || fail "installed chatterlab --version: $(cat "$work/version.out")"
# The installed command finds the installed shipped studies: init of a kind that reads a data
# file starts from one and names the installed copy of its data.
expect_exit 0 "$work/init_surface" "$chatterlab" init surface -o "$work/surface.toml"
grep -q "^file = \"$(readlink -f "$prefix")/share/chatterlab/studies/data/" "$work/surface.toml" ||
  fail "installed init surface does not name the installed data: $(grep '^file' "$work/surface.toml")"
expect_exit 0 "$work/validate_surface" "$chatterlab" validate "$work/surface.toml"

# Skeleton builds use ccache when there is one (CI's second run of this test is then quick).
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)

# ---- 2. one project per kind
for kind in model study analysis kinematics suppression; do
  name=my_$kind
  dir=$work/$name
  expect_exit 0 "$work/$name.new" "$chatterlab" new-plugin --kind "$kind" "$name" "$dir"
  for f in CMakeLists.txt README.md "$name.cpp" "${name}_test.cpp" study.toml; do
    [ -f "$dir/$f" ] || fail "$kind: new-plugin wrote no $f"
  done
  grep -q "find_package(chatterlab" "$dir/CMakeLists.txt" || fail "$kind: CMakeLists.txt does not use find_package(chatterlab)"
  grep -q "cmake --build build" "$dir/README.md" || fail "$kind: README.md has no build command"
  # Configured against the installed prefix only: the package registry and the system paths
  # cannot offer this build tree.
  expect_exit 0 "$work/$name.configure" cmake -S "$dir" -B "$dir/build" "${generator[@]}" "${launcher[@]}" \
    -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
  found=$(sed -n 's/^chatterlab_DIR:PATH=//p' "$dir/build/CMakeCache.txt")
  case "$found" in
    "$prefix"/*) ;;
    *) fail "$kind: find_package(chatterlab) found '$found', not the installed prefix" ;;
  esac
  expect_exit 0 "$work/$name.build" cmake --build "$dir/build" -j 2
  expect_exit 0 "$work/$name.ctest" ctest --test-dir "$dir/build" --output-on-failure
  grep -q "100% tests passed, 0 tests failed out of 2" "$work/$name.ctest.out" ||
    fail "$kind: the project's two tests did not both pass"
  [ -f "$dir/build/lib$name.so" ] || { fail "$kind: no lib$name.so"; continue; }
  expect_exit 0 "$work/$name.list" "$chatterlab" list --plugin "$dir/build/lib$name.so"
  grep -q "  $name  .*(from $dir/build/lib$name.so)" "$work/$name.list.out" || fail "$kind: $name not listed with its origin"
  expect_exit 0 "$work/$name.describe" "$chatterlab" describe "$name" --plugin "$dir/build/lib$name.so"
  expect_exit 0 "$work/$name.validate" "$chatterlab" validate "$dir/study.toml"
  expect_exit 0 "$work/$name.run" "$chatterlab" run "$dir/study.toml" --out "$dir/out" --threads 2
  [ -s "$dir/out/results.csv" ] || fail "$kind: the study wrote no results.csv"
done

# ---- 3. the out-of-tree study kind: listed as a study kind, and its grid under MPI
library=$work/my_study/build/libmy_study.so
"$chatterlab" list --plugin "$library" | grep -q "^study kind *my_study  " || fail "my_study is not listed as a study kind"
if [ -f "$work/my_study/out/results.csv" ]; then
  [ "$(csv_column "$work/my_study/out/results.csv" status | grep -c '^ok$')" -eq 6 ] ||
    fail "my_study: not all 6 grid points ok"
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
  expect_exit 0 "$work/my_study.mpi" "$mpiexec" -np 2 --oversubscribe "$chatterlab" run "$work/my_study/study.toml" \
    --out "$work/my_study/out_mpi" --threads 1
  grep -q '"ranks": 2' "$work/my_study/out_mpi/meta.json" || fail "my_study under mpirun did not run on 2 ranks"
  cmp -s "$work/my_study/out/results.csv" "$work/my_study/out_mpi/results.csv" ||
    fail "my_study: results.csv of 2 MPI ranks differs from one process"
fi

# ---- 4. completion and the Debian package
completions=$(bash -c 'source "$1"; COMP_WORDS=("$2" describe my_m --plugin "$3"); COMP_CWORD=2; _chatterlab; printf "%s\n" "${COMPREPLY[@]}"' \
  _ "$prefix/share/bash-completion/completions/chatterlab" "$chatterlab" "$work/my_model/build/libmy_model.so")
[ "$completions" = my_model ] || fail "bash completion of 'describe my_m' gave '$completions'"
kinds=$(bash -c 'source "$1"; COMP_WORDS=("$2" init stab); COMP_CWORD=2; _chatterlab; printf "%s\n" "${COMPREPLY[@]}"' \
  _ "$prefix/share/bash-completion/completions/chatterlab" "$chatterlab")
[ "$kinds" = "$(printf 'stability_lobes\nstability_map')" ] || fail "bash completion of 'init stab' gave '$kinds'"
cmp -s "$prefix/share/zsh/vendor-completions/_chatterlab" <("$chatterlab" completion zsh) ||
  fail "installed zsh completion differs from 'chatterlab completion zsh'"

expect_exit 0 "$work/cpack" cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/package"
deb=$(find "$work/package" -maxdepth 1 -name 'chatterlab_*.deb' | head -1)
if [ -z "$deb" ]; then
  fail "cpack made no chatterlab_*.deb"
else
  dpkg-deb -c "$deb" > "$work/deb.contents"
  for f in ./usr/bin/chatterlab ./usr/include/chatterlab/plugin_api.hpp chatterlabConfig.cmake libchatterlab.so; do
    grep -q -- "$f" "$work/deb.contents" || fail "the .deb has no $f"
  done
  dpkg-deb -f "$deb" Depends | grep -q "libfftw3" || fail "the .deb's Depends do not name its libraries: $(dpkg-deb -f "$deb" Depends)"
fi
finish
