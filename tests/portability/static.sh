#!/bin/bash
# The static build runs where there is no C library at all, and writes the same bytes as the
# default build. Builds target/static/shmgen with scripts/build-static, checks it names no
# shared library and no loader (a static PIE relocates itself), renders a small dataset with
# it inside an empty root (chroot: a folder with the binary and the recipe, nothing else;
# without root, under `env -i` instead) and compares every file with the default build's run.
#
#   tests/portability/static.sh [DEFAULT_BINARY]     (default target/release/shmgen)
set -euo pipefail
cd "$(dirname "$0")/../.."
dynamic=$(realpath "${1:-target/release/shmgen}")
[ -x "$dynamic" ] || { echo "portability test: no binary at $dynamic" >&2; exit 1; }
fail() {
    echo "portability test FAILED: $*" >&2
    exit 1
}

scripts/build-static
static=target/static/shmgen
if readelf -d "$static" | grep -q "NEEDED\|INTERP"; then
    readelf -d "$static" >&2
    fail "$static still loads shared libraries"
fi
readelf -l "$static" | grep -q "INTERP" && fail "$static asks for a program interpreter"

work=$(mktemp -d /tmp/shmgen-static-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/root"
cp "$static" "$work/root/shmgen"
cp scripts/quickstart.rhai "$work/root/quickstart.rhai"
settings=(--set samples=3 --threads 2 --quiet)

"$dynamic" run scripts/quickstart.rhai --out "$work/default" "${settings[@]}"
if [ "$(id -u)" -eq 0 ]; then
    # Nothing in the root but the binary and the recipe: no /lib, no /etc, no /proc.
    chroot "$work/root" /shmgen run /quickstart.rhai --out /static "${settings[@]}"
    where="an empty root (chroot)"
else
    (cd "$work/root" && env -i ./shmgen run quickstart.rhai --out static "${settings[@]}")
    where="an empty environment (env -i; not root, so no chroot)"
fi
diff -r "$work/default" "$work/root/static" || fail "the static build wrote other bytes"
echo "portability test passed: the static build ran in $where and wrote the default build's bytes"
