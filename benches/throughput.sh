#!/usr/bin/env bash
# Rendering throughput of one or more tracer builds, side by side: renders
# each scene with each integrator at 256 x 256 on two threads, alternating
# the builds round by round (the machine's noise then falls on all of
# them alike), and prints a Markdown table of median camera samples per
# second, with each build's ratio to the first.
#
#   benches/throughput.sh                          # target/release/tracer alone
#   benches/throughput.sh old=/tmp/tracer-old new=target/release/tracer
#
# Environment: SCENES (default: the Cornell box, the caustic scene and
# benches/scenes/dragon.json when ../shared/meshes/dragon.obj exists),
# INTEGRATORS (default "pt lt bdpt"), ROUNDS (default 3), THREADS (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -eq 0 ]; then
    cargo build --release --quiet --bin tracer
    set -- tracer=target/release/tracer
fi
labels=() binaries=()
for arg in "$@"; do
    labels+=("${arg%%=*}")
    binaries+=("${arg#*=}")
done

default_scenes="scenes/cornell-box.json scenes/cornell-caustics.json"
[ -f ../shared/meshes/dragon.obj ] && default_scenes+=" benches/scenes/dragon.json"
SCENES=${SCENES:-$default_scenes}
INTEGRATORS=${INTEGRATORS:-pt lt bdpt}
ROUNDS=${ROUNDS:-3}
THREADS=${THREADS:-2}
# Enough samples for a few seconds each; BDPT's samples cost the most.
spp_of() { case $1 in pt) echo 16 ;; lt) echo 8 ;; *) echo 4 ;; esac; }

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for round in $(seq "$ROUNDS"); do
    for scene in $SCENES; do
        for integrator in $INTEGRATORS; do
            for k in "${!binaries[@]}"; do
                "${binaries[$k]}" render "$scene" --integrator "$integrator" \
                    --spp "$(spp_of "$integrator")" --width 256 --height 256 \
                    --threads "$THREADS" --no-cache --quiet -o "$out/image.pfm" 2>&1 |
                    sed -n 's/.* \([0-9.]*\) M samples\/s.*/\1/p' \
                        >>"$out/$(basename "$scene" .json)-$integrator-$k"
            done
        done
    done
done

median() { sort -g "$1" | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
echo "- date: $(date -u +%Y-%m-%dT%H:%M:%S+00:00)"
echo "- machine: $(uname -m), $(nproc) CPUs; $THREADS threads, 256 x 256, medians of $ROUNDS rounds"
for k in "${!binaries[@]}"; do
    echo "- ${labels[$k]}: ${binaries[$k]}"
done
echo
header="| scene | integrator | spp |"
rule="|---|---|---:|"
for k in "${!labels[@]}"; do
    header+=" ${labels[$k]} M samples/s |"
    rule+="---:|"
    if [ "$k" -gt 0 ]; then
        header+=" ${labels[$k]} / ${labels[0]} |"
        rule+="---:|"
    fi
done
echo "$header"
echo "$rule"
for scene in $SCENES; do
    name=$(basename "$scene" .json)
    for integrator in $INTEGRATORS; do
        row="| $name | $integrator | $(spp_of "$integrator") |"
        first=$(median "$out/$name-$integrator-0")
        for k in "${!binaries[@]}"; do
            m=$(median "$out/$name-$integrator-$k")
            row+=" $m |"
            if [ "$k" -gt 0 ]; then
                row+=" $(awk -v a="$m" -v b="$first" 'BEGIN {printf "%.2f", a / b}') |"
            fi
        done
        echo "$row"
    done
done
