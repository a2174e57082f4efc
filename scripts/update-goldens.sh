#!/usr/bin/env bash
# Regenerates tests/golden/*.exr with the CPU backend at the reduced settings the golden test
# defines (tests/frame.rs, bundled_scenes_match_golden_images). Run after an intended change of
# the image formation.
set -euo pipefail
cd "$(dirname "$0")/.."
UPDATE_GOLDENS=1 cargo test --release --test frame bundled_scenes_match_golden_images -- --nocapture
