#!/usr/bin/env bash
# Runs the Slurm recipes of docs/progressive.md, as the files in
# docs/slurm/ hold them, on a one-node cluster (tests/slurm/cluster.sh):
# the array job of sample ranges and the array job of crops, each with its
# dependent merge job. Each merged image must equal one render of all the
# samples: to rounding for sample ranges, bit for bit for crops.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
# The recipes in the documentation are these files, word for word.
for f in docs/slurm/*; do
    python3 - "$f" docs/progressive.md <<'PY' || { echo "docs/progressive.md does not quote $f as it is" >&2; exit 1; }
import sys
recipe, doc = open(sys.argv[1]).read(), open(sys.argv[2]).read()
sys.exit(0 if "```sh\n" + recipe + "```" in doc else 1)
PY
done
cargo build --release --quiet
export PATH="$root/target/release:$PATH"
tests/slurm/cluster.sh

work=$(mktemp -d "$root/target/slurm.XXXXXX")
trap 'rm -rf "$work"' EXIT
# A small Cornell box, so sixteen tasks take seconds.
python3 - "$root/scenes/cornell-box.json" "$work/scene.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["film"] = dict(scene.get("film", {}), width=32, height=24)
json.dump(scene, open(sys.argv[2], "w"))
PY
cp docs/slurm/* "$work/"
cd "$work"

# Waits until Slurm has no job left and `file` exists.
wait_for() {
    local file=$1
    for _ in $(seq 1 600); do
        if [ -z "$(squeue -h)" ]; then
            [ -f "$file" ] && return 0
            echo "the jobs ended without writing $file:" >&2
            cat slurm-*.out >&2 || true
            return 1
        fi
        sleep 0.5
    done
    echo "timed out waiting for the jobs" >&2
    squeue >&2
    return 1
}

# Relative MSE between two images, from `tracer compare`.
compare() { tracer compare "$1" "$2"; }

echo "== sample ranges: 16 array tasks, then merge"
bash submit.sh
wait_for scene.exr
tracer render scene.json --spp 1024 -q -o reference.exr
error=$(compare scene.exr reference.exr)
echo "merged against one render of 1024 spp: relative MSE $error"
python3 -c "import sys; sys.exit(0 if float('$error') < 1e-8 else 1)" ||
    { echo "the merged image differs from one render" >&2; exit 1; }

echo "== crops: 4 array tasks of bands, then merge"
rm -f scene.exr slurm-*.out
W=64 H=48 bash submit-crops.sh
wait_for scene.exr
tracer render scene.json --width 64 --height 48 --spp 64 -q -o reference-crops.exr
error=$(compare scene.exr reference-crops.exr)
echo "merged bands against one render: relative MSE $error"
[ "$error" = "0.000000e0" ] || { echo "the merged bands differ from one render" >&2; exit 1; }
echo "slurm recipes: ok"
