#!/usr/bin/env bash
# Installs the system packages ocellus needs on a fresh Debian machine.
# The build needs a Rust toolchain and a C compiler; video input (ocellus attend/surprise and
# their tests) runs the ffmpeg program as a subprocess; the GPU backend needs a Vulkan loader
# and, without a GPU, a software Vulkan driver; the Python package's tests need python3 with
# venv; the report's browser test opens the generated page in headless Chromium.
set -euo pipefail

need=()
command -v cc >/dev/null 2>&1 || need+=(gcc)
command -v pkg-config >/dev/null 2>&1 || need+=(pkg-config)
command -v ffmpeg >/dev/null 2>&1 || need+=(ffmpeg)
# The GPU backend's tests (crates/ocellus-gpu) run on Mesa's software Vulkan driver
# (lavapipe) where there is no GPU.
ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1 || need+=(mesa-vulkan-drivers)
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || need+=(libvulkan1)
# The Python package's tests run in a virtual environment (python3 -m venv, with pip).
command -v python3 >/dev/null 2>&1 || need+=(python3)
python3 -m venv --help >/dev/null 2>&1 || need+=(python3-venv)
# The report's browser test (crates/ocellus-cli/tests/report_browser.rs) runs headless Chromium.
command -v chromium >/dev/null 2>&1 || need+=(chromium)

if [ ${#need[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
  echo "setup: installing ${need[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}"
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install Rust (https://rustup.rs) and run again" >&2
  exit 1
fi
echo "setup: ok"
