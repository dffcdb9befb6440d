#!/bin/bash
# The cluster path for real: a one-node Slurm on this machine (Debian's slurm-wlm and munge,
# installed when absent), a 4-shard array driven by scripts/cluster/shmgen-slurm with one task
# crashing by drill and another killed with kill -9 while it renders, and every byte of the
# result compared with a single-process run of the same recipe. Stops every daemon it started.
# Skips, saying why, where Slurm cannot be installed (not root, no apt-get, no package).
#
#   tests/cluster/slurm.sh [SHMGEN_BINARY]     (default target/release/shmgen)
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
shmgen=$(realpath "${1:-${SHMGEN:-target/release/shmgen}}")
[ -x "$shmgen" ] || { echo "cluster test: no binary at $shmgen (cargo build --release)" >&2; exit 1; }

skip() {
    echo "cluster test SKIPPED: $*"
    exit 0
}
have_slurm() {
    command -v slurmctld && command -v slurmd && command -v munged && command -v sbatch
} >/dev/null

if ! have_slurm; then
    [ "$(id -u)" -eq 0 ] || skip "Slurm is not installed and only root can install it"
    command -v apt-get >/dev/null || skip "Slurm is not installed and there is no apt-get"
    echo "cluster test: installing slurm-wlm and munge (Debian packages)"
    install() {
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            slurm-wlm munge >/dev/null
    }
    install || { apt-get update -qq >/dev/null && install; } ||
        skip "apt-get could not install slurm-wlm and munge"
fi
[ "$(id -u)" -eq 0 ] || skip "a local slurmd must run as root"

work=$(mktemp -d /tmp/shmgen-slurm-test.XXXXXX)
chmod 755 "$work" # munged wants a path to its socket every user may walk
cluster=$work/cluster
stop_cluster() { "$root/scripts/cluster/local-slurm" stop "$cluster" >/dev/null 2>&1 || true; }
trap 'stop_cluster; rm -rf "$work"' EXIT
fail() {
    echo "cluster test FAILED: $*" >&2
    exit 1
}

"$root/scripts/cluster/local-slurm" start "$cluster"
export SLURM_CONF=$cluster/slurm.conf SHMGEN=$shmgen
recipe=$root/scripts/quickstart.rhai
settings=(--set samples=64)

"$shmgen" run "$recipe" --out "$work/single" --threads 1 --quiet "${settings[@]}"

# Shard 1 crashes by drill after its first sample; shard 2 is killed from outside once it has
# written a sample: the driver must find both unfinished and resubmit exactly them.
"$root/scripts/cluster/shmgen-slurm" --shards 4 --drill 1 --poll 1 --retries 2 \
    --sbatch=--cpus-per-task=1 "$recipe" "$work/array" "${settings[@]}" >"$work/driver.log" 2>&1 &
driver=$!

# Samples of shard $1 in the manifest (0 before the folder exists); status exits 2 or 3 here.
shard_done() {
    local count
    count=$("$shmgen" status "$work/array" --json --shards 4 2>/dev/null |
        tr -d ' \n' | grep -o "{\"index\":$1,\"done\":[0-9]*" | sed 's/.*://') || true
    echo "${count:-0}"
}
killed=""
for _ in $(seq 1 600); do
    pid=$(pgrep -f -- "--shard 2/4" | head -1 || true)
    if [ -n "$pid" ] && [ "$(shard_done 2)" -ge 1 ]; then
        kill -9 "$pid" && killed=$pid
        break
    fi
    kill -0 "$driver" 2>/dev/null || break
    sleep 0.05
done
code=0
wait "$driver" || code=$?
cat "$work/driver.log"
[ "$code" -eq 0 ] || fail "shmgen-slurm exited with $code"
[ -n "$killed" ] || fail "shard 2/4 ended before it could be killed; the test needs longer tasks"
echo "cluster test: killed shard 2/4 (pid $killed) after its first sample"

grep -q "^round 1: job [0-9]*, --array=1-2 " "$work/driver.log" ||
    fail "the second round did not resubmit exactly shards 1 and 2"
grep -q "^verified: " "$work/driver.log" || fail "the driver did not end with shmgen verify"
diff -r "$work/single" "$work/array" || fail "the Slurm dataset differs from the single run"
echo "cluster test: 4 shards on Slurm, one crashed and one killed, equal byte for byte to one process"

daemons=$(cat "$cluster"/*.pid)
stop_cluster
for pid in $daemons; do
    # A zombie has ended; only its parent has not yet read its exit status.
    if [ -e "/proc/$pid" ] && ! grep -q '^State:.*Z' "/proc/$pid/status" 2>/dev/null; then
        fail "daemon $pid still running after local-slurm stop"
    fi
done
echo "cluster test passed"
