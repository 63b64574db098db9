#!/bin/sh
# The study in docs/trace.md ("What each family recovers"): four traced fibres, every family
# fitted to each by `hairfit compare --models all`. Usage: scripts/trace_study.sh [OUTDIR] [RAYS]
# (defaults: trace-study, 2000000 rays per incidence). Prints one row per fibre and family.
set -eu
out=${1:-trace-study}
rays=${2:-2000000}
bin=${HAIRFIT:-target/release/hairfit}
rig='longitudinal:incidences=15,30,45:phi=0,30,60,90,120,150,180:steps=35:max=75'
mkdir -p "$out"
fiber() { printf '%s\n' "$2" > "$out/$1.json"; }
fiber brown '{"eta": 1.55, "sigma_a": 0.5, "cuticle_tilt_deg": -3, "roughness_deg": 6}'
fiber blond '{"eta": 1.55, "sigma_a": 0.1, "cuticle_tilt_deg": -3, "roughness_deg": 6}'
fiber dark '{"eta": 1.55, "sigma_a": 2.0, "cuticle_tilt_deg": -3, "roughness_deg": 6}'
fiber elliptical '{"eta": 1.55, "sigma_a": 0.5, "cuticle_tilt_deg": -3, "roughness_deg": 6, "eccentricity": 0.85}'
for f in brown blond dark elliptical; do
    "$bin" trace --fiber "$out/$f.json" --rig "$rig" --rays "$rays" --seed 1 --output "$out/$f.csv"
    "$bin" compare "$out/$f.csv" --models all --out "$out/$f-compare" >/dev/null 2>&1 || true
done
python3 - "$out" <<'PY'
import json, sys, os
out = sys.argv[1]
skip = {"model", "delta_eta_prime", "delta_h_m"}
def fmt(v):
    return ("%.3g" % v) if isinstance(v, float) else str(v)
print("| fibre | family | parameters | verdict | reduced χ² | rank |")
print("|---|---|---|---|---|---|")
for f in ["brown", "blond", "dark", "elliptical"]:
    path = os.path.join(out, f + "-compare", "compare.json")
    if not os.path.exists(path):
        print("|", f, "| no compare.json | | | | |"); continue
    c = json.load(open(path))
    rank = {r["family"]: r["rank"] for r in c["ranking"]}
    for m in c["models"]:
        p = ", ".join(k + " " + fmt(v) for k, v in m["params"].items() if k not in skip)
        print(f"| {f} | {m['family']} | {p} | {m['verdict']} | {m['reduced_chi2']:.3g} | {rank.get(m['family'], '')} |")
PY
