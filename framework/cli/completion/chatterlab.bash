# bash completion for chatterlab: commands, options, plugin and study-kind names (asked of
# `chatterlab list`, with the --plugin libraries already on the line), study files and libraries.
# Installed as share/bash-completion/completions/chatterlab; `chatterlab completion bash` prints it
# (e.g. `source <(chatterlab completion bash)` for a chatterlab that is not installed).

# Names of one kind ("model", "study kind", ...; all kinds when empty) from `chatterlab list`,
# whose lines are "<kind>  <name>  <description>" in columns separated by two or more spaces.
_chatterlab_names() {
  local kind="$1" i plugins=()
  for ((i = 1; i < ${#COMP_WORDS[@]} - 1; i++)); do
    [[ ${COMP_WORDS[i]} == --plugin ]] && plugins+=(--plugin "${COMP_WORDS[i + 1]}")
  done
  "${COMP_WORDS[0]}" list "${plugins[@]}" 2>/dev/null |
    awk -F '  +' -v kind="$kind" 'kind == "" || $1 == kind { print $2 }'
}

_chatterlab() {
  local cur="${COMP_WORDS[COMP_CWORD]}" prev="${COMP_WORDS[COMP_CWORD - 1]}"
  local commands="list describe validate run merge new-plugin check-plugin init completion"
  COMPREPLY=()
  if ((COMP_CWORD == 1)); then
    mapfile -t COMPREPLY < <(compgen -W "$commands --help --version" -- "$cur")
    return
  fi
  case "$prev" in
    --plugin) compopt -o filenames; mapfile -t COMPREPLY < <(compgen -f -X '!*.so' -- "$cur"; compgen -d -- "$cur"); return ;;
    --out | -o | --output) compopt -o filenames; mapfile -t COMPREPLY < <(compgen -f -- "$cur"); return ;;
    --kind) mapfile -t COMPREPLY < <(compgen -W "model study analysis kinematics suppression" -- "$cur"); return ;;
    --model) mapfile -t COMPREPLY < <(compgen -W "$(_chatterlab_names model)" -- "$cur"); return ;;
    --machine) mapfile -t COMPREPLY < <(compgen -W "$(_chatterlab_names kinematics)" -- "$cur"); return ;;
    --suppression) mapfile -t COMPREPLY < <(compgen -W "$(_chatterlab_names suppression)" -- "$cur"); return ;;
    --threads | --name | --example | --point-timeout | --shard) return ;;
  esac
  local options
  case "${COMP_WORDS[1]}" in
    list) options="--plugin --help" ;;
    describe) options="--plugin --help $(_chatterlab_names '')" ;;
    validate) options="--plugin --allow-large --help" ;;
    run) options="--plugin --allow-large --out --threads --resume --retry-failed --isolate --point-timeout --progress --no-progress --shard --help" ;;
    merge) options="--threads --no-progress --help" ;;
    new-plugin) options="--kind --help" ;;
    check-plugin) options="--quick --threads --help" ;;
    init) options="--output --force --name --example --model --machine --suppression --plugin --help $(_chatterlab_names 'study kind')" ;;
    completion) options="bash zsh" ;;
  esac
  if [[ $cur == -* || ${COMP_WORDS[1]} =~ ^(list|describe|init|completion)$ ]]; then
    mapfile -t COMPREPLY < <(compgen -W "$options" -- "$cur")
    return
  fi
  # Positional files: study files for validate/run, libraries for check-plugin, a directory for new-plugin.
  compopt -o filenames
  case "${COMP_WORDS[1]}" in
    validate | run) mapfile -t COMPREPLY < <(compgen -f -X '!*.toml' -- "$cur"; compgen -d -- "$cur") ;;
    check-plugin) mapfile -t COMPREPLY < <(compgen -f -X '!*.so' -- "$cur"; compgen -d -- "$cur") ;;
    merge) mapfile -t COMPREPLY < <(compgen -d -- "$cur") ;;
    *) mapfile -t COMPREPLY < <(compgen -f -- "$cur") ;;
  esac
}

complete -F _chatterlab chatterlab
