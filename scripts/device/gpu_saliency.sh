#!/usr/bin/env bash
# The GPU figures of issue 18 on a machine with a GPU (e.g. the lent NVIDIA machine): builds
# the CLI, names the adapter wgpu picks, and prints `ocellus bench saliency --backend gpu
# --json` at 640x480: end to end with every output read back, maps only, and batches of 8
# and 64 frames, with the largest difference from the scalar CPU map. A software adapter
# (llvmpipe) in the "device" field means no GPU driver was found: its times say nothing.
set -euo pipefail
cd "$(dirname "$0")/../.."
export NODEVICE_SELECT=1
cargo build --release --locked -p ocellus-cli
./target/release/ocellus bench saliency --backend gpu --frames "${FRAMES:-500}" --json
