#!/usr/bin/env python3
"""Renders one of our scenes with Mitsuba 3 a few times and prints each
render's seconds: a fixed workload to run under a sampling profiler, to see
where Mitsuba's time goes (Embree's traversal against Dr.Jit's kernels).

    perf record -e cpu-clock -F 2000 -o target/mitsuba.perf \\
        benches/peers/mitsuba_render.py scenes/cornell-box.json --spp 64
    perf report -i target/mitsuba.perf --no-children --sort dso

The scene goes through `to_mitsuba.py` as in `compare.py`, which also sets
Mitsuba up (variant, thread count, LLVM library). The first render compiles
Dr.Jit's kernels, unless its cache on disk has them; the renders after it
find them compiled. Seconds leave out compilation, as `compare.py`'s do.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import compare  # noqa: E402  (this folder's harness)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="a scene JSON file")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--size", type=int, default=256, help="width and height")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--renders", type=int, default=3, help="timed renders after the first")
    p.add_argument("--integrator", default="path", help="Mitsuba's: path or ptracer")
    p.add_argument("--sampler", default="independent")
    p.add_argument("--max-depth", type=int, default=16)
    p.add_argument("--variant", default="llvm_ad_rgb")
    args = p.parse_args(argv)

    mi, dr = compare.setup_mitsuba(args.variant, args.threads)
    mitsuba = compare.Mitsuba(mi, dr, args.variant)
    obj, spp = mitsuba.load(args.scene, args.integrator, args.sampler, args.spp,
                            (args.size, args.size), args.max_depth)
    pixels = args.size * args.size
    for seed in range(args.renders + 1):
        _, seconds, compile_s = mitsuba.render(obj, seed)
        what = "first" if seed == 0 else f"seed {seed}"
        print(f"{what}: {seconds:.3f} s, {pixels * spp / seconds / 1e6:.2f} M samples/s"
              f" (compilation {compile_s:.2f} s, not counted)", flush=True)


if __name__ == "__main__":
    main()
