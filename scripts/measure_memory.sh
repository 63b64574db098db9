#!/usr/bin/env bash
# Peak memory and wall time of a 10-million-sample fit (not part of the test suite).
#
# Synthesizes N samples (default 10,000,000) of the model, scale 2, 2% relative Gaussian noise:
# with `hairfit synth --rig sphere` when the binary has it (GEN=synth), else (GEN=eval) random
# angles from a small Python generator, S from `hairfit eval`, scale and noise with awk. Runs
# `hairfit fit` on them under `/usr/bin/time -v` and prints the peak RSS and wall time of the
# load + fit + outputs (and of the generation, for reference).
#
# Usage: scripts/measure_memory.sh [N]           (from the repository root; builds --release)
# Env:   WORKDIR (default /tmp/hairfit-mem-$N), KEEP=1 keeps the data and outputs,
#        FIT_ARGS extra `hairfit fit` options (default: the defaults), MODE cubic|exact,
#        GEN synth|eval (default: synth if available).
# Needs: /usr/bin/time (GNU time); python3 and awk for GEN=eval; disk ~3 GB per 10M samples
# (data + curves.csv).
set -euo pipefail

N="${1:-10000000}"
WORKDIR="${WORKDIR:-/tmp/hairfit-mem-$N}"
MODE="${MODE:-cubic}"
FIT_ARGS="${FIT_ARGS:-}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="$ROOT/target/release/hairfit"

command -v python3 >/dev/null || { echo "measure_memory: python3 is needed" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "measure_memory: GNU time (/usr/bin/time) is needed" >&2; exit 2; }

(cd "$ROOT" && cargo build --release --quiet)
mkdir -p "$WORKDIR"
cd "$WORKDIR"

# True parameters: MODEL.md's known-value set.
cat > truth.json <<'EOF'
{"eta": 1.55, "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15,
 "eccentricity": 0.9}
EOF

# peak_rss LOG -> "NNN MiB"; wall LOG -> "h:mm:ss"
peak_rss() { awk -F': ' '/Maximum resident set size/ {printf "%.0f MiB", $2/1024}' "$1"; }
wall() { awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$1"; }

GEN="${GEN:-$("$BIN" synth --help >/dev/null 2>&1 && echo synth || echo eval)}"
if [ "$GEN" = synth ]; then
    echo "== hairfit synth: $N samples, sphere rig |θ| ≤ 60°, scale 2, 2% relative noise"
    /usr/bin/time -v -o gen.time "$BIN" synth --params truth.json --rig "sphere:n=$N:max=60" \
        --noise relative:0.02 --seed 20261122 --scale 2 --mode "$MODE" --output data.csv
    ls -l data.csv
else
    echo "== generating $N angles (seeded)"
    python3 - "$N" > angles.csv <<'EOF'
import random, sys
n = int(sys.argv[1])
rng = random.Random(20261122)
out = sys.stdout
out.write("theta_i,phi_i,theta_r,phi_r,z\n")
u, g = rng.uniform, rng.gauss
buf = []
for i in range(n):
    # Goniometer-like coverage: inclinations within ±60°, azimuths all round, plus a noise draw.
    buf.append("%.5f,%.5f,%.5f,%.5f,%.6f\n" % (u(-60, 60), u(0, 360), u(-60, 60), u(-180, 180), g(0, 1)))
    if len(buf) == 100000:
        out.write("".join(buf)); buf = []
out.write("".join(buf))
EOF

    echo "== hairfit eval (model values)"
    /usr/bin/time -v -o gen.time "$BIN" eval --params truth.json --input angles.csv --output s.csv --mode "$MODE"
    rm -f angles.csv

    echo "== scale 2, 2% relative noise"
    # Columns of s.csv: theta_i,phi_i,theta_r,phi_r,z,s  ->  data with radiance and sigma.
    awk -F, 'NR == 1 {print "theta_i,phi_i,theta_r,phi_r,radiance,sigma"; next}
             {v = 2 * $6; printf "%s,%s,%s,%s,%.9g,%.9g\n", $1, $2, $3, $4, v * (1 + 0.02 * $5), 0.02 * v}' \
        s.csv > data.csv
    rm -f s.csv
    ls -l data.csv
fi

echo "== hairfit fit (load + fit + outputs) under /usr/bin/time -v"
rm -rf fit
# shellcheck disable=SC2086
/usr/bin/time -v -o fit.time "$BIN" fit data.csv --out fit --no-progress --mode "$MODE" $FIT_ARGS | tee fit.log

echo
echo "== results ($N samples, 1 channel, $(nproc) cores)"
echo "$GEN: peak RSS $(peak_rss gen.time), wall $(wall gen.time) (generation)"
echo "fit:   peak RSS $(peak_rss fit.time), wall $(wall fit.time)"
grep -E '^  stage|^wall time' fit.log || true
ls -l fit/

if [ "${KEEP:-0}" != 1 ]; then
    rm -rf data.csv data.truth.json fit
fi
