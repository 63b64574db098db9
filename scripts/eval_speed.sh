#!/usr/bin/env bash
# One-thread speed of `hairfit eval`, CSV reading and writing included (not part of the test
# suite; the README's eval table was measured this way).
#
# Writes 1,000,000 random directions (`hairfit synth --rig sphere`, |θ| ≤ 85°, seeded) twice:
# as synth writes them (each float's shortest text, mostly 16–17 significant digits) and with
# six decimals (as a goniometer's files). Evaluates each with one and with three channels, RAYON_NUM_THREADS=1,
# output to /dev/null, RUNS times, the binaries interleaved run by run so that the machine's
# drift touches them alike, and prints the CPU time (user + sys) per case and binary: min,
# median, and rows per second at the median.
#
# Usage: scripts/eval_speed.sh [RUNS] [BINARY...]   (from the repository root)
#        With no BINARY, builds --release and times target/release/hairfit; give two builds to
#        compare them (e.g. a copy of the previous build and the new one).
# Env:   WORKDIR (default /tmp/hairfit-eval-speed), ROWS (default 1000000).
# Needs: awk, bash's `time`; disk ~250 MB while the directions are made, ~160 MB after.
set -euo pipefail

RUNS="${1:-20}"
shift || true
case "$RUNS" in
    '' | *[!0-9]* | 0)
        echo "eval_speed: RUNS must be a positive number of runs, not \`$RUNS\` (usage: scripts/eval_speed.sh [RUNS] [BINARY...])" >&2
        exit 2
        ;;
esac
bins=()
for bin in "$@"; do
    [ -x "$bin" ] || { echo "eval_speed: \`$bin\` is not an executable hairfit" >&2; exit 2; }
    # Absolute, as the runs happen in WORKDIR.
    bins+=("$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")")
done
set -- "${bins[@]+"${bins[@]}"}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
WORKDIR="${WORKDIR:-/tmp/hairfit-eval-speed}"
ROWS="${ROWS:-1000000}"
if [ "$#" -eq 0 ]; then
    (cd "$ROOT" && cargo build --release --quiet)
    set -- "$ROOT/target/release/hairfit"
fi
mkdir -p "$WORKDIR"
cd "$WORKDIR"

cat > p1.json <<'EOF'
{"eta": 1.55, "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}
EOF
if [ ! -s "angles17_$ROWS.csv" ] || [ ! -s "angles6_$ROWS.csv" ]; then
    # Directions from the tool itself; the angles keep synth's text, the values are dropped.
    "$1" synth --params p1.json --rig "sphere:n=$ROWS:max=85" --seed 7 --output synth.csv \
        > /dev/null 2> synth.log || { cat synth.log >&2; exit 1; }
    awk -F, '!/^#/ { print $1 "," $2 "," $3 "," $4 }' synth.csv > angles17.tmp
    awk -F, 'NR == 1 { print; next } { printf "%.6f,%.6f,%.6f,%.6f\n", $1, $2, $3, $4 }' \
        angles17.tmp > angles6.tmp
    mv angles17.tmp "angles17_$ROWS.csv"
    mv angles6.tmp "angles6_$ROWS.csv"
    rm -f synth.csv synth.truth.json synth.log
fi
cat > p3.json <<'EOF'
{"eta": 1.55, "sigma_a": [0.2, 0.4, 0.8], "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}
EOF

: > times.txt
TIMEFORMAT='%3U %3S'
for ((run = 0; run < RUNS; run++)); do
    for digits in 17 6; do
        for channels in 1 3; do
            for ((b = 1; b <= $#; b++)); do
                bin="${!b}"
                t=$( { time RAYON_NUM_THREADS=1 "$bin" eval --params "p$channels.json" \
                    --input "angles${digits}_$ROWS.csv" > /dev/null; } 2>&1 )
                echo "$digits $channels $b $t" >> times.txt
            done
        done
    done
done

echo "hairfit eval, $ROWS rows, one thread, CPU seconds (user + sys) over $RUNS interleaved runs"
for ((b = 1; b <= $#; b++)); do
    echo "binary $b: ${!b}"
done
for digits in 17 6; do
    for channels in 1 3; do
        for ((b = 1; b <= $#; b++)); do
            awk -v d="$digits" -v c="$channels" -v b="$b" '$1 == d && $2 == c && $3 == b { print $4 + $5 }' times.txt |
                sort -n |
                awk -v d="$digits" -v c="$channels" -v b="$b" -v rows="$ROWS" '
                    { t[NR] = $1 }
                    END {
                        m = (NR % 2) ? t[(NR + 1) / 2] : (t[NR / 2] + t[NR / 2 + 1]) / 2
                        form = (d == 17) ? "shortest text (16-17 digits)" : "six decimals                "
                        printf "%s, %s channel(s), binary %s: min %.3f s, median %.3f s = %.2f M rows/s\n",
                            form, c, b, t[1], m, rows / m / 1e6
                    }'
        done
    done
done
