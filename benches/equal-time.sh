#!/bin/sh
# Equal-time error of PT, LT and BDPT against a long reference, on the
# bundled Cornell box and caustic scene at 256 x 256 with two threads.
# Prints samples per second and the relative MSE of each render.
#
#   benches/equal-time.sh            # 30 s (Cornell) / 60 s (caustics) renders, 300 s references
#   T_CORNELL=10 T_CAUSTICS=20 REF=120 benches/equal-time.sh   # quicker, noisier
set -eu
cd "$(dirname "$0")/.."
T_CORNELL=${T_CORNELL:-30}
T_CAUSTICS=${T_CAUSTICS:-60}
REF=${REF:-300}
OUT=${OUT:-target/equal-time}
cargo build --release --quiet
tracer=target/release/tracer
mkdir -p "$OUT"
for scene in cornell-box cornell-caustics; do
    if [ "$scene" = cornell-box ]; then t=$T_CORNELL; ref=pt; else t=$T_CAUSTICS; ref=bdpt; fi
    # The reference: a different seed, so its noise is independent of the renders'.
    $tracer render "scenes/$scene.json" --integrator $ref --seed 1000 --spp 1000000 \
        --time-limit "$REF" --threads 2 -q -o "$OUT/$scene-reference.pfm" 2> "$OUT/log"
    echo "$scene reference ($ref): $(grep wrote "$OUT/log" | sed 's/.*: //')"
    for integrator in pt lt bdpt; do
        $tracer render "scenes/$scene.json" --integrator $integrator --spp 1000000 \
            --time-limit "$t" --threads 2 -q -o "$OUT/$scene-$integrator.pfm" 2> "$OUT/log"
        error=$($tracer compare "$OUT/$scene-$integrator.pfm" "$OUT/$scene-reference.pfm")
        echo "$scene $integrator: $(grep wrote "$OUT/log" | sed 's/.*: //'), relative MSE $error"
    done
done
