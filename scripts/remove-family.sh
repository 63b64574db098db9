#!/usr/bin/env bash
# A family is one folder plus its two lines in src/families/ (its `pub mod` line in mod.rs and
# its line in registry.rs's `registry!` list): for each family, in a scratch copy of the tree,
# delete exactly those and check that the library and the Python package still compile.
# Nothing else may name the family (CONTRIBUTING.md, "Adding a family"). Not part of the test
# suite (six checks take a few minutes); run it after changing what families provide.
#
# Usage: scripts/remove-family.sh [FAMILY...]   (from the repository root; default: every
#        folder under src/families/ that the registry lists). Env: WORKDIR (default
#        /tmp/hairfit-remove-family), CARGO_TARGET_DIR (default $WORKDIR/target).
set -euo pipefail

root="$(pwd)"
[ -f "$root/src/families/registry.rs" ] || {
    echo "remove-family: run from the repository root (no src/families/registry.rs here)" >&2
    exit 2
}
work="${WORKDIR:-/tmp/hairfit-remove-family}"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$work/target}"
if [ "$#" -gt 0 ]; then
    families=("$@")
else
    mapfile -t families < <(grep -E '=> (Own|Table)\(' src/families/registry.rs |
        grep -oE 'crate::families::[a-z_]+::' |
        sed -E 's/crate::families::([a-z_]+)::/\1/' | sort -u)
fi
failed=()
for family in "${families[@]}"; do
    [ -d "src/families/$family" ] || {
        echo "remove-family: no folder src/families/$family" >&2
        exit 2
    }
    copy="$work/tree"
    rm -rf "$copy"
    mkdir -p "$copy"
    # The tracked tree as it is now (uncommitted edits included), without target/.
    git ls-files -z --cached --others --exclude-standard |
        grep -zv '^target/' | xargs -0 cp --parents -t "$copy"
    rm -rf "$copy/src/families/$family"
    sed -i "/^pub mod $family;/d" "$copy/src/families/mod.rs"
    sed -i "/crate::families::$family::/d" "$copy/src/families/registry.rs"
    if (cd "$copy" && cargo check --quiet --lib --workspace 2>"$work/$family.log"); then
        echo "$family: removed (folder + 2 lines), library and Python package compile"
    else
        echo "$family: FAILS without it; first errors ($work/$family.log):"
        grep -E '^error|-->' "$work/$family.log" | head -8
        failed+=("$family")
    fi
done
[ "${#failed[@]}" -eq 0 ] || {
    echo "remove-family: something outside the folder names ${failed[*]}" >&2
    exit 1
}
