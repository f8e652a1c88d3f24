#!/usr/bin/env bash
# The Blender demo (README): installs what it needs on a fresh machine (tests/scripts/setup.sh:
# the toolkit with its servo, bpy), then builds, simulates, bakes and renders the finger cut
# into build/blender-demo/ (frames/, contact_sheet.png, blender_demo.blend).
# --setup runs the installation even when the toolkit and bpy are already there.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = "--setup" ]; then
  shift
  bash tests/scripts/setup.sh
elif ! python3 -c "import bpy, hapticut; hapticut.servo_path()" >/dev/null 2>&1; then
  bash tests/scripts/setup.sh
fi
python3 examples/blender_demo.py "$@"
