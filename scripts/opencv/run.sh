#!/usr/bin/env bash
# Compares ocellus with OpenCV on the same data (see compare_calibration.py). Makes a virtual
# environment with opencv-python-headless in target/opencv-venv (network needed once).
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/opencv/venv.sh
"$PY" scripts/opencv/compare_calibration.py target/release/ocellus "${1:-20}"
