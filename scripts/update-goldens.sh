#!/usr/bin/env bash
# Regenerates tests/golden/*.exr with the CPU backend at the reduced settings the golden test
# uses (tests/frame.rs, golden_settings). Run after an intended change of the image formation.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release
for scene in cornell-box cornell-box-glossy mnroom; do
    size="96 96"
    [ "$scene" = mnroom ] && size="96 72"
    set -- $size
    ./target/release/antiradiance render "scenes/$scene.toml" --backend cpu \
        --width "$1" --height "$2" --bins 32 --iterations 3 --shadow-map-size 512 \
        --exr "tests/golden/$scene.exr"
done
