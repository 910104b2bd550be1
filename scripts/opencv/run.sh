#!/usr/bin/env bash
# Compares ocellus with OpenCV on the same data (see compare_calibration.py). Makes a virtual
# environment with opencv-python-headless in target/opencv-venv (network needed once).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release -q
if [ ! -x target/opencv-venv/bin/python ]; then
  python3 -m venv target/opencv-venv
  target/opencv-venv/bin/pip install -q opencv-python-headless numpy
fi
target/opencv-venv/bin/python scripts/opencv/compare_calibration.py target/release/ocellus "${1:-20}"
