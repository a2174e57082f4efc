#!/bin/bash
# The frame against the solve (issue 30): renders the bundled Cornell box at 512² with each
# binary in turn, N times alternating, and prints the medians of the frame passes, one solver
# iteration and their ratio from `render --json`'s pass_ms, with this machine's CPU.
# usage: scripts/frame-ratio.sh BINARY[@SCENE] [BINARY[@SCENE] ...]   (N=3 by default; set N=5
# for more); a run's scene is the bundled Cornell box unless given after `@` (a copy with other
# settings compares those settings on one binary).
set -euo pipefail
N=${N:-3}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
root=$(cd "$(dirname "$0")/.." && pwd)
for i in $(seq "$N"); do
  b=0
  for arg in "$@"; do
    bin=${arg%%@*}
    scene=$root/scenes/cornell-box.toml
    [[ $arg == *@* ]] && scene=${arg#*@}
    "$bin" render "$scene" --width 512 --height 512 \
      -o "$dir/x.png" --json "$dir/r$b-$i.json" >/dev/null 2>&1
    b=$((b + 1))
  done
done
echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; medians of $N runs"
b=0
for bin in "$@"; do
  python3 - "$dir" "$b" "$N" "$bin" <<'PY'
import json, statistics as st, sys
d, b, n, name = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
rs = [json.load(open(f"{d}/r{b}-{i + 1}.json")) for i in range(n)]
it = lambda r: sum(r["pass_ms"][k] for k in ["global", "local", "push", "pull"]) / r["iterations"]
fr = lambda r: sum(r["pass_ms"].get(k, 0.0) for k in ["vertex_values", "gbuffer", "splat", "direct_blocks", "compose"])
m = lambda f: st.median(f(r) for r in rs)
print(f"{name}: compose {m(lambda r: r['pass_ms']['compose']):.0f} ms, direct_blocks "
      f"{m(lambda r: r['pass_ms'].get('direct_blocks', 0.0)):.0f}, splat "
      f"{m(lambda r: r['pass_ms'].get('splat', 0.0)):.0f}, gbuffer {m(lambda r: r['pass_ms']['gbuffer']):.0f}, "
      f"frame {m(fr):.0f}, one iteration {m(it):.0f}; frame/iteration {st.median(fr(r) / it(r) for r in rs):.2f}")
PY
  b=$((b + 1))
done
