#!/bin/sh
# Installs what benches/peers/compare.py needs: the Python packages pinned in
# requirements.txt (Mitsuba 3, Dr.Jit, numpy, OpenEXR) and, when missing,
# LLVM's shared library (Debian package libllvm19) for Mitsuba's llvm_ad_rgb
# variant. Prints the DRJIT_LIBLLVM_PATH to export.
#
#   benches/peers/setup.sh                 # uses python3 (3.11 tested)
#   PYTHON=.venv/bin/python benches/peers/setup.sh
set -eu
here=$(cd "$(dirname "$0")" && pwd)
PYTHON=${PYTHON:-python3}

"$PYTHON" -m pip install -r "$here/requirements.txt"

find_llvm() {
    for p in ${DRJIT_LIBLLVM_PATH:-} \
        /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 /usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        /usr/lib/aarch64-linux-gnu/libLLVM.so.19.1 /usr/lib/aarch64-linux-gnu/libLLVM-19.so \
        /usr/lib/llvm-19/lib/libLLVM.so.1 /usr/lib/llvm-19/lib/libLLVM.so; do
        if [ -e "$p" ]; then
            echo "$p"
            return 0
        fi
    done
    return 1
}

if ! lib=$(find_llvm); then
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "error: no LLVM 19 shared library found and no apt-get: install LLVM 19 and" \
            "set DRJIT_LIBLLVM_PATH to its libLLVM.so" >&2
        exit 1
    fi
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        sudo=sudo
    fi
    $sudo apt-get update
    $sudo apt-get install -y libllvm19
    lib=$(find_llvm) || { echo "error: libllvm19 installed but libLLVM.so not found" >&2; exit 1; }
fi

DRJIT_LIBLLVM_PATH="$lib" "$PYTHON" -c '
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
print(f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}: llvm_ad_rgb works")
'
echo "export DRJIT_LIBLLVM_PATH=$lib"
