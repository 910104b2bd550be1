#!/usr/bin/env bash
# Compares `ocellus track` with OpenCV's CamShift on the generated ball sequences (see
# camshift_tracking.py). Makes the OpenCV virtual environment in target/opencv-venv.
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/opencv/venv.sh
"$PY" scripts/opencv/camshift_tracking.py target/release/ocellus "${1:-1,2,3}"
