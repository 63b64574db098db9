#!/usr/bin/env bash
# Look at a rendered report the way a reader does: fit the demo (or use a given fit directory),
# render `hairfit report`, and screenshot index.html with headless Chromium (offline: the page
# must need no network). Not part of the test suite; needs `chromium` (Debian: apt-get install
# chromium). Usage: scripts/check_report.sh [FIT_DIR] [OUT.png]
set -euo pipefail
cd "$(dirname "$0")/.."
dir="${1:-}"
shot="${2:-target/report_screenshot.png}"
cargo build --release --quiet
if [[ -z "$dir" ]]; then
    dir="$(mktemp -d)/demo"
    ./target/release/hairfit demo --out "$dir" --starts 4 --no-progress >/dev/null
fi
./target/release/hairfit report "$dir"
browser="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
if [[ -z "$browser" ]]; then
    echo "check_report: no chromium found; open $dir/index.html yourself" >&2
    exit 1
fi
profile="$(mktemp -d)"
trap 'rm -rf "$profile"' EXIT
"$browser" --headless --no-sandbox --disable-gpu --disable-background-networking \
    --disable-component-update --disable-sync --no-first-run --user-data-dir="$profile" \
    --screenshot="$(realpath -m "$shot")" --window-size=1400,3000 \
    "file://$(realpath "$dir")/index.html" 2>/dev/null
echo "check_report: screenshot of $dir/index.html in $shot"
