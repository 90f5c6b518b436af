#!/bin/sh
# Equal-time error of each integrator against a long reference, on the
# bundled Cornell box and caustic scene at 256 x 256 with two threads.
# Prints samples per second and the relative MSE of each render.
#
#   benches/equal-time.sh            # 30 s (Cornell) / 60 s (caustics) renders, 300 s references
#   T_CORNELL=10 T_CAUSTICS=20 REF=120 benches/equal-time.sh   # quicker, noisier
#   SCENES=cornell-caustics INTEGRATORS="bdpt vcm" T_CAUSTICS=40 benches/equal-time.sh
set -eu
cd "$(dirname "$0")/.."
T_CORNELL=${T_CORNELL:-30}
T_CAUSTICS=${T_CAUSTICS:-60}
REF=${REF:-300}
OUT=${OUT:-target/equal-time}
SCENES=${SCENES:-"cornell-box cornell-caustics"}
INTEGRATORS=${INTEGRATORS:-"pt lt bdpt vcm"}
cargo build --release --quiet
tracer=target/release/tracer
mkdir -p "$OUT"
for scene in $SCENES; do
    if [ "$scene" = cornell-box ]; then t=$T_CORNELL; ref=pt; else t=$T_CAUSTICS; ref=bdpt; fi
    # The reference: a different seed, so its noise is independent of the
    # renders'. Kept between runs of the same length: delete it to remake it.
    reference="$OUT/$scene-reference-$REF.pfm"
    if [ ! -f "$reference" ]; then
        $tracer render "scenes/$scene.json" --integrator $ref --seed 1000 --spp 1000000 \
            --time-limit "$REF" --threads 2 -q -o "$reference" 2> "$OUT/log"
        echo "$scene reference ($ref): $(grep wrote "$OUT/log" | sed 's/.*: //')"
    fi
    for integrator in $INTEGRATORS; do
        $tracer render "scenes/$scene.json" --integrator $integrator --spp 1000000 \
            --time-limit "$t" --threads 2 -q -o "$OUT/$scene-$integrator.pfm" 2> "$OUT/log"
        error=$($tracer compare "$OUT/$scene-$integrator.pfm" "$reference")
        echo "$scene $integrator: $(grep wrote "$OUT/log" | sed 's/.*: //'), relative MSE $error"
    done
done
