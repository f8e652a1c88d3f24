#!/usr/bin/env bash
# The demo: installs what it needs (as tests/run_all.sh does), then runs a
# 50-point blade stroke through the paper's 320-face sphere.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tests/scripts/setup.sh
python3 examples/demo_stroke.py "$@"
