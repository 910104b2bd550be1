#!/usr/bin/env bash
# Sourced by the comparison scripts: builds ocellus and makes the virtual environment with
# opencv-python-headless in target/opencv-venv (network needed once); sets $PY to its python.
cargo build --release -q
if [ ! -x target/opencv-venv/bin/python ]; then
  python3 -m venv target/opencv-venv
  target/opencv-venv/bin/pip install -q opencv-python-headless numpy
fi
PY=target/opencv-venv/bin/python
