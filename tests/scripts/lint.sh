#!/usr/bin/env bash
# Formatters and linters: clang-format and clang-tidy on the C++, ruff on the Python.
set -euo pipefail
cd "$(dirname "$0")/../.."

mapfile -t cpp_files < <(git ls-files '*.cpp' '*.h')
echo "lint: clang-format (${#cpp_files[@]} files)"
clang-format --dry-run --Werror "${cpp_files[@]}"

echo "lint: clang-tidy (core/src, server, tools/evaluation/src)"
mapfile -t tidy_files < <(git ls-files 'core/src/*.cpp' 'core/src/**/*.cpp' 'server/*.cpp' 'server/**/*.cpp' \
  'tools/evaluation/src/*.cpp')
tidy_output=$(clang-tidy -p build/tests --quiet "${tidy_files[@]}" 2>&1 || true)
if grep -qE '(warning|error):' <<<"$tidy_output"; then
  grep -vE '^[0-9]+ warnings? generated\.$' <<<"$tidy_output" >&2
  echo "lint: clang-tidy found problems (above)" >&2
  exit 1
fi

echo "lint: ruff"
python3 -m ruff check .
python3 -m ruff format --check .
