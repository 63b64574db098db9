#!/usr/bin/env bash
# Rewrite the outputs kept in git (fits/README.md): the demo fit and its report, the exports of
# it, and the cost ledgers. Run after a change to the model, the fit, the report or an export,
# then review `git diff --stat fits/` and commit. Commands write to untracked directories by
# default; only this script writes the committed ones. The ledgers are timings of the machine
# that runs it (docs/performance.md names the one they were measured on).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked
hairfit=target/release/hairfit

$hairfit demo --no-progress --out fits/demo
for to in pbrt:demo.pbrt blender:demo.py materialx:demo.mtlx unreal:demo_unreal.json unity:demo_unity.json; do
    $hairfit export fits/demo --to "${to%%:*}" --output "fits/export/${to#*:}"
done
# The Chiang fit of the same data is exported, not kept in git (7 MB; fits/demo_chiang is
# ignored), and named in the exports' headers.
$hairfit fit fits/demo/data.csv --model chiang --no-progress --out fits/demo_chiang
for to in pbrt:demo_chiang.pbrt blender:demo_chiang.py materialx:demo_chiang.mtlx; do
    $hairfit export fits/demo_chiang --to "${to%%:*}" --output "fits/export/${to#*:}"
done
$hairfit cost --out fits/cost
$hairfit cost --model chiang --out fits/cost_chiang
# fits/export/demo_blender.png needs Blender: scripts/install-test-tools.sh --with-bpy, then
# cargo test --release --test files export_blender:: -- --ignored (docs/export.md).
git status --short fits/
