#!/usr/bin/env bash
# Renders the bundled JSON scenes into docs/images/ for the README's gallery:
# 256 x 256, seed 0, path tracing at 256 spp, the caustic scene with BDPT
# at 512 spp (path tracing finds its caustics only by chance), and the
# rough-materials scene with BDPT at 256 spp (the light through its rough
# glass is noisy for path tracing), and the sky scene with path tracing at
# 512 spp in its own 320 x 200 (it is lit by an image sky, which path
# tracing samples directly), and the mirror-caustic scene with VCM at 256 spp
# in its own 256 x 192 (only VCM renders its caustic in the mirror).
#
#   docs/render-gallery.sh
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release
tracer=target/release/tracer
mkdir -p docs/images

render() {
    local name=$1
    shift
    echo "== $name"
    "$tracer" render "scenes/$name.json" -o "docs/images/$name.png" --seed 0 -q "$@"
    # The JSON sidecar records timings that change from run to run; the
    # gallery keeps only the pictures.
    rm -f "docs/images/$name.png.json"
}

render cornell-box --spp 256 --width 256 --height 256
render cornell-caustics --spp 512 --integrator bdpt --width 256 --height 256
render lights --spp 256 --width 256 --height 256
render textured --spp 256 --width 256 --height 256
render rough-materials --spp 256 --integrator bdpt --width 256 --height 256
render sky-materials --spp 512
render mirror-caustic --spp 256 --integrator vcm
