#!/usr/bin/env bash
# shmgen against Blender Cycles on one machine, side by side: the same A1 beams (the paper's
# 12,288-triangle boxes, 960×960, vertical field of view π/3, RGB + depth written), Cycles on
# the CPU at 1 and 16 samples per pixel (python/bench/blender_beams.py), shmgen's
# `scripts/a1_beams.rhai --set paper_mesh=true` (RGB, depth, mask and JSON written).
# Prints the median seconds per pair of each, over RUNS runs (each run's own median for
# Blender, whose first render of a beam also builds its scene; whole runs for shmgen).
# Then outdoors: a beam on abutments on a ground under a 0.53° sun and a Nishita sky
# (python/bench/blender_outdoor.py; Cycles at 1 and 16 spp, and EEVEE, Blender's rasteriser,
# under xvfb-run with Mesa's software OpenGL when xvfb-run is installed) against
# `scripts/outdoor.rhai` (15 samples × 2 views, cached lighting and per_pixel).
#
#     benches/blender.sh            (RUNS=3 BEAMS=3 VIEWS=5 OUTDOOR_VIEWS=4 by default)
#
# Skips, saying so, when Blender is not installed (Debian: apt-get install blender).
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-3}
BEAMS=${BEAMS:-3}
VIEWS=${VIEWS:-5}
OUTDOOR_VIEWS=${OUTDOOR_VIEWS:-4}
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null; then
    echo "benches/blender.sh: skipped, no Blender ($BLENDER) on this machine"
    exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "$("$BLENDER" --version 2>/dev/null | head -1), $BEAMS beams × $VIEWS views per run, $RUNS runs"
for spp in 1 16; do
    runs=()
    for _ in $(seq "$RUNS"); do
        rm -rf "$work/blender"
        runs+=("$("$BLENDER" -b --factory-startup -noaudio --python python/bench/blender_beams.py -- \
            --spp "$spp" --beams "$BEAMS" --views "$VIEWS" --out "$work/blender" 2>/dev/null |
            awk '/^median/ { print $2 }')")
    done
    s=$(printf '%s\n' "${runs[@]}" | median)
    echo "Blender Cycles, $spp spp: $s s per pair ($(awk -v s="$s" 'BEGIN { printf "%.2f", 1 / s }') pairs/s); runs: ${runs[*]}"
done

cargo build --release --quiet
runs=()
for _ in $(seq "$RUNS"); do
    rm -rf "$work/shmgen"
    seconds=$(target/release/shmgen run scripts/a1_beams.rhai --out "$work/shmgen" --quiet \
        --set paper_mesh=true --set samples="$BEAMS" --set views="$VIEWS" |
        sed -n 's/.* pairs in \([0-9.]*\) s.*/\1/p')
    runs+=("$(awk -v s="$seconds" -v n=$((BEAMS * VIEWS)) 'BEGIN { printf "%.4f", s / n }')")
done
s=$(printf '%s\n' "${runs[@]}" | median)
echo "shmgen (paper mesh, paper prompts): $s s per pair ($(awk -v s="$s" 'BEGIN { printf "%.1f", 1 / s }') pairs/s); runs: ${runs[*]}"

# Outdoors. Each Blender run renders OUTDOOR_VIEWS views of one scene; its median per pair.
outdoor_blender() { # engine spp [launcher...]
    local engine=$1 spp=$2 runs=() s
    shift 2
    for _ in $(seq "$RUNS"); do
        rm -rf "$work/outdoor"
        runs+=("$("$@" "$BLENDER" -b --factory-startup -noaudio \
            --python python/bench/blender_outdoor.py -- --engine "$engine" --spp "$spp" \
            --views "$OUTDOOR_VIEWS" --out "$work/outdoor" 2>/dev/null |
            awk '/^median/ { print $2 }')")
    done
    s=$(printf '%s\n' "${runs[@]}" | median)
    echo "outdoor, Blender $engine, $spp spp: $s s per pair; runs: ${runs[*]}"
}
outdoor_blender CYCLES 1
outdoor_blender CYCLES 16
if command -v xvfb-run >/dev/null; then
    outdoor_blender BLENDER_EEVEE 16 xvfb-run -a
else
    echo "outdoor, Blender EEVEE: skipped, no xvfb-run (Debian: apt-get install xvfb)"
fi
for shading in cached per_pixel; do
    runs=()
    for _ in $(seq "$RUNS"); do
        rm -rf "$work/shmgen"
        seconds=$(target/release/shmgen run scripts/outdoor.rhai --out "$work/shmgen" --quiet \
            --set shading="$shading" | sed -n 's/.* pairs in \([0-9.]*\) s.*/\1/p')
        runs+=("$(awk -v s="$seconds" 'BEGIN { printf "%.4f", s / 30 }')")
    done
    s=$(printf '%s\n' "${runs[@]}" | median)
    echo "outdoor, shmgen outdoor.rhai, shading=$shading: $s s per pair ($(awk -v s="$s" 'BEGIN { printf "%.1f", 1 / s }') pairs/s); runs: ${runs[*]}"
done
