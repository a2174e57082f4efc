#!/usr/bin/env bash
# Makes the README's error-vs-time figures: a path-traced reference and a `study` for each named
# bundled scene (default: cornell-box). Usage:
#   scripts/study-bundled.sh OUTDIR [scene ...]
# Environment: BIN (default: cargo's release binary), SIZE (default 256), REF_SPP (default 4096),
# STUDY_ARGS (extra flags for `study`).
set -euo pipefail
out=${1:?usage: study-bundled.sh OUTDIR [scene ...]}
shift || true
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(cornell-box)
size=${SIZE:-256}
spp=${REF_SPP:-4096}
if [ -z "${BIN:-}" ]; then
  cargo build --release --quiet
  BIN=target/release/antiradiance
fi
mkdir -p "$out"
for s in "${scenes[@]}"; do
  ref="$out/ref/$s.exr"
  mkdir -p "$out/ref"
  [ -f "$ref" ] || "$BIN" reference "scenes/$s.toml" --spp "$spp" --width "$size" --height "$size" \
    --seed 1 --exr "$ref" --json "$out/ref/$s.json"
  # shellcheck disable=SC2086
  "$BIN" study "scenes/$s.toml" --reference "$ref" --out "$out/$s" --width "$size" \
    --height "$size" ${STUDY_ARGS:-}
done
