#!/usr/bin/env bash
# Installs what a fresh machine lacks, then runs the whole test suite and prints the total.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# The GPU backend's conformance tests run on Mesa's software Vulkan driver (lavapipe), the
# same on every machine, unless the caller names a driver.
if [ -z "${VK_DRIVER_FILES:-}" ]; then
  lvp=$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n 1 || true)
  if [ -n "$lvp" ]; then export VK_DRIVER_FILES="$lvp"; fi
fi
# Mesa's device-select layer looks for a Wayland display and complains on headless machines.
export NODEVICE_SELECT=1
log=$(mktemp)
trap 'rm -f "$log"' EXIT
set +e
# The report's browser test must not skip: setup.sh installed chromium.
OCELLUS_REQUIRE_CHROMIUM=1 cargo test --workspace --locked 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
set -e
# The examples that show the API on real images must run, too.
examples=(
  "ocellus-attention saliency_peak"
  "ocellus-attention attend_sequence"
  "ocellus-synth calibrate_chessboards"
  "ocellus-geometry stereo_depth"
  "ocellus-fovea logpolar_register"
  "ocellus-odometry floor_odometry"
  "ocellus-sim corridor_event"
  "ocellus-eval mit1003_scores"
  "ocellus-sim ball_study"
  "ocellus-sim stereo_head"
  "ocellus-retina retina_fovea"
)
ran=0
for e in "${examples[@]}"; do
  set -- $e
  if [ "$status" -eq 0 ]; then
    if cargo run -q --locked -p "$1" --example "$2" > "$log.example" 2>&1; then
      ran=$((ran + 1))
    else
      cat "$log.example"
      echo "example $2 of $1 failed"
      status=1
    fi
  fi
done
rm -f "$log.example"
# The Python package (python/): a virtual environment filled from the package registry, the
# wheel built by maturin and installed (`pip install ./python`), then pytest. The tests compare
# with the command-line program the cargo tests built, and run the Ray example on a local Ray.
py_passed=0
if [ "$status" -eq 0 ]; then
  venv=target/python-venv
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
  # Ray Data (with Pillow, its image reader) for the distributed example's test.
  "$venv/bin/pip" install -q --disable-pip-version-check numpy pytest pillow "ray[data]"
  if "$venv/bin/pip" install -q --disable-pip-version-check ./python \
    && OCELLUS_BIN="$PWD/target/debug/ocellus" OCELLUS_REQUIRE_RAY=1 "$venv/bin/python" -m pytest -q python/tests > "$log.py" 2>&1; then
    py_passed=$(grep -Eo '[0-9]+ passed' "$log.py" | grep -Eo '[0-9]+' || echo 0)
  else
    cat "$log.py" 2>/dev/null || true
    echo "the Python package's tests failed"
    status=1
  fi
  rm -f "$log.py"
fi
# One closing line for the whole suite (cargo prints one per test binary).
awk -v ran="$ran" -v all="${#examples[@]}" -v py="$py_passed" '/^test result:/ { p += $4; f += $6 } END { printf "tests: %d passed, %d failed; examples: %d of %d ran; python: %d passed\n", p, f, ran, all, py }' "$log"
exit "$status"
