#!/usr/bin/env bash
# One command for a lent GPU (issue 30): profiles the bundled scenes, animates the moving box, and
# renders the Cornell box and MNRoom at 512² for the frame against one iteration, and writes
# OUT/gpu-bench.json (every run's report, with the device) and OUT/gpu-bench.md (one table: per-pass
# ms, iteration ms, the frame's passes, the moving box's frame ms and fps, memory, device and
# driver); each run's own output goes to OUT/raw.tar.gz (the device tool brings back 8 files).
#
#   scripts/gpu-bench.sh [OUT]      OUT defaults to $OUT (the device tool's folder) or gpu-bench/
#
# Uses target/release/antiradiance when it exists (build it here and carry it), else builds it.
# Each scene gets at most $SCENE_LIMIT seconds (default 40) so the whole stays under 4 minutes;
# a scene that runs out is listed as such, not dropped. DEVICE selects a Vulkan device by name.
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-${OUT:-gpu-bench}}
BIN=${BIN:-target/release/antiradiance}
LIMIT=${SCENE_LIMIT:-40}
mkdir -p "$OUT/raw"
now() { date +%s.%N; }
since() { python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" "$1" "$(now)"; }
if [ ! -x "$BIN" ]; then
    cargo build --release || exit 1
fi
dev=()
[ -n "${DEVICE:-}" ] && dev=(--device "$DEVICE")

RAW="$OUT/raw"
(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true) > "$RAW/nvidia-smi.txt" 2>&1
status="$RAW/status.txt"
: > "$status"
for s in cornell-box cornell-box-glossy mnroom veach-bidir dragon-room breakfast-room; do
    start=$(now)
    timeout "$LIMIT" "$BIN" profile "scenes/$s.toml" --frames 3 --warmup 1 "${dev[@]}" \
        --json "$RAW/profile-$s.json" > "$RAW/profile-$s.txt" 2>&1
    rc=$?
    echo "$s profile rc=$rc wall_s=$(since "$start")" >> "$status"
done
# The frame (G-buffer, splat, compose) against one iteration, from render's pass_ms.
for s in cornell-box mnroom; do
    start=$(now)
    timeout "$LIMIT" "$BIN" render "scenes/$s.toml" --width 512 --height 512 "${dev[@]}" \
        -o "$RAW/render-$s.exr" --json "$RAW/render-$s.json" > "$RAW/render-$s.txt" 2>&1
    echo "$s render rc=$? wall_s=$(since "$start")" >> "$status"
done
start=$(now)
timeout "$LIMIT" "$BIN" animate scenes/cornell-box-moving.toml --out "$RAW/animate" --frames 12 \
    "${dev[@]}" > "$RAW/animate.txt" 2>&1
echo "cornell-box-moving animate rc=$? wall_s=$(since "$start")" >> "$status"

python3 - "$OUT" <<'EOF'
import csv, json, os, sys
out = sys.argv[1]
raw = os.path.join(out, "raw")
status = {}
for line in open(os.path.join(raw, "status.txt")):
    parts = line.split()
    status[(parts[0], parts[1])] = dict(p.split("=") for p in parts[2:])
runs, rows = {}, []
device = "?"
for (scene, kind), st in status.items():
    if kind != "profile":
        continue
    path = os.path.join(raw, f"profile-{scene}.json")
    if st["rc"] != "0" or not os.path.exists(path):
        rows.append(f"| {scene} | rc {st['rc']} after {float(st['wall_s']):.0f} s (see profile-{scene}.txt) |||||||")
        continue
    r = json.load(open(path))
    runs[scene] = r
    device = r.get("device_name", device)
    passes = r.get("passes", {})
    def ms(k):
        v = passes.get(k, {}).get("median_ms")
        return f"{v:.2f}" if isinstance(v, (int, float)) else "–"
    it = r.get("frame", {}).get("median_ms")
    wall = r.get("iteration_wall", {}).get("median_ms")
    mem = r.get("memory_bytes", {}).get("total")
    rows.append("| {} | {} | {} | {} | {} | {} | {} | {} |".format(
        scene, " / ".join(ms(k) for k in ("global", "push", "local", "pull")),
        f"{it:.2f}" if isinstance(it, (int, float)) else "–",
        f"{wall:.2f}" if isinstance(wall, (int, float)) else "–",
        f"{1000.0 / wall:.1f}" if isinstance(wall, (int, float)) and wall > 0 else "–",
        f"{mem / 1e6:.0f} MB" if isinstance(mem, (int, float)) else "–",
        r.get("links", "–"), st["wall_s"]))
anim = {}
frames = os.path.join(raw, "animate", "frames.csv")
if os.path.exists(frames):
    rows_csv = list(csv.DictReader(open(frames)))[1:]  # the first frame is solved from scratch
    if rows_csv:
        med = lambda k: sorted(float(r[k]) for r in rows_csv)[len(rows_csv) // 2]
        anim = {"frames": len(rows_csv), "median_total_ms": med("total_ms"),
                "median_update_ms": med("update_ms"), "median_solve_ms": med("solve_ms"),
                "median_draw_ms": med("draw_ms")}
renders = {}
for scene in ("cornell-box", "mnroom"):
    path = os.path.join(raw, f"render-{scene}.json")
    if os.path.exists(path):
        r = json.load(open(path))
        p = r["pass_ms"]
        it = sum(p.get(k, 0.0) for k in ("global", "local", "push", "pull")) / max(r["iterations"], 1)
        fr = sum(p.get(k, 0.0) for k in ("vertex_values", "gbuffer", "splat", "direct_blocks", "compose"))
        renders[scene] = {"pass_ms": p, "iterations": r["iterations"], "iteration_ms": it,
                          "frame_ms": fr, "frame_over_iteration": fr / it if it > 0 else None}
smi = open(os.path.join(raw, "nvidia-smi.txt")).read().strip()
json.dump({"device": device, "nvidia_smi": smi, "renders": renders, "status": {f"{a} {b}": v for (a, b), v in status.items()},
           "profiles": runs, "animate": anim}, open(os.path.join(out, "gpu-bench.json"), "w"), indent=1)
with open(os.path.join(out, "gpu-bench.md"), "w") as f:
    f.write(f"Device: {device} ({smi})\n\n")
    f.write("| scene | global / push / local / pull ms (GPU, median) | iteration ms (GPU) | iteration ms (wall) | iterations/s | solver memory | links | run s |\n")
    f.write("|---|---|---|---|---|---|---|---|\n")
    f.write("\n".join(rows) + "\n")
    if anim:
        f.write("\nMoving Cornell box (`animate`, {frames} warm-started frames, medians): update {median_update_ms:.1f} ms, solve {median_solve_ms:.1f} ms, draw {median_draw_ms:.1f} ms, frame {median_total_ms:.1f} ms ({fps:.1f} fps).\n".format(fps=1000.0 / anim["median_total_ms"], **anim))
    for scene, r in renders.items():
        p = r["pass_ms"]
        f.write(f"\n{scene} at 512×512 (`render`, {r['iterations']} iterations): G-buffer {p.get('gbuffer', 0):.2f} ms, "
                f"splat {p.get('splat', 0):.2f}, compose {p.get('compose', 0):.2f}: frame {r['frame_ms']:.2f} ms "
                f"against {r['iteration_ms']:.2f} ms per iteration ({r['frame_over_iteration']:.2f}×).\n")
print(open(os.path.join(out, "gpu-bench.md")).read())
EOF
tar -czf "$OUT/raw.tar.gz" -C "$OUT" raw && rm -rf "$RAW"
