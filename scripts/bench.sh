#!/usr/bin/env bash
# The waiting times users see, as the speed targets name them (docs/performance.md): wall and
# CPU seconds of whole commands, the best of RUNS runs each. Not part of the test suite.
#
#   compare   hairfit compare fits/demo/data.csv --models all       (target ≤ 5 s wall)
#   deon      hairfit demo --model deon                            (target ≤ 1 s wall)
#   frostbite hairfit demo --model frostbite
#   100k      hairfit fit on 100,000 random directions × 1 channel (target ≤ 0.3 s wall)
#             (synth --params data/true_1ch.json --rig sphere:n=100000:max=85
#              --noise relative:0.02 --seed 1, made once)
#
# Usage: scripts/bench.sh [RUNS] [BINARY]   (from the repository root; default 3 runs and
#        target/release/hairfit, built first). Env: WORKDIR (default /tmp/hairfit-bench).
# Prints one row per case: best wall, its CPU (user + sys), and every run's wall.
set -euo pipefail

RUNS="${1:-3}"
case "$RUNS" in
    '' | *[!0-9]* | 0)
        echo "bench: RUNS must be a positive number of runs, not \`$RUNS\`" >&2
        exit 2
        ;;
esac
root="$(pwd)"
if [ -n "${2:-}" ]; then
    bin="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"
else
    cargo build --release --quiet
    bin="$root/target/release/hairfit"
fi
[ -x "$bin" ] || { echo "bench: \`$bin\` is not an executable hairfit" >&2; exit 2; }
work="${WORKDIR:-/tmp/hairfit-bench}"
mkdir -p "$work"
sphere="$work/sphere_100k.csv"
[ -f "$sphere" ] || "$bin" synth --params "$root/data/true_1ch.json" \
    --rig sphere:n=100000:max=85 --noise relative:0.02 --seed 1 --output "$sphere" >/dev/null

# One case: NAME then the command (its --out is $work/out, removed before each run).
run_case() {
    local name="$1"
    shift
    local best="" best_cpu="" all=""
    for _ in $(seq "$RUNS"); do
        rm -rf "$work/out"
        local t
        /usr/bin/time -o "$work/time" -f "%e %U %S" "$@" --out "$work/out" --no-progress \
            >/dev/null 2>"$work/stderr" || {
            echo "bench: $name failed:" >&2
            tail -5 "$work/stderr" >&2
        }
        t=$(tail -1 "$work/time")
        local wall cpu
        wall=$(echo "$t" | awk '{print $1}')
        cpu=$(echo "$t" | awk '{printf "%.2f", $2 + $3}')
        all="$all $wall"
        if [ -z "$best" ] || awk "BEGIN{exit !($wall < $best)}"; then
            best="$wall"
            best_cpu="$cpu"
        fi
    done
    printf '%-10s %8s s wall %8s s CPU   runs:%s\n' "$name" "$best" "$best_cpu" "$all"
}

echo "hairfit bench: $(nproc) cores, $(uptime | sed 's/.*load average/load average/'), $RUNS runs each"
run_case compare "$bin" compare "$root/fits/demo/data.csv" --models all
run_case deon "$bin" demo --model deon
run_case frostbite "$bin" demo --model frostbite
run_case 100k "$bin" fit "$sphere"
