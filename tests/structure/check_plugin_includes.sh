#!/usr/bin/env bash
# Plugins meet through the framework's public headers and typed capabilities, never through each
# other's code (docs/architecture.md, "Layout"). For every file under plugins/:
#   plugins/<kind>/<name>/...  may include chatterlab/... (the public SDK), files of its own folder
#                              and plugins/shared/<library>/...;
#   plugins/shared/<lib>/...   may include chatterlab/... and plugins/shared/...;
# and no file includes framework internals (framework/src). Test files follow the same rule, except
# that they may also use the test helpers under tests/ (unit/...).
# Usage: check_plugin_includes.sh SOURCE_DIR
set -u
root=$1
cd "$root/plugins" || exit 2
violations=0
while IFS= read -r file; do
  dir=$(dirname "$file")
  kind=${dir%%/*}
  # Quoted includes only: system and third-party headers use <...>.
  while IFS= read -r include; do
    case "$include" in
      chatterlab/*) continue ;;
      shared/*) continue ;;
    esac
    if [ "$kind" != shared ]; then
      own=${dir#./}
      [ "$(dirname "$include")" = "$own" ] && continue
    fi
    case "$file" in
      *_test.cpp) case "$include" in unit/*) continue ;; esac ;;
    esac
    echo "plugins/$file includes \"$include\": not its own folder, not plugins/shared/, not chatterlab/" >&2
    violations=$((violations + 1))
  done < <(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$file")
done < <(find . -type f \( -name '*.cpp' -o -name '*.hpp' \) | sed 's|^\./||' | sort)
if [ "$violations" -gt 0 ]; then
  echo "$violations include(s) cross plugin boundaries" >&2
  exit 1
fi
echo "no plugin includes another plugin's or the framework's internal headers"
