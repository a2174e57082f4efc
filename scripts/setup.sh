#!/usr/bin/env bash
# Installs the system packages antiradiance needs on Debian 12 (idempotent; skips apt when present).
# Vulkan (lavapipe, loader, validation layers) for the GPU passes; glslc compiles the shaders at build time.
set -euo pipefail
pkgs=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers vulkan-tools
      glslc spirv-tools pkg-config
      xvfb xauth libx11-6 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0)
missing=()
for p in "${pkgs[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install a Rust toolchain >= 1.82 (rustup) and re-run" >&2
  exit 1
fi
