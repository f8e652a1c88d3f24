#!/usr/bin/env bash
# The demo (README): a knife through a finger in Blender. Installs only what the product needs
# (tools/install_lib.sh: the toolkit with scene building and its servo, and bpy; each step
# skipped when already done), then runs examples/blender_demo.py: the finger tetrahedralized
# by the add-on, the stroke run through the servo, baked and rendered with Cycles on the CPU.
# It ends with the contact sheet's path and a summary (forces, states, each stage's time).
#   --quick       3 frames at 8 samples;   --no-render   no pictures at all;
#   any other option goes to examples/blender_demo.py (--help lists them).
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/install_lib.sh

began=$SECONDS
install_apt "${PRODUCT_APT_PACKAGES[@]}"
install_toolkit
install_bpy 5.0.1
echo "demo: install $((SECONDS - began)) s"
python3 examples/blender_demo.py "$@"
