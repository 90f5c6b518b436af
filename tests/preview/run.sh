#!/usr/bin/env bash
# The preview window, for real: builds `tracer` with the preview feature,
# starts a virtual X server (Xvfb), renders with --preview and, separately,
# a T-racer scene whose Display type is "Window", takes a screenshot of each
# while the window is up, and checks that the window shows the render
# (tests/preview/check_screenshot.py). Screenshots are kept in
# target/preview/ for a person to look at.
#
# Needs Xvfb and xwd (Debian: xvfb, x11-apps); .ci/run installs them.
set -euo pipefail
cd "$(dirname "$0")/../.."

cargo build --quiet --features preview
tracer=target/debug/tracer
shots=target/preview
mkdir -p "$shots"
tmp=$(mktemp -d)
display=":$((90 + RANDOM % 100))"
Xvfb "$display" -screen 0 640x480x24 -nolisten tcp >"$tmp/xvfb.log" 2>&1 &
xvfb=$!
trap 'kill $xvfb 2>/dev/null || true; rm -rf "$tmp"' EXIT
export DISPLAY=$display
for _ in $(seq 100); do [ -S "/tmp/.X11-unix/X${display#:}" ] && break; sleep 0.1; done

# Waits for FILE, then for the window to show a few more passes, screenshots
# the screen into SHOT, stops tracer (PID) with Ctrl-C, and checks that it
# exits within 10 seconds with status EXPECTED.
screenshot_and_stop() {
    local pid=$1 file=$2 shot=$3 expected=$4
    for _ in $(seq 200); do [ -s "$file" ] && break; sleep 0.1; done
    [ -s "$file" ] || { echo "preview: $file never appeared"; kill -9 "$pid"; exit 1; }
    sleep 2
    xwd -root -silent -display "$display" >"$shot"
    kill -INT "$pid"
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then
        kill -9 "$pid"
        echo "preview: tracer did not exit after Ctrl-C"
        exit 1
    fi
    local status=0
    wait "$pid" || status=$?
    echo "tracer exited with $status"
    [ "$status" -eq "$expected" ] || { echo "preview: expected exit status $expected"; exit 1; }
}

echo "== render --preview"
$tracer render scenes/cornell-box.json --preview --width 256 --height 256 --spp 100000 \
    --checkpoint 0.2 -q -o "$tmp/box.png" &
# Ctrl-C during the render: it writes the image and exits with 130.
screenshot_and_stop $! "$tmp/box.png" "$tmp/box.xwd" 130
# The image written at Ctrl-C is the window's last frame or one pass newer.
python3 tests/preview/check_screenshot.py "$tmp/box.xwd" "$tmp/box.png" "$shots/render-preview.png"

echo "== a T-racer scene with Display Window"
cp -r scenes/trs "$tmp/trs"
sed -i 's/"Type": "TGA"/"Type": "Window"/' "$tmp/trs/cornell.trs"
grep -q '"Type": "Window"' "$tmp/trs/cornell.trs"
$tracer render "$tmp/trs/cornell.trs" -q -o "$tmp/trs.png" &
# This render finishes; the window then keeps showing it until closed.
# Ctrl-C after it: the window closes and tracer exits normally.
screenshot_and_stop $! "$tmp/trs.png" "$tmp/trs.xwd" 0
python3 tests/preview/check_screenshot.py "$tmp/trs.xwd" "$tmp/trs.png" "$shots/trs-window.png"
echo "preview: ok"
