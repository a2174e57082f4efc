#!/usr/bin/env python3
"""Image-based radiosity against instant radiosity and antiradiance (issue 32, "where it
breaks"): per scene, a path-traced reference at the study size (cached), then each method's
render at that size with `--json`, measured with `compare`. Prints one markdown table: the
method and its setting, the one-time build (setup: VPLs, hemicubes, warp, or linking and the
solve), the frame (what a moved camera costs), the cube's or the solver's memory, and the
relative RMSE against the reference.

    python3 scripts/ibr-scaling.py [--bin B] [--spp N] [--size WxH] [--backend gpu] SCENE...
"""
import argparse, json, os, subprocess, sys, tempfile, time

ap = argparse.ArgumentParser()
ap.add_argument("scenes", nargs="+")
ap.add_argument("--bin", default="target/release/antiradiance")
ap.add_argument("--spp", type=int, default=1024)
ap.add_argument("--size", default="128x128")
ap.add_argument("--backend", default="gpu")
ap.add_argument("--cubes", default="64,128,256")
ap.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "ibr-scaling"))
a = ap.parse_args()
w, h = a.size.split("x")
os.makedirs(a.out, exist_ok=True)


def run(args):
    r = subprocess.run([a.bin] + args, capture_output=True, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["?"])[-1]
        print(f"failed: {' '.join(args)}: {last}", file=sys.stderr)
        return None
    return r


def cpu():
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return "?"


rows = []
for scene in a.scenes:
    name = os.path.splitext(os.path.basename(scene))[0]
    ref = os.path.join(a.out, f"{name}-ref-{a.size}-{a.spp}.exr")
    if not os.path.exists(ref):
        if run(["reference", scene, "--spp", str(a.spp), "--width", w, "--height", h, "--exr", ref]) is None:
            continue
    runs = [(f"image-based radiosity, cube {c}", ["--method", "image-based-radiosity", "--cube", c])
            for c in a.cubes.split(",")]
    runs += [("instant radiosity", ["--method", "instant-radiosity"]), ("antiradiance", [])]
    for label, extra in runs:
        exr = os.path.join(a.out, f"{name}-{len(rows)}.exr")
        js = exr + ".json"
        t = time.time()
        if run(["render", scene, "--width", w, "--height", h, "--backend", a.backend, "-o", exr,
                "--json", js] + extra) is None:
            continue
        wall = time.time() - t
        r = json.load(open(js))
        p = r["pass_ms"]
        f = (r.get("method_report") or {}).get("figures", {})
        frame = sum(p.get(k, 0.0) for k in ("frame", "vertex_values", "gbuffer", "splat", "direct_blocks", "compose", "interpolate"))
        if "cube_bytes" in f:
            mem = f["cube_bytes"]
            build = f["hemicube_ms"] + f["warp_ms"] + f["trace_ms"]
            note = f"{int(f['vpls'])} VPLs, {int(f['cube_layers']):,} layers"
        else:
            mem = None
            build = r["total_ms"] - frame
            note = f"{int(f['vpls'])} VPLs" if "vpls" in f else f"{r['links']:,} links, {r['iterations']} iterations"
        c = run(["compare", exr, ref])
        if c is None:
            continue
        m = json.loads(c.stdout)
        rows.append((name, label, build, frame, mem, m["rel_rmse"], note, wall))

print(f"{cpu()}, {os.cpu_count()} cores; {a.backend} backend; {a.size}, references {a.spp} spp\n")
print("| scene | method | build ms | frame ms | cube MB | rel. RMSE | notes |")
print("|---|---|---|---|---|---|---|")
for name, label, build, frame, mem, err, note, wall in rows:
    mb = f"{mem / 1e6:.1f}" if mem is not None else "–"
    print(f"| {name} | {label} | {build:,.0f} | {frame:,.0f} | {mb} | {err:.3f} | {note} |")
