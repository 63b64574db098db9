#!/usr/bin/env bash
# Install the real tools the export tests load hairfit's files in:
# - MaterialX's Python package (tests/export_materialx.rs, default suite: validate() with the
#   standard library);
# - with --with-bpy, Blender as a Python module (tests/export_blender.rs, ignored by default:
#   runs the exported script and renders with Cycles; a ~400 MB download).
# Both need Python 3.11 (the wheels pinned here are built for it).
set -euo pipefail
python=${PYTHON:-python3}
"$python" -m pip install --user materialx==1.39.5
if [[ "${1:-}" == "--with-bpy" ]]; then
    "$python" -m pip install --user bpy==5.0.1
fi
"$python" -c "import MaterialX as mx; print('MaterialX', mx.getVersionString())"
