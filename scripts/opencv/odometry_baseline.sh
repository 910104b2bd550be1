#!/usr/bin/env bash
# Issue 7's baseline on this machine: OpenCV pyramidal LK + RANSAC partial affine
# (lk_odometry.py) against `ocellus odometry` (robust mode) on the generated floors, 3 seeds,
# easy and hard, each also as a real camera sees it (`synth ground --real-camera`: area pixels,
# lens distortion, vignetting; variants real-easy, real-hard). Prints one line per run:
# texture variant seed, then final drift % of the path, final heading error (degrees) and ATE
# RMSE (mm) of each. Needs the venv of run.sh (network once). VARIANTS="real-easy" and
# TEXTURES="low-contrast fine-grained" ./... run a subset; the default is every floor
# (brick grass gravel mosaic low-contrast fine-grained repetitive) and every variant.
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/opencv/venv.sh
O=target/release/ocellus
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
drift() {
  "$O" odometry eval "$1" "$2" --plot "$T/plot.png" |
    awk '/final drift/ {d = $3; h = $11} /ATE RMSE/ {a = $3} END {printf "%s %s %s", d, h, a}'
}
echo "texture variant seed | lk_drift_% lk_heading_deg lk_ate_mm lk_ms | ocellus_drift_% ocellus_heading_deg ocellus_ate_mm"
for tex in ${TEXTURES:-brick grass gravel mosaic low-contrast fine-grained repetitive}; do
  for variant in ${VARIANTS:-easy hard real-easy real-hard}; do
    for seed in 1 2 3; do
      flag=""
      case "$variant" in
        hard) flag="--hard" ;;
        real-easy) flag="--real-camera" ;;
        real-hard) flag="--hard --real-camera" ;;
      esac
      "$O" synth ground --texture "$tex" --seed "$seed" $flag --out "$T/seq" > /dev/null
      ms=$("$PY" scripts/opencv/lk_odometry.py "$T/seq/frames" "$T/seq/camera.toml" "$T/lk.tum" | awk '{print $1}')
      "$O" odometry "$T/seq/frames" --camera "$T/seq/camera.toml" --out "$T/ours" > /dev/null
      echo "$tex $variant $seed | $(drift "$T/lk.tum" "$T/seq/groundtruth.tum") $ms | $(drift "$T/ours/trajectory.tum" "$T/seq/groundtruth.tum")"
      rm -rf "$T/seq" "$T/ours"
    done
  done
done
