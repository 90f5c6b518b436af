#!/usr/bin/env python3
"""Peer comparison: tracer against Mitsuba 3 on the bundled Cornell scenes.

For each scene (default: scenes/cornell-box.json,
scenes/cornell-caustics.json and, when ../shared/meshes/dragon.obj is
there, benches/scenes/dragon.json; at 256 x 256, 2 threads):

1. A reference: tracer's `bdpt` at --reference-spp, rendered as
   --reference-parts processes with disjoint `--sample-offset`s (the parts
   give the reference's own noise) and joined by `tracer merge`. It is
   cached under target/peers/reference/, keyed by the scene file's hash,
   `tracer --version` and the settings, and reused by later runs.
2. Fixed spp: Mitsuba's `path` and `ptracer` with the samplers
   `independent`, `multijitter`, `ldsampler` and `orthogonal`, and tracer's
   `pt`, `lt` and `bdpt`, at --spp (a Mitsuba sampler that cannot take that
   count takes the largest it can below it: ldsampler a square power of two,
   orthogonal the square of a prime). --runs renders of each, with seeds 0,
   1, ...; the runs go round all configurations in turn, so load on a shared
   machine falls on all of them alike. Seconds are the median; the relative
   MSE is the mean over the seeds.
3. Equal time: each configuration again, at the spp its fixed-spp speed
   says it reaches in the time tracer's `pt` took for --spp (or
   --equal-time seconds). `ldsampler` and `orthogonal`, which take only
   some counts, take the count nearest to that, or several independent
   passes of a smaller count they take (averaged) when that is nearer.
4. Agreement: a long Mitsuba `path` render (--agreement-passes independent
   passes, --agreement-spp samples in all) against the reference, by 8 x 8
   pixel blocks: a Welch t statistic per block and channel, from the spread
   of the passes and of the reference's parts, judged with a Bonferroni
   bound at a 1% family-wise level; and the image mean per channel. As a
   control, the same test on tracer's own `pt` with the same samples (it
   converges to the reference's image, so what it flags is the test's own
   false-alarm rate on that scene; path-traced caustics have rare, very
   bright samples, which make block means far from normal). Where the
   control fails, both are tested again on coarser blocks (16 x 16, then
   32 x 32): block means over more pixels are nearer normal, and the
   verdict at the finest size where the control passes is reported beside
   the 8 x 8 one (as `calibrated`).

Timing: Mitsuba seconds are the wall time of `mi.render` and reading the
image back into numpy, after a warm-up render of the same configuration;
any kernel compilation that still happens in a timed call (Dr.Jit's kernel
history reports it) is subtracted. Scene loading is excluded. tracer's
seconds are its own `tracer.renderSeconds` (the render, excluding scene
loading and BVH build). Samples per second count camera samples, pixels x
spp; for the light tracers (`lt`, `ptracer`) one sample is one light path.

Relative MSE is `tracer compare`'s: the mean over pixels and channels of
(image - reference)^2 / (reference^2 + 0.01) (checked against
`tracer compare` on one image per scene). The reference's own noise adds to
every figure; its estimate from the parts is printed as `ref floor`.
Efficiency = 1 / (relMSE x seconds).

Results: a table on stdout, and target/peers/results.json and results.md
with the date, the machine, and the versions.
"""

import argparse
import datetime
import glob
import hashlib
import json
import math
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

import to_mitsuba  # noqa: E402  (needs no Mitsuba until convert() is called)

DEFAULT_SCENES = ["scenes/cornell-box.json", "scenes/cornell-caustics.json"]
# What the agreement verdict alone would not tell a reader, by scene name.
SCENE_NOTES = {
    "dragon": "On the dragon scene the images do differ: Mitsuba starts each ray a fixed "
              "distance off its surface (about 9e-5 in this 0.2-unit scene), so rays escape "
              "through the mesh's finest creases and its dragon comes out up to a few per cent "
              "brighter; scaled up 100 times, the same scene agrees within 0.1% (rendered, both "
              "renderers, 256 spp), while tracer's image is the same at every scale "
              "([details](docs/benchmarks.md#mitsuba-on-the-dragon-scene)).",
}
# The Stanford dragon on a floor under a small light, when ../shared/meshes
# has the mesh: a scene where the BVH, not the shading, takes most of the time.
if os.path.exists(os.path.join(REPO, "..", "shared", "meshes", "dragon.obj")):
    DEFAULT_SCENES.append("benches/scenes/dragon.json")
MI_INTEGRATORS = ["path", "ptracer"]
MI_SAMPLERS = ["independent", "multijitter", "ldsampler", "orthogonal"]
TRACER_INTEGRATORS = ["pt", "lt", "bdpt"]
REFERENCE_SEED = 1000
EQUAL_TIME_SEED = 100
AGREEMENT_SEED = 10000
BLOCK = 8
COARSE_BLOCK = 32
# Block sizes for the calibrated verdict, finest first (see `calibrate`).
CALIBRATION_BLOCKS = (BLOCK, 16, COARSE_BLOCK)
ALPHA = 0.01
LLVM_CANDIDATES = [
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/llvm-19/lib/libLLVM.so",
    "/usr/lib/aarch64-linux-gnu/libLLVM.so.19.1",
]


def log(*args):
    print(*args, file=sys.stderr, flush=True)


# ------------------------------------------------------------------ images

def read_exr(path):
    import OpenEXR
    with OpenEXR.File(path) as f:
        header = dict(f.header())
        channels = f.channels()
        if "RGB" in channels:
            px = np.asarray(channels["RGB"].pixels, np.float64)
        else:
            px = np.stack([np.asarray(channels[c].pixels, np.float64) for c in "RGB"], -1)
    return px[..., :3], header


def write_exr(path, img):
    import OpenEXR
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    tmp = path + ".tmp.exr"
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(img, np.float32)}) as f:
        f.write(tmp)
    os.replace(tmp, path)


def relmse(img, ref):
    """`tracer compare`'s relative MSE."""
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 0.01)))


def header_float(header, key):
    v = header.get(key)
    if v is None:
        return None
    return float(np.asarray(v).ravel()[0])


# ---------------------------------------------------------------- statistics

def _betacf(a, b, x):
    """Continued fraction of the incomplete beta function (Lentz's method)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c if abs(1.0 + aa / c) > tiny else tiny
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c if abs(1.0 + aa / c) > tiny else tiny
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < 1e-14:
            break
    return h


def _betainc(a, b, x):
    """Regularised incomplete beta function I_x(a, b)."""
    if x <= 0:
        return 0.0
    if x >= 1:
        return 1.0
    lbeta = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
    front = math.exp(lbeta + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1) / (a + b + 2):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1 - x) / b


def t_two_sided_p(t, dof):
    """P(|T| >= |t|) for Student's t with `dof` degrees of freedom."""
    if not math.isfinite(t):
        return 0.0
    return _betainc(dof / 2.0, 0.5, dof / (dof + t * t))


def t_threshold(p, dof):
    """|t| whose two-sided tail probability is p (bisection)."""
    lo, hi = 0.0, 1e3
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if t_two_sided_p(mid, dof) > p:
            lo = mid
        else:
            hi = mid
    return hi


def block_means(img, block=BLOCK):
    h, w, c = img.shape
    hb, wb = h // block * block, w // block * block
    return img[:hb, :wb].reshape(hb // block, block, wb // block, block, c).mean(axis=(1, 3))


def agreement(passes, parts, block=BLOCK):
    """Compare two sets of independent renders of one image, block by block."""
    a = np.stack([block_means(p, block) for p in passes])
    b = np.stack([block_means(p, block) for p in parts])
    na, nb = len(a), len(b)
    ma, mb = a.mean(0), b.mean(0)
    va, vb = a.var(0, ddof=1) / na, b.var(0, ddof=1) / nb
    v = va + vb
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(v > 0, (ma - mb) / np.sqrt(v), np.where(ma == mb, 0.0, np.inf))
        dof = np.where(v > 0, v ** 2 / (va ** 2 / (na - 1) + vb ** 2 / (nb - 1)), na + nb - 2)
    dof = np.nan_to_num(dof, nan=na + nb - 2)
    tests = t.size
    flat = np.abs(t).ravel()
    worst = int(np.argmax(flat))
    by, bx, ch = np.unravel_index(worst, t.shape)
    p_worst = t_two_sided_p(float(flat[worst]), float(dof.ravel()[worst]))
    # The smallest p over all blocks (not always at the largest |t|: dof differ).
    pvals = np.array([t_two_sided_p(float(x), float(d)) for x, d in zip(flat, dof.ravel())])
    p_min = float(pvals.min())
    # Image mean per channel: the ratio and its own t statistic.
    ta, tb = a.mean(axis=(1, 2)), b.mean(axis=(1, 2))  # (n, 3)
    ratio, ratio_se, ratio_t, ratio_p = [], [], [], []
    for c in range(3):
        xa, xb = ta[:, c].mean(), tb[:, c].mean()
        sa, sb = ta[:, c].var(ddof=1) / na, tb[:, c].var(ddof=1) / nb
        r = xa / xb if xb > 0 else float("nan")
        ratio.append(float(r))
        ratio_se.append(float(r * math.sqrt(sa / xa ** 2 + sb / xb ** 2)) if xa > 0 and xb > 0 else float("nan"))
        tt = (xa - xb) / math.sqrt(sa + sb) if sa + sb > 0 else 0.0
        d = (sa + sb) ** 2 / (sa ** 2 / (na - 1) + sb ** 2 / (nb - 1)) if sa + sb > 0 else na + nb - 2
        ratio_t.append(float(tt))
        ratio_p.append(t_two_sided_p(tt, d))
    blocks_ok = p_min * tests >= ALPHA
    means_ok = min(ratio_p) * 3 >= ALPHA
    dof_typ = float(np.median(dof))
    return {
        "blocks": int(t.shape[0] * t.shape[1]),
        "tests": int(tests),
        "block_size": block,
        "passes": na,
        "reference_parts": nb,
        "worst_t": float(t.ravel()[worst]),
        "worst_at": {"x": int(bx * block), "y": int(by * block), "channel": "RGB"[ch],
                     "mitsuba": float(ma[by, bx, ch]), "reference": float(mb[by, bx, ch])},
        "worst_p": p_worst,
        "min_p_bonferroni": min(1.0, p_min * tests),
        "threshold_t": t_threshold(ALPHA / tests, dof_typ),
        "median_dof": dof_typ,
        "frac_abs_t_over_3": float(np.mean(flat > 3)),
        "mean_t2": float(np.mean(np.where(np.isfinite(t), t, 0) ** 2)),
        "ratio": ratio,
        "ratio_se": ratio_se,
        "ratio_t": ratio_t,
        "pass": bool(blocks_ok and means_ok),
    }


# ------------------------------------------------------------------ tracer

class Tracer:
    def __init__(self, path, threads, out):
        self.path = path
        self.threads = threads
        self.out = out
        v = subprocess.run([path, "--version"], capture_output=True, text=True, check=True)
        self.version = v.stdout.strip()

    def render(self, scene, out, integrator, spp, seed, size, max_depth, extra=()):
        cmd = [self.path, "render", scene, "--integrator", integrator, "--spp", str(spp),
               "--seed", str(seed), "--threads", str(self.threads), "--width", str(size[0]),
               "--height", str(size[1]), "--max-depth", str(max_depth), "-q", "--no-cache",
               "--checkpoint", "1000000", "-o", out, *extra]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"error: {' '.join(cmd)} failed:\n{r.stderr}")
        img, header = read_exr(out)
        seconds = header_float(header, "tracer.renderSeconds")
        if seconds is None:  # fall back on the report line: "wrote ...: ..., X s, ..."
            m = re.search(r"wrote .*?, ([0-9.]+) s,", r.stderr)
            seconds = float(m.group(1))
        return img, seconds

    def compare(self, image, reference):
        r = subprocess.run([self.path, "compare", image, reference], capture_output=True,
                           text=True, check=True)
        m = re.search(r"[-+0-9.eE]+(?:inf|nan)?", r.stdout.strip().split()[-1])
        return float(m.group(0))

    def merge(self, parts, out):
        subprocess.run([self.path, "merge", *parts, "-o", out], capture_output=True, text=True,
                       check=True)


def file_hash(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def reference(tracer, scene, args, size, max_depth):
    """tracer's bdpt reference, in parts, cached; returns (image, parts, info)."""
    parts_n = args.reference_parts
    per_part = max(1, -(-args.reference_spp // parts_n))
    total = per_part * parts_n
    version = re.sub(r"[^A-Za-z0-9.]+", "-", tracer.version).strip("-")
    key = (f"{os.path.splitext(os.path.basename(scene))[0]}-{file_hash(scene)[:12]}-{version}"
           f"-bdpt-{total}spp-{parts_n}parts-{size[0]}x{size[1]}-d{max_depth}-s{REFERENCE_SEED}")
    folder = os.path.join(args.out, "reference", key)
    info_path = os.path.join(folder, "info.json")
    ref_path = os.path.join(folder, "reference.exr")
    part_paths = [os.path.join(folder, f"part-{i:03d}.exr") for i in range(parts_n)]
    if not args.fresh_reference and os.path.exists(info_path) and os.path.exists(ref_path) \
            and all(map(os.path.exists, part_paths)):
        with open(info_path) as f:
            info = json.load(f)
        info["cached"] = True
        log(f"  reference: cached {folder} ({info['seconds']:.0f} s when made)")
    else:
        os.makedirs(folder, exist_ok=True)
        log(f"  reference: tracer bdpt, {total} spp in {parts_n} parts of {per_part} -> {folder}")
        seconds = 0.0
        start = time.perf_counter()
        for i, p in enumerate(part_paths):
            _, s = tracer.render(scene, p, "bdpt", per_part, REFERENCE_SEED, size, max_depth,
                                 extra=["--sample-offset", str(i * per_part)])
            seconds += s
            if i == 0:
                log(f"    part 0: {s:.1f} s; about {s * parts_n / 60:.1f} min in all")
        tracer.merge(part_paths, ref_path)
        info = {"integrator": "bdpt", "spp": total, "parts": parts_n, "seed": REFERENCE_SEED,
                "seconds": seconds, "wall_seconds": time.perf_counter() - start,
                "tracer": tracer.version, "scene_sha256": file_hash(scene),
                "made": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
        with open(info_path, "w") as f:
            json.dump(info, f, indent=1)
        info["cached"] = False
    ref, _ = read_exr(ref_path)
    parts = [read_exr(p)[0] for p in part_paths]
    mean = np.mean(parts, axis=0)
    gap = float(np.max(np.abs(mean - ref)) / max(1e-12, float(np.max(np.abs(ref)))))
    if gap > 1e-4:
        raise SystemExit(f"error: {ref_path} is not the mean of its parts (gap {gap:.2e})")
    # The reference's own expected relative MSE: its per-pixel variance (from
    # the parts) over (ref^2 + 0.01), averaged.
    var = np.var(parts, axis=0, ddof=1) / parts_n
    info["floor"] = float(np.mean(var / (ref ** 2 + 0.01)))
    info["path"] = os.path.relpath(ref_path, REPO)
    return ref, parts, info


# ----------------------------------------------------------------- mitsuba

def setup_mitsuba(variant, threads):
    if variant.startswith("llvm") and not os.environ.get("DRJIT_LIBLLVM_PATH"):
        found = [p for p in LLVM_CANDIDATES if os.path.exists(p)]
        found += sorted(glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"))
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = found[0]
    try:
        import drjit as dr
        import mitsuba as mi
        mi.set_variant(variant)
    except Exception as e:  # noqa: BLE001
        raise SystemExit(f"error: cannot load Mitsuba's {variant} variant ({e}); run "
                         f"benches/peers/setup.sh and set DRJIT_LIBLLVM_PATH as it says, "
                         f"or pass --variant scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)
    dr.set_thread_count(threads)
    if variant.startswith("llvm"):
        dr.set_flag(dr.JitFlag.KernelHistory, True)
    return mi, dr


class Mitsuba:
    def __init__(self, mi, dr, variant):
        self.mi, self.dr, self.variant = mi, dr, variant
        self.jit = variant.startswith(("llvm", "cuda"))

    def load(self, scene, integrator, sampler, spp, size, max_depth, samples_per_pass=None):
        d = to_mitsuba.convert(scene, integrator=integrator, sampler=sampler, spp=spp,
                               width=size[0], height=size[1], max_depth=max_depth,
                               samples_per_pass=samples_per_pass)
        obj = self.mi.load_dict(d)
        real = int(obj.sensors()[0].sampler().sample_count())
        return obj, real

    def render(self, obj, seed):
        """(image, seconds, compile seconds): the seconds of mi.render and the
        read-back, less the kernel compilation Dr.Jit reports within them."""
        if self.jit:
            self.dr.kernel_history()  # clears it
        start = time.perf_counter()
        img = self.mi.render(obj, seed=seed)
        arr = np.array(img, dtype=np.float64)
        seconds = time.perf_counter() - start
        compile_s = 0.0
        if self.jit:
            for k in self.dr.kernel_history():
                if not k.get("cache_hit", 1):
                    compile_s += (k.get("codegen_time", 0) + k.get("backend_time", 0)) / 1000.0
        return arr[..., :3], seconds - compile_s, compile_s


# ------------------------------------------------------------------- main

def machine():
    """The CPU as `lscpu` names it, with its family, model and widest vector
    instructions: cloud CPUs often report only a brand ("AMD EPYC"), and
    tracer's speed (its native build) and Mitsuba's (its LLVM kernels) both
    depend on whether AVX-512 is there."""
    model = platform.processor() or platform.machine()
    details = []
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        field = lambda name: (re.search(rf"^{name}:\s*(.+)$", out, re.M) or [None, None])[1]
        model = (field("Model name") or model).strip()
        if field("CPU family") and field("Model"):
            details.append(f"family {field('CPU family').strip()}, model {field('Model').strip()}")
        flags = set((field("Flags") or "").split())
        if "avx512f" in flags:
            details.append("AVX-512")
        elif "avx2" in flags:
            details.append("AVX2")
    except OSError:
        pass
    cpu = f"{model} ({', '.join(details)})" if details else model
    return {"cpu": cpu, "cores": os.cpu_count(), "system": platform.platform()}


def git(*args):
    try:
        return subprocess.run(["git", "-C", REPO, *args], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def fmt_row(r):
    spp = f"{r['spp']}" if r.get("passes", 1) == 1 else f"{r['spp']} ({r['passes']} x {r['spp_per_pass']})"
    return (f"| {r['renderer']} | {r['integrator']} | {r['sampler']} | {spp} | "
            f"{r['seconds']:.2f} | {r['msamples_per_s']:.2f} | {r['relmse']:.4g} | "
            f"{r['efficiency']:.4g} |")


TABLE_HEAD = ("| renderer | integrator | sampler | spp | seconds | M samples/s | relMSE | "
              "efficiency |\n|---|---|---|---|---|---|---|---|")


def summarize(cfg, spp_per_pass, passes, secs, errs, pixels):
    sec = statistics.median(secs)
    err = statistics.fmean(errs)
    spp = spp_per_pass * passes
    return {**cfg, "spp": spp, "spp_per_pass": spp_per_pass, "passes": passes, "seconds": sec,
            "seconds_runs": secs, "relmse": err, "relmse_runs": errs,
            "msamples_per_s": pixels * spp / sec / 1e6,
            "efficiency": 1.0 / (err * sec) if err > 0 and sec > 0 else float("inf")}


def run_scene(scene, args, tracer, mits, images):
    settings = to_mitsuba.settings(scene)
    size = (args.size, args.size)
    max_depth = settings["max_depth"]
    pixels = size[0] * size[1]
    name = os.path.splitext(os.path.basename(scene))[0]
    log(f"\n== {scene}: {size[0]}x{size[1]}, max_depth {max_depth}, {args.threads} threads")
    ref, parts, ref_info = reference(tracer, scene, args, size, max_depth)
    ref_path = os.path.join(REPO, ref_info["path"])
    log(f"  reference floor (its own relMSE, estimated): {ref_info['floor']:.3g}")

    # Configurations: (labels, render(spp, seed, warm, passes) -> (image, seconds, spp)).
    configs = []
    loaded = {}

    def mi_config(integ, samp):
        def render(spp, seed, warm, passes):
            key = (integ, samp, spp)
            if key not in loaded:
                loaded[key] = mits.load(scene, integ, samp, spp, size, max_depth)
            obj, real = loaded[key]
            if warm:
                mits.render(obj, seed + 7777)
            total, seconds = 0.0, 0.0
            for j in range(passes):  # independent passes, averaged
                img, s, _ = mits.render(obj, seed + 1000 * j)
                total, seconds = total + img, seconds + s
            return total / passes, seconds, real
        return render

    def tr_config(integ):
        def render(spp, seed, warm, passes):
            assert passes == 1
            out = os.path.join(args.out, "tmp", f"{name}-{integ}.exr")
            img, s = tracer.render(scene, out, integ, spp, seed, size, max_depth)
            return img, s, spp
        return render

    for integ in args.mitsuba_integrators:
        for samp in args.samplers:
            configs.append(({"renderer": "mitsuba", "integrator": integ, "sampler": samp},
                            mi_config(integ, samp)))
    for integ in args.tracer_integrators:
        configs.append(({"renderer": "tracer", "integrator": integ, "sampler": "owen-sobol"},
                        tr_config(integ)))

    def measure(label, spp_of, seed0, warm):
        """Render every config args.runs times, round-robin; summarise."""
        results = {i: {"secs": [], "errs": [], "spp": None} for i in range(len(configs))}
        for run in range(args.runs):
            for i, (cfg, render) in enumerate(configs):
                spp, passes = spp_of(i, cfg)
                img, s, real = render(spp, seed0 + run, warm and run == 0, passes)
                results[i]["spp"], results[i]["passes"] = real, passes
                results[i]["secs"].append(s)
                results[i]["errs"].append(relmse(img, ref))
                if run == args.runs - 1:
                    path = os.path.join(args.out, "images",
                                        f"{name}-{label}-{cfg['renderer']}-{cfg['integrator']}"
                                        f"-{cfg['sampler']}.exr")
                    write_exr(path, img)
                    images.append(path)
                log(f"  [{label} run {run + 1}/{args.runs}] {cfg['renderer']:8s} "
                    f"{cfg['integrator']:8s} {cfg['sampler']:12s} {passes:2d} x {real:5d} spp "
                    f"{s:8.2f} s  relMSE {results[i]['errs'][-1]:.4g}")
        return [summarize(cfg, results[i]["spp"], results[i]["passes"], results[i]["secs"],
                          results[i]["errs"], pixels) for i, (cfg, _) in enumerate(configs)]

    fixed = measure("fixed", lambda i, cfg: (args.spp, 1), 0, True)

    # Check our relMSE against `tracer compare` on the last fixed-spp image of config 0.
    probe = os.path.join(args.out, "images",
                         f"{name}-fixed-{fixed[0]['renderer']}-{fixed[0]['integrator']}"
                         f"-{fixed[0]['sampler']}.exr")
    mine = relmse(read_exr(probe)[0], ref)
    theirs = tracer.compare(probe, ref_path)
    if abs(mine - theirs) > 1e-3 * max(abs(theirs), 1e-9) + 1e-7:
        raise SystemExit(f"error: relMSE {mine} differs from `tracer compare`'s {theirs}")

    equal = []
    budget = None
    if not args.no_equal_time:
        pt = [r for r in fixed if r["renderer"] == "tracer" and r["integrator"] == "pt"]
        budget = args.equal_time or (pt[0]["seconds"] if pt else fixed[0]["seconds"])
        log(f"  equal time: {budget:.2f} s each")

        def spp_at_budget(i, cfg):
            """(spp per pass, passes) reaching about `budget` seconds at the fixed-spp speed.
            A Mitsuba sampler that takes only some counts (ldsampler, orthogonal) renders
            several independent passes of the largest count it takes below the target."""
            r = fixed[i]
            want = max(1, round(budget * r["spp"] / r["seconds"]))
            if cfg["renderer"] == "mitsuba":
                down = to_mitsuba.valid_spp(cfg["sampler"], want)
                up = to_mitsuba.valid_spp(cfg["sampler"], want, up=True)
                options = [(down, max(1, round(want / down))), (up, 1)]
                return min(options, key=lambda o: (round(abs(math.log(o[0] * o[1] / want)), 6), o[1]))
            return want, 1

        equal = measure("equal-time", spp_at_budget, EQUAL_TIME_SEED, False)

    agree = None
    if not args.no_agreement:
        n = args.agreement_passes
        per = max(1, args.agreement_spp // n)
        log(f"  agreement: Mitsuba path, independent, {n} passes of {per} spp")
        obj, real = mits.load(scene, "path", "independent", per, size, max_depth,
                              samples_per_pass=min(per, 256))
        passes, secs = [], 0.0
        for k in range(n):
            img, s, c = mits.render(obj, AGREEMENT_SEED + k)
            passes.append(img)
            secs += s + c
        agree = agreement(passes, parts)
        agree["coarse"] = agreement(passes, parts, COARSE_BLOCK)
        agree["mitsuba_spp"] = real * n
        agree["mitsuba_seconds"] = secs
        long_img = np.mean(passes, axis=0)
        path = os.path.join(args.out, "images", f"{name}-agreement-mitsuba-path.exr")
        write_exr(path, long_img)
        images.append(path)
        agree["relmse_vs_reference"] = relmse(long_img, ref)
        if not args.no_control:
            # The same test on tracer's own path tracer: how often it flags
            # blocks when both sides are known to converge to the same image.
            log(f"  agreement control: tracer pt, {n} passes of {per} spp")
            out = os.path.join(args.out, "tmp", f"{name}-control.exr")
            ctrl, secs = [], 0.0
            for k in range(n):
                img, s = tracer.render(scene, out, "pt", per, AGREEMENT_SEED + k, size, max_depth)
                ctrl.append(img)
                secs += s
            control = agreement(ctrl, parts)
            control["coarse"] = agreement(ctrl, parts, COARSE_BLOCK)
            control["mitsuba_spp"] = per * n  # the same field name, for agreement_text
            control["seconds"] = secs
            agree["control"] = control
            agree["calibrated"] = calibrate(passes, ctrl, parts)
    return {"scene": scene, "size": list(size), "max_depth": max_depth, "reference": ref_info,
            "spp": args.spp, "fixed": fixed, "equal_time_budget_s": budget,
            "equal_time_given": bool(args.equal_time), "equal_time": equal,
            "agreement": agree}


def calibrate(passes, control_passes, parts):
    """Mitsuba's verdict at the finest block size of CALIBRATION_BLOCKS at
    which the control (tracer's `pt`, which converges to the reference)
    passes; None when it fails at all of them. A control that fails on
    small blocks says their means are too far from normal for the t test
    (rare, very bright samples); coarser blocks average more pixels."""
    for block in CALIBRATION_BLOCKS:
        control = agreement(control_passes, parts, block)
        if control["pass"]:
            mitsuba = agreement(passes, parts, block)
            mitsuba["control_worst_t"] = control["worst_t"]
            mitsuba["control_threshold_t"] = control["threshold_t"]
            return mitsuba
    return None


def calibrated_text(a):
    """The calibrated verdict of `a` (an agreement with a control), in words."""
    if "calibrated" not in a:
        return ""
    c = a["calibrated"]
    sizes = ", ".join(f"{b}x{b}" for b in CALIBRATION_BLOCKS)
    if c is None:
        return (f" Calibrated: the control fails at every block size tried ({sizes}), so "
                f"the test says nothing on this scene.")
    b = c["block_size"]
    return (f" Calibrated ({b}x{b} blocks, the finest of {sizes} at which the control "
            f"passes: worst |t| {abs(c['control_worst_t']):.2f} against a bound of "
            f"{c['control_threshold_t']:.2f}): {'PASS' if c['pass'] else 'FAIL'}, worst |t| = "
            f"{abs(c['worst_t']):.2f} against a bound of {c['threshold_t']:.2f}.")


def best_samplers(res):
    out = {}
    for table, key in (("fixed", "efficiency"), ("equal_time", "efficiency")):
        for integ in MI_INTEGRATORS:
            rows = [r for r in res[table] if r["renderer"] == "mitsuba" and r["integrator"] == integ]
            if rows:
                b = max(rows, key=lambda r: r[key])
                out[f"{table}/{integ}"] = b["sampler"]
    return out


def agreement_text(a, who="Mitsuba path"):
    w = a["worst_at"]
    ratio = ", ".join(f"{c} {r:.4f} ± {s:.4f}" for c, r, s in zip("RGB", a["ratio"], a["ratio_se"]))
    coarse = ""
    if a.get("coarse"):
        c = a["coarse"]
        coarse = (f" For context, {c['block_size']}x{c['block_size']} blocks: worst |t| = "
                  f"{abs(c['worst_t']):.2f}, bound {c['threshold_t']:.2f}, |t| > 3 in "
                  f"{100 * c['frac_abs_t_over_3']:.2f}%.")
    return (f"{'PASS' if a['pass'] else 'FAIL'}: {who} {a['mitsuba_spp']} spp "
            f"({a['passes']} passes) against the reference ({a['reference_parts']} parts), "
            f"{a['blocks']} blocks of {a['block_size']}x{a['block_size']} x 3 channels: worst "
            f"|t| = {abs(a['worst_t']):.2f} at block ({w['x']}, {w['y']}) {w['channel']} "
            f"({who.split()[0]} {w['mitsuba']:.4g}, reference {w['reference']:.4g}); Bonferroni bound "
            f"{a['threshold_t']:.2f} (1% family-wise, median dof {a['median_dof']:.0f}); smallest "
            f"p x tests = {a['min_p_bonferroni']:.3g}; |t| > 3 in "
            f"{100 * a['frac_abs_t_over_3']:.2f}% of tests; mean t^2 {a['mean_t2']:.2f}. "
            f"Image mean, {who.split()[0]} / reference: {ratio}.{coarse}")


def markdown(meta, results):
    lines = ["# Peers: Mitsuba 3", ""]
    lines += [f"- date: {meta['date']}",
              f"- machine: {meta['machine']['cpu']}, {meta['machine']['cores']} cores "
              f"(load average {meta['loadavg_start']} at the start, {meta['loadavg_end']} at "
              f"the end)",
              f"- tracer: {meta['tracer']} (git {meta['git']}{' with local changes' if meta['git_dirty'] else ''})",
              f"- Mitsuba {meta['mitsuba']} / Dr.Jit {meta['drjit']}, variant `{meta['variant']}`",
              f"- command: `{meta['command']}`",
              f"- {meta['threads']} threads, seeds 0..{meta['runs'] - 1}: seconds are medians of "
              f"{meta['runs']} runs, relMSE the mean over them; relMSE against tracer's `bdpt` "
              f"reference; efficiency = 1 / (relMSE x seconds); samples/s = pixels x spp / s",
              "- `lt` and `ptracer` cannot render mirrors and glass seen directly by the "
              "camera: on a scene with them, their relMSE is mostly that difference and "
              "barely falls with more samples",
              f"- wall time of the whole run: {meta['wall_minutes']:.1f} min", ""]
    for res in results:
        ref = res["reference"]
        lines += [f"## {res['scene']} ({res['size'][0]}x{res['size'][1]}, max_depth "
                  f"{res['max_depth']})", "",
                  f"Reference: tracer `bdpt`, {ref['spp']} spp ({ref['parts']} parts, "
                  f"{ref['seconds']:.0f} s); its own estimated relMSE (a floor under every "
                  f"figure): {ref['floor']:.3g}.", "",
                  f"Fixed spp ({res['spp']} requested):", "",
                  TABLE_HEAD] + [fmt_row(r) for r in res["fixed"]] + [""]
        if res["equal_time"]:
            source = ("--equal-time" if res.get("equal_time_given")
                      else "tracer `pt`'s time at the fixed spp")
            lines += [f"Equal time ({res['equal_time_budget_s']:.2f} s: {source}; "
                      f"`N (k x n)`: k independent passes of n spp, averaged, for "
                      f"samplers that take only some counts):", "", TABLE_HEAD] + [fmt_row(r) for r in res["equal_time"]] + [""]
        best = best_samplers(res)
        if best:
            lines += ["Best Mitsuba sampler by efficiency: " + "; ".join(
                f"{k}: `{v}`" for k, v in best.items()), ""]
        if res["agreement"]:
            lines += ["Agreement: " + agreement_text(res["agreement"])
                      + calibrated_text(res["agreement"]), ""]
            if res["agreement"].get("control"):
                lines += ["Control (the same test on tracer's own `pt`, which converges to the "
                          "reference's image): " + agreement_text(res["agreement"]["control"],
                                                                 "tracer pt"), ""]
    return "\n".join(lines)


README_BEGIN = "<!-- made by benches/peers/compare.py --readme from its results.json; do not edit -->"
README_END = "<!-- end of the table made by compare.py -->"


def readme_table(meta, results):
    """The README's table of renders against Mitsuba, between its markers."""
    m = meta["machine"]
    lines = [README_BEGIN, "",
             f"Rendering against Mitsuba {meta['mitsuba']} (`{meta['variant']}`, Dr.Jit "
             f"{meta['drjit']}) in the same run: {meta['threads']} threads, "
             f"{meta['date'][:10]}, {m['cpu']}, {m['cores']} cores, tracer at git {meta['git']}, "
             f"`{meta['command']}`. Efficiency is 1 / (relative MSE x seconds) at equal samples "
             f"per pixel, against Mitsuba's most efficient sampler for the scene. Mitsuba has "
             f"no bidirectional path tracer: tracer's `bdpt` is set against its `path`.", "",
             "| scene | tracer M samples/s | Mitsuba M samples/s | tracer / Mitsuba | "
             "efficiency, tracer / Mitsuba (its sampler) |",
             "|---|---|---|---:|---:|"]
    for res in results:
        scene = f"{os.path.splitext(os.path.basename(res['scene']))[0]} {res['size'][0]} x {res['size'][1]}, {res['spp']} spp"
        # Mitsuba has no BDPT: tracer's bdpt is set against its path tracer,
        # which estimates the same image.
        for ours, theirs in (("pt", "path"), ("lt", "ptracer"), ("bdpt", "path")):
            mine = [r for r in res["fixed"] if r["renderer"] == "tracer" and r["integrator"] == ours]
            peers = [r for r in res["fixed"] if r["renderer"] == "mitsuba" and r["integrator"] == theirs]
            if not mine or not peers:
                continue
            t = mine[0]
            fastest = max(peers, key=lambda r: r["msamples_per_s"])
            best = max(peers, key=lambda r: r["efficiency"])
            lines.append(f"| {scene} | `{ours}` {t['msamples_per_s']:.2f} | `{theirs}` "
                         f"{fastest['msamples_per_s']:.2f} (`{fastest['sampler']}`) | "
                         f"{t['msamples_per_s'] / fastest['msamples_per_s']:.2f}x | "
                         f"{t['efficiency'] / best['efficiency']:.2f}x (`{best['sampler']}`) |")
    def verdict(r):
        a = r["agreement"]
        text = (f"{os.path.splitext(os.path.basename(r['scene']))[0]}: "
                f"{'agrees' if a['pass'] else 'does not agree'} (worst |t| {abs(a['worst_t']):.1f} "
                f"against a bound of {a['threshold_t']:.1f}, {a['mitsuba_spp']} spp)")
        control = a.get("control")
        if control:
            text += (f"; the same test on tracer's own `pt`, which converges to the reference, "
                     f"{'passes' if control['pass'] else 'fails too'} (worst |t| "
                     f"{abs(control['worst_t']):.1f})")
        if control and not control["pass"] and "calibrated" in a:
            c = a["calibrated"]
            if c is None:
                last = CALIBRATION_BLOCKS[-1]
                text += (f", and fails on every block size up to {last}x{last}, so the test "
                         f"says nothing there")
            else:
                b = c["block_size"]
                text += (f"; on {b}x{b} blocks, where the control passes, Mitsuba "
                         f"{'agrees' if c['pass'] else 'does not agree'} (worst |t| "
                         f"{abs(c['worst_t']):.1f} against {c['threshold_t']:.1f})")
        return text

    verdicts = [verdict(r) for r in results if r["agreement"]]
    notes = [SCENE_NOTES[n] for n in
             (os.path.splitext(os.path.basename(r["scene"]))[0] for r in results if r["agreement"])
             if n in SCENE_NOTES]
    if verdicts:
        lines += ["", "Mitsuba's long `path` render against tracer's reference, block by block, "
                  "within noise at a 1% family-wise level: " + "; ".join(verdicts) + ". A failing "
                  "control means the test's normal approximation does not hold on that scene "
                  "(rare, very bright caustic samples), not that the images differ; see "
                  "[docs/benchmarks.md](docs/benchmarks.md#peers-mitsuba-3)."] + \
            (["", " ".join(notes)] if notes else [])
    lines += ["", README_END]
    return "\n".join(lines)


def update_readme(meta, results):
    path = os.path.join(REPO, "README.md")
    with open(path) as f:
        text = f.read()
    if README_BEGIN not in text or README_END not in text:
        raise SystemExit(f"error: {path} has no compare.py markers")
    head, rest = text.split(README_BEGIN, 1)
    tail = rest.split(README_END, 1)[1]
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(head + readme_table(meta, results) + tail)
    os.replace(tmp, path)
    log(f"updated the table in {os.path.relpath(path, REPO)}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", nargs="+", default=DEFAULT_SCENES)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--size", type=int, default=256, help="image width and height")
    ap.add_argument("--quick", action="store_true",
                    help="tiny settings: a smoke test in under a minute")
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--reference-parts", type=int, default=16)
    ap.add_argument("--fresh-reference", action="store_true", help="ignore a cached reference")
    ap.add_argument("--equal-time", type=float,
                    help="seconds per equal-time render (default: tracer pt's time at --spp)")
    ap.add_argument("--no-equal-time", action="store_true")
    ap.add_argument("--agreement-spp", type=int, default=4096)
    ap.add_argument("--agreement-passes", type=int, default=16)
    ap.add_argument("--no-agreement", action="store_true")
    ap.add_argument("--no-control", action="store_true",
                    help="skip the agreement check's control (tracer pt against the reference)")
    ap.add_argument("--samplers", nargs="+", default=MI_SAMPLERS, choices=to_mitsuba.SAMPLERS)
    ap.add_argument("--mitsuba-integrators", nargs="+", default=MI_INTEGRATORS,
                    choices=MI_INTEGRATORS)
    ap.add_argument("--tracer-integrators", nargs="+", default=TRACER_INTEGRATORS,
                    choices=TRACER_INTEGRATORS)
    ap.add_argument("--variant", default="llvm_ad_rgb",
                    help="Mitsuba variant (llvm_ad_rgb; scalar_rgb needs no LLVM)")
    ap.add_argument("--tracer", default=os.path.join(REPO, "target", "release", "tracer"))
    ap.add_argument("--tracer-commit",
                    help="for the record: the commit the --tracer binary was built from "
                         "(default: this checkout's HEAD)")
    ap.add_argument("--no-build", action="store_true",
                    help="do not run `cargo build --release` first")
    ap.add_argument("--out", default=os.path.join(REPO, "target", "peers"))
    ap.add_argument("--report", metavar="RESULTS_JSON",
                    help="render nothing: print the Markdown tables of an earlier run's results.json")
    ap.add_argument("--readme", action="store_true",
                    help="rewrite the README's table of renders against Mitsuba from this run "
                         "(or, with --report, from that run's results)")
    args = ap.parse_args(argv)
    if args.report:
        with open(args.report) as f:
            saved = json.load(f)
        print(markdown(saved["meta"], saved["results"]))
        if args.readme:
            update_readme(saved["meta"], saved["results"])
        return 0
    if args.quick:
        args.size, args.spp, args.runs = 64, 4, 1
        args.reference_spp, args.reference_parts = 64, 8
        args.agreement_spp, args.agreement_passes = 128, 8
        if args.out == ap.get_default("out"):
            args.out = os.path.join(REPO, "target", "peers", "quick")
    if args.size % BLOCK:
        ap.error(f"--size must be a multiple of {BLOCK}")
    if args.runs < 1 or args.reference_parts < 2 or args.agreement_passes < 2:
        ap.error("--runs must be >= 1, --reference-parts and --agreement-passes >= 2")
    os.chdir(REPO)
    wall = time.perf_counter()
    for d in ("tmp", "images"):
        os.makedirs(os.path.join(args.out, d), exist_ok=True)
    if not args.no_build:
        log("cargo build --release")
        if subprocess.run(["cargo", "build", "--release", "--quiet"]).returncode != 0:
            raise SystemExit("error: cargo build --release failed (or pass --no-build "
                             "--tracer PATH)")
    if not os.path.exists(args.tracer):
        raise SystemExit(f"error: no tracer binary at {args.tracer}")
    tracer = Tracer(args.tracer, args.threads, args.out)
    for s in args.scenes:  # refuse what cannot be converted before any work
        try:
            to_mitsuba.load(s)
        except OSError as e:
            raise SystemExit(f"error: {s}: {e}")
    mi, dr = setup_mitsuba(args.variant, args.threads)
    mits = Mitsuba(mi, dr, args.variant)
    for s in args.scenes:
        try:
            to_mitsuba.convert(s, spp=1, width=8, height=8)
        except to_mitsuba.Unsupported as e:
            raise SystemExit(f"error: {s}: cannot convert to Mitsuba: {e}")

    meta = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": machine(),
        "loadavg_start": " ".join(f"{x:.1f}" for x in os.getloadavg()),
        "tracer": tracer.version,
        "tracer_path": os.path.relpath(os.path.abspath(args.tracer), REPO),
        "git": args.tracer_commit or git("rev-parse", "--short", "HEAD"),
        "git_dirty": False if args.tracer_commit else
        bool(git("status", "--porcelain", "--", "src", "Cargo.toml", "Cargo.lock")),
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "variant": args.variant,
        "python": platform.python_version(),
        "threads": args.threads,
        "runs": args.runs,
        "command": "benches/peers/compare.py " + " ".join(sys.argv[1:] if argv is None else argv),
    }
    images = []
    results = [run_scene(s, args, tracer, mits, images) for s in args.scenes]
    meta["loadavg_end"] = " ".join(f"{x:.1f}" for x in os.getloadavg())
    meta["wall_minutes"] = (time.perf_counter() - wall) / 60
    shutil.rmtree(os.path.join(args.out, "tmp"), ignore_errors=True)

    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump({"meta": meta, "results": results}, f, indent=1)
    md = markdown(meta, results)
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write(md + "\n")
    print(md)
    if args.readme and not args.quick:
        update_readme(meta, results)
    log(f"\nwrote {os.path.relpath(os.path.join(args.out, 'results.json'), REPO)}, "
        f"results.md and {len(images)} images in {os.path.relpath(os.path.join(args.out, 'images'), REPO)}")
    if args.quick:
        log("(--quick: the agreement verdicts above rest on too few samples to mean anything)")
        return 0
    return 0 if all(r["agreement"] is None or r["agreement"]["pass"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
