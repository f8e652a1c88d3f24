#!/usr/bin/env bash
# The test command (README.md): setup, lint, the C++ tests, the Python tests.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tests/scripts/setup.sh
bash tests/scripts/lint.sh
echo "== C++ tests (ctest)"
ctest --test-dir build/tests --output-on-failure -j 2
echo "== Python tests (pytest)"
python3 -m pytest -q -m "not slow" tests/python
