#!/usr/bin/env bash
# The add-on's tests once more under the oldest Blender its manifest admits
# (blender_version_min = "4.2.0": bpy 4.2.0 from PyPI, in its own virtual environment that
# tests/scripts/setup.sh made). The toolkit is the one the main tests use.
set -euo pipefail
cd "$(dirname "$0")/../.."

venv=build/venv-bpy42
if [ ! -x "$venv/bin/python" ]; then
  echo "addon_oldest_blender: $venv is missing; run tests/scripts/setup.sh" >&2
  exit 1
fi
toolkit=${HAPTICUT_TOOLKIT:-$(command -v hapticut || true)}
if [ -z "$toolkit" ]; then
  echo "addon_oldest_blender: the hapticut command is not on PATH" >&2
  exit 1
fi
version=$("$venv/bin/python" -c "import bpy; print(bpy.app.version_string)" 2>/dev/null | tail -n 1)
echo "== Blender add-on tests under bpy $version (the manifest's blender_version_min)"
HAPTICUT_TOOLKIT="$toolkit" "$venv/bin/python" -m pytest -q -p no:cacheprovider tests/python/addon
