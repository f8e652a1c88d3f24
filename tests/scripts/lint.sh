#!/usr/bin/env bash
# Formatters and linters on what the repository holds: clang-format and clang-tidy on the C++,
# ruff on the Python. clang-tidy runs one file per process, as many at a time as there are
# cores, and remembers a file that passed, keyed by the file, the headers it can include, the
# compile commands (the checkout's own path left out), the checks and clang-tidy's version:
# a second run, or a fresh clone on the same machine, checks only what changed. The passes
# are kept in HAPTICUT_LINT_CACHE (default: ~/.cache/hapticut/clang-tidy-passed, outside the
# checkout, like a compiler cache; an empty folder there checks every file).
set -euo pipefail
cd "$(dirname "$0")/../.."

mapfile -t cpp_files < <(git ls-files '*.cpp' '*.h')
echo "lint: clang-format (${#cpp_files[@]} files)"
clang-format --dry-run --Werror "${cpp_files[@]}"

mapfile -t tidy_files < <(git ls-files 'core/src/*.cpp' 'core/src/**/*.cpp' 'server/*.cpp' \
  'server/**/*.cpp' 'tools/evaluation/src/*.cpp')
passed=${HAPTICUT_LINT_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/hapticut/clang-tidy-passed}
mkdir -p "$passed"
# The compile commands' flags, whatever folder the checkout is in.
commands_key=$(sed "s|$PWD||g" build/main/compile_commands.json | sha1sum | cut -d' ' -f1)
# The headers a file can include: the engine's own, plus the servo's for the servo and the
# evaluation's for the evaluation (the engine includes neither).
headers_key() {
  {
    clang-tidy --version
    cat .clang-tidy
    echo "$commands_key"
    git ls-files -z 'core/*.h' "$@" | xargs -0 sha1sum
  } | sha1sum | cut -d' ' -f1
}
core_key=$(headers_key)
server_key=$(headers_key 'server/*.h')
evaluation_key=$(headers_key 'tools/evaluation/*.h')
todo=()
for file in "${tidy_files[@]}"; do
  case "$file" in
    server/*) shared_key=$server_key ;;
    tools/evaluation/*) shared_key=$evaluation_key ;;
    *) shared_key=$core_key ;;
  esac
  key=$( (echo "$shared_key" && sha1sum "$file") | sha1sum | cut -d' ' -f1)
  [ -f "$passed/$key" ] || todo+=("$file" "$key")
done
echo "lint: clang-tidy ($((${#todo[@]} / 2)) of ${#tidy_files[@]} files changed since they passed)"
# One file: its findings on stderr (then a failure), or its pass remembered.
tidy_one() {
  local output
  output=$(clang-tidy -p build/main --quiet "$1" 2>&1 || true)
  if grep -qE '(warning|error):' <<<"$output"; then
    grep -vE '^[0-9]+ warnings? generated\.$' <<<"$output" >&2
    return 1
  fi
  touch "$2"
}
export -f tidy_one
if [ ${#todo[@]} -gt 0 ]; then
  for ((i = 0; i < ${#todo[@]}; i += 2)); do
    printf '%s\0%s\0' "${todo[i]}" "$passed/${todo[i + 1]}"
  done | xargs -0 -n 2 -P "$(nproc)" bash -c 'tidy_one "$0" "$1"' || {
    echo "lint: clang-tidy found problems (above)" >&2
    exit 1
  }
fi

echo "lint: ruff"
python3 -m ruff check .
python3 -m ruff format --check .
