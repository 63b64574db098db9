#!/usr/bin/env bash
# Install the real tools the export tests load hairfit's files in, into target/test-venv (the
# venv scripts/test uses; nothing is installed outside the repository):
# - MaterialX's Python package (tests/files/export_materialx.rs, default suite; scripts/test installs
#   it too);
# - with --with-bpy, Blender as a Python module (tests/files/export_blender.rs, ignored by default:
#   runs the exported script and renders with Cycles; a ~400 MB download). Then run
#   `PATH=$PWD/target/test-venv/bin:$PATH cargo test --release --test files export_blender:: -- --ignored`.
# Both need Python 3.11 (the wheels pinned here are built for it).
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/test-venv
export PYTHONNOUSERSITE=1
[[ -x "$venv/bin/python3" ]] || python3 -m venv "$venv"
"$venv/bin/python3" -m pip install --quiet --disable-pip-version-check materialx==1.39.5
if [[ "${1:-}" == "--with-bpy" ]]; then
    "$venv/bin/python3" -m pip install --quiet --disable-pip-version-check bpy==5.0.1
fi
"$venv/bin/python3" -c "import MaterialX as mx; print('MaterialX', mx.getVersionString())"
