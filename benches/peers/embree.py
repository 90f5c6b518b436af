#!/usr/bin/env python3
"""BVH build and ray traversal: tracer against Intel Embree 4 on the very
same triangles and rays, measured in one run.

For each input (an OBJ mesh, or a scene file whose camera makes the primary
rays), `tracer bench --save-rays` writes its ray sets (primary, diffuse,
incoherent, shadow) and the triangles it traced, and measures itself; then
Embree, through `embreex` (Embree 4.4 with TBB), builds a BVH over the same
triangles and traces the same rays, once per thread count, in a process
pinned to that many CPUs (so TBB's build uses exactly those); and the
`obvhs` crate (its CWBVH, `fast_build` preset) does the same through
`examples/obvhs_rays.rs`, also pinned. It prints one table per input:
Mrays/s for tracer, Embree and obvhs, tracer's ratio to each, and whether
the hit counts and the sums of closest-hit distances agree with Embree's.

Embree's build time is its commit (`rtcCommitScene`, which embreex calls
on the first query), not embreex's copy of the triangles into Embree's
buffers. Embree is called as embreex calls it: `rtcIntersect1` / `rtcOccluded1` one
ray at a time in a compiled loop over numpy arrays, the closest-hit query
returning the primitive ids (distances are read in a separate, untimed
pass). With more than one thread the rays are split into one contiguous
range per thread, traced from Python threads (embreex releases the GIL
around its loop).

With `--rounds N`, the three libraries are measured N times in turn
(tracer, Embree, obvhs, then again), tracer tracing the saved ray files
after the first round, and each figure is the median over the rounds of
each round's median of `--runs`: the machine's slow spells then fall on
every library alike. The tables then also give the range of the
per-round ratios to Embree.

With `--spatial-splits FRACTION`, tracer also traces the saved rays
through a second BVH built with spatial splits (`tracer bench
--spatial-splits`), and the table gains its figures and ratio to Embree.

    benches/peers/embree.py ../shared/meshes/dragon.obj --threads 1,2
    benches/peers/embree.py ../shared/meshes/sponza.obj --spatial-splits 0.3
    benches/peers/embree.py scenes/cornell-box.json --runs 3 --out target/embree

Needs `pip install embreex==4.4.0.post1 numpy` (requirements.txt).
"""

import argparse
import concurrent.futures
import datetime
import importlib.metadata
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

import compare  # this folder's peer harness: its description of the machine

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SETS = ("primary", "diffuse", "incoherent", "shadow")


def load_rays(path):
    """Origins, directions and far distances of a rays file; a ray with a
    non-zero tmin starts tmin further along (Embree's tnear is 0 here)."""
    r = np.fromfile(path, np.float32).reshape(-1, 8)
    tmin, tmax = r[:, 3], r[:, 7]
    origins = np.ascontiguousarray(r[:, :3] + r[:, 4:7] * tmin[:, None])
    dirs = np.ascontiguousarray(r[:, 4:7])
    far = np.ascontiguousarray(tmax - tmin)
    return origins, dirs, far


def median_seconds(runs, f):
    times = []
    for _ in range(max(1, runs)):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def worker(folder, threads, runs):
    """Embree's figures for one thread count (run in a pinned process)."""
    import embreex.mesh_construction as mesh
    import embreex.rtcore_scene as rts

    triangles = np.fromfile(os.path.join(folder, "triangles.f32"), np.float32).reshape(-1, 3, 3)
    probe = (np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
    builds = []
    for _ in range(max(1, min(runs, 3))):
        # embreex copies the triangles into Embree's buffers in a slow loop
        # of its own (about 1 s for the dragon): left out. Embree builds its
        # BVH when the scene is committed, on the first query: timed.
        scene = rts.EmbreeScene()
        mesh.TriangleMesh(scene, triangles)
        start = time.perf_counter()
        scene.run(*probe)
        builds.append(time.perf_counter() - start)
    build_seconds = statistics.median(builds)
    pool = concurrent.futures.ThreadPoolExecutor(threads)

    def split(n):
        bounds = np.linspace(0, n, threads + 1).astype(int)
        return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]

    def parallel(o, d, far, query):
        parts = split(len(o))
        # embreex writes the hit distances into the array it is given: a fresh copy each time.
        futures = [pool.submit(scene.run, o[p], d[p], far[p].copy(), query) for p in parts]
        return np.concatenate([f.result() for f in futures])

    traces = []
    for name in SETS:
        path = os.path.join(folder, f"{name}.rays")
        if not os.path.exists(path):
            continue
        o, d, far = load_rays(path)
        closest = scene.run(o, d, far.copy(), output=1)
        hit = closest["primID"] != -1
        distance_sum = float(closest["tfar"][hit].astype(np.float64).sum())
        for query, kind in (("closest", "INTERSECT"), ("any", "OCCLUDED")):
            result = parallel(o, d, far, kind)
            hits = int((result != -1).sum())
            seconds = median_seconds(runs, lambda: parallel(o, d, far, kind))
            traces.append({"rays": name, "query": query, "threads": threads, "count": len(o),
                           "mrays_per_second": len(o) / seconds / 1e6, "hits": hits,
                           "distance_sum": distance_sum if query == "closest" else 0.0})
    return {"threads": threads, "build_seconds": build_seconds, "traces": traces}


def run_worker(folder, threads, runs):
    """Embree's figures in a child process pinned to the first `threads` CPUs."""
    cpus = sorted(os.sched_getaffinity(0))[:threads]
    code = ("import os, sys, json; sys.path.insert(0, %r); os.sched_setaffinity(0, %r); "
            "import embree; print(json.dumps(embree.worker(%r, %d, %d)))"
            % (os.path.dirname(os.path.abspath(__file__)), cpus, folder, threads, runs))
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def obvhs_version():
    """The obvhs version Cargo.lock pins (what examples/obvhs_rays.rs is built with)."""
    with open(os.path.join(ROOT, "Cargo.lock")) as f:
        packages = f.read().split("[[package]]")
    for p in packages:
        if 'name = "obvhs"' in p:
            return p.split('version = "')[1].split('"')[0]
    return "unknown"


def run_obvhs(binary, folder, threads, runs):
    """obvhs's figures (examples/obvhs_rays.rs), pinned like Embree's."""
    cpus = sorted(os.sched_getaffinity(0))[:threads]
    out = subprocess.run([binary, folder, str(threads), str(runs)], check=True,
                         capture_output=True, text=True,
                         preexec_fn=lambda: os.sched_setaffinity(0, cpus))
    return json.loads(out.stdout.strip().splitlines()[-1])


def tracer_bench(tracer, source, folder, threads, runs):
    cmd = [tracer, "bench", source, "--json", "--runs", str(runs), "--save-rays", folder,
           "--threads", ",".join(map(str, threads))]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def tracer_rays(tracer, source, folder, threads, runs, extra=()):
    """tracer tracing the ray files the first run saved, one call per set
    (a later round, or with `extra` options such as spatial splits)."""
    report = None
    for name in SETS:
        path = os.path.join(folder, f"{name}.rays")
        if not os.path.exists(path):
            continue
        cmd = [tracer, "bench", source, "--json", "--runs", str(runs), "--rays-file", path,
               "--threads", ",".join(map(str, threads)), *extra]
        out = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        if report is None:
            report = out
        else:
            report["traces"] += out["traces"]
    return report


def tracer_bench_split(tracer, source, folder, threads, runs, budget):
    """tracer with spatial splits, tracing the ray files the first run saved."""
    return tracer_rays(tracer, source, folder, threads, runs, ["--spatial-splits", str(budget)])


def merge_rounds(rounds):
    """One report from the same report made in several rounds: every figure
    the median over the rounds, each trace keeping its rounds' figures."""
    first = json.loads(json.dumps(rounds[0]))
    key = lambda t: (t["rays"], t["query"], t["threads"])
    by_key = [{key(t): t for t in r["traces"]} for r in rounds]
    for t in first["traces"]:
        values = [r[key(t)]["mrays_per_second"] for r in by_key if key(t) in r]
        t["rounds"] = values
        t["mrays_per_second"] = statistics.median(values)
    if "builds" in first:
        for i, b in enumerate(first["builds"]):
            b["seconds"] = statistics.median(r["builds"][i]["seconds"] for r in rounds)
    if "build_seconds" in first:
        first["build_seconds"] = statistics.median(r["build_seconds"] for r in rounds)
    return first


def ratio_range(mine, theirs):
    """min-max of the per-round ratios, when there were several rounds."""
    a, b = mine.get("rounds"), theirs.get("rounds")
    if not a or not b or len(a) < 2:
        return None
    ratios = [x / y for x, y in zip(a, b)]
    return f"{min(ratios):.2f}-{max(ratios):.2f}"


def table(ours, embree, obvhs, split=None):
    lines = ["| rays | query | threads | tracer Mrays/s | Embree Mrays/s | obvhs Mrays/s "
             "| tracer / Embree | tracer / obvhs | hits (tracer, Embree, obvhs) | distance sums |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|---|"]
    if split:
        lines[0] += " tracer, spatial splits, Mrays/s | spatial splits / Embree | hits |"
        lines[1] += "---:|---:|---|"
    splits = {(t["rays"], t["query"], t["threads"]): t for t in split["traces"]} if split else {}
    theirs = {(t["rays"], t["query"], t["threads"]): t for e in embree for t in e["traces"]}
    others = {(t["rays"], t["query"], t["threads"]): t for o in obvhs for t in o["traces"]}
    for t in ours["traces"]:
        key = (t["rays"], t["query"], t["threads"])
        e = theirs.get(key)
        if e is None:
            continue
        o = others.get(key)
        counts = [e["hits"]] + ([o["hits"]] if o else [])
        same = "equal" if all(c == t["hits"] for c in counts) else \
            ", ".join(str(c) for c in [t["hits"]] + counts)
        if t["query"] == "closest" and e["distance_sum"] > 0:
            rel = abs(t["distance_sum"] - e["distance_sum"]) / e["distance_sum"]
            sums = f"rel. diff {rel:.1e}"
        else:
            sums = "-"
        mine = t["mrays_per_second"]
        spread = ratio_range(t, e)
        obvhs_cells = (f"{o['mrays_per_second']:.2f}", f"{mine / o['mrays_per_second']:.2f}") \
            if o else ("-", "-")
        row = (f"| {t['rays']} | {t['query']} | {t['threads']} | {mine:.2f} | "
               f"{e['mrays_per_second']:.2f} | {obvhs_cells[0]} | "
               f"{mine / e['mrays_per_second']:.2f}"
               + (f" ({spread})" if spread else "")
               + f" | {obvhs_cells[1]} | {same} | {sums} |")
        if split:
            sp = splits.get(key)
            if sp:
                agree = "equal" if sp["hits"] == e["hits"] else f"{sp['hits']}, Embree {e['hits']}"
                row += (f" {sp['mrays_per_second']:.2f} | "
                        f"{sp['mrays_per_second'] / e['mrays_per_second']:.2f} | {agree} |")
            else:
                row += " - | - | - |"
        lines.append(row)
    lines += ["", "| build | threads | tracer s | Embree s | obvhs s | Embree / tracer | obvhs / tracer |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    if split:
        lines[-2] += " tracer, spatial splits, s | Embree / spatial splits | references |"
        lines[-1] += "---:|---:|---:|"
    split_builds = {b["threads"]: b["seconds"] for b in split["builds"]} if split else {}
    builds = {e["threads"]: e["build_seconds"] for e in embree}
    obvhs_builds = {o["threads"]: o["build_seconds"] for o in obvhs}
    for b in ours["builds"]:
        if b["threads"] in builds:
            e = builds[b["threads"]]
            o = obvhs_builds.get(b["threads"])
            cells = (f"{o:.3f}", f"{o / b['seconds']:.2f}") if o else ("-", "-")
            row = (f"| {ours['triangles']} triangles | {b['threads']} | {b['seconds']:.3f} | "
                   f"{e:.3f} | {cells[0]} | {e / b['seconds']:.2f} | {cells[1]} |")
            if split:
                sb = split_builds.get(b["threads"])
                extra = split["references"] / split["triangles"] - 1
                row += (f" {sb:.3f} | {e / sb:.2f} | +{100 * extra:.1f}% |" if sb
                        else " - | - | - |")
            lines.append(row)
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("inputs", nargs="+", help="OBJ meshes or scene files")
    ap.add_argument("--threads", default="1,2", help="thread counts, e.g. 1,2")
    ap.add_argument("--runs", type=int, default=5, help="timed runs per figure (median)")
    ap.add_argument("--rounds", type=int, default=1,
                    help="measure the libraries this many times in turn (median of rounds)")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "embree"))
    ap.add_argument("--tracer", default=os.path.join(ROOT, "target", "release", "tracer"))
    ap.add_argument("--obvhs", default=os.path.join(ROOT, "target", "release", "examples", "obvhs_rays"),
                    help="the obvhs_rays example binary")
    ap.add_argument("--no-obvhs", action="store_true", help="leave obvhs out")
    ap.add_argument("--no-build", action="store_true", help="do not run cargo build --release")
    ap.add_argument("--spatial-splits", type=float, metavar="FRACTION",
                    help="also trace with a BVH built with spatial splits, this reference budget")
    args = ap.parse_args(argv)
    threads = [int(t) for t in args.threads.split(",")]
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "tracer",
                        "--example", "obvhs_rays"], cwd=ROOT, check=True)
    os.makedirs(args.out, exist_ok=True)
    report = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": f"{compare.machine()['cpu']}, {os.cpu_count()} CPUs",
        "embreex": importlib.metadata.version("embreex"),
        "tracer": subprocess.run([args.tracer, "--version"], capture_output=True, text=True).stdout.strip(),
        "inputs": [],
    }
    md = [f"# tracer against Embree\n\n- date: {report['date']}\n- machine: {report['machine']}\n"
          f"- {report['tracer']}; embreex {report['embreex']} (Embree 4.4); obvhs {obvhs_version()} (CWBVH, fast_build)\n"
          f"- medians of {args.runs} runs"
          + (f", then the median of {args.rounds} rounds taken in turn (in brackets: the"
             " range of the rounds' ratios to Embree)" if args.rounds > 1 else "")
          + "; Mrays/s = rays / seconds\n"
          + (f"- spatial splits: reference budget {args.spatial_splits}\n"
             if args.spatial_splits is not None else "")]
    for source in args.inputs:
        name = os.path.splitext(os.path.basename(source))[0]
        folder = os.path.join(args.out, name)
        print(f"== {source}", flush=True)
        rounds = []
        for r in range(max(1, args.rounds)):
            if r == 0:
                ours = tracer_bench(args.tracer, source, folder, threads, args.runs)
            else:
                print(f"   round {r + 1} of {args.rounds}", flush=True)
                ours = tracer_rays(args.tracer, source, folder, threads, args.runs)
            embree = [run_worker(folder, t, args.runs) for t in threads]
            obvhs = [] if args.no_obvhs else [run_obvhs(args.obvhs, folder, t, args.runs)
                                              for t in threads]
            rounds.append((ours, embree, obvhs))
        ours = merge_rounds([r[0] for r in rounds])
        embree = [merge_rounds([r[1][i] for r in rounds]) for i in range(len(threads))]
        obvhs = [merge_rounds([r[2][i] for r in rounds]) for i in range(len(rounds[0][2]))]
        split = None if args.spatial_splits is None else tracer_bench_split(
            args.tracer, source, folder, threads, args.runs, args.spatial_splits)
        report["inputs"].append({"input": source, "tracer": ours, "embree": embree, "obvhs": obvhs,
                                 "tracer_spatial_splits": split})
        text = table(ours, embree, obvhs, split)
        print(text, flush=True)
        md.append(f"## {source} ({ours['triangles']} triangles)\n\n{text}\n")
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(report, f, indent=1)
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write("\n".join(md))
    print(f"wrote {args.out}/results.json and results.md")


if __name__ == "__main__":
    main()
