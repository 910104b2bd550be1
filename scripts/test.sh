#!/usr/bin/env bash
# Installs what a fresh machine lacks, then runs the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --workspace --locked
