"""The binding's overhead: ocellus.SaliencyEngine.process called from Python (and
process_input on the engine's shared input buffer) against the same engine timed inside Rust
(no Python in the loop), on one 640x480 photo, in one run.

    python bench_overhead.py [--frames 300] [--json]

Prints the median milliseconds of both and the overhead in percent; the two loops alternate
in rounds so that both see the same machine load.
"""

import argparse
import json
import pathlib
import statistics
import time

import numpy as np

import ocellus

ROOT = pathlib.Path(__file__).resolve().parents[2]


def frame_640x480() -> np.ndarray:
    """The astronaut photo resampled (nearest) to 640x480."""
    p = ocellus.read_image(ROOT / "testdata" / "astronaut.png")
    ys = np.arange(480) * p.shape[0] // 480
    xs = np.arange(640) * p.shape[1] // 640
    return np.ascontiguousarray(p[ys][:, xs])


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--frames", type=int, default=300)
    a.add_argument("--json", action="store_true")
    args = a.parse_args()
    img = frame_640x480()
    engine = ocellus.SaliencyEngine(640, 480)
    for _ in range(20):
        engine.process(img)
    py_ms, rust_ms, shared_ms = [], [], []
    engine.input[:] = img
    rounds = 10
    per = max(1, args.frames // rounds)
    for _ in range(rounds):
        for _ in range(per):
            t = time.perf_counter()
            engine.process(img)
            py_ms.append((time.perf_counter() - t) * 1e3)
        rust_ms.extend(engine.time_in_rust(img, per))
        for _ in range(per):
            t = time.perf_counter()
            engine.process_input()
            shared_ms.append((time.perf_counter() - t) * 1e3)
    py, rust, shared = statistics.median(py_ms), statistics.median(rust_ms), statistics.median(shared_ms)
    figures = {
        "frame": "640x480",
        "preset": "ace2009",
        "frames": len(py_ms),
        "ms_per_frame_python": py,
        "ms_per_frame_rust": rust,
        "overhead_percent": 100.0 * (py - rust) / rust,
        "ms_per_frame_python_shared_input": shared,
        "overhead_shared_input_percent": 100.0 * (shared - rust) / rust,
    }
    if args.json:
        print(json.dumps(figures))
    else:
        print(
            f"saliency 640x480 ace2009: {py:.3f} ms from Python, {rust:.3f} ms in Rust "
            f"(median of {len(py_ms)}): overhead {figures['overhead_percent']:.1f} %; "
            f"{shared:.3f} ms through the shared input buffer ({figures['overhead_shared_input_percent']:.1f} %)"
        )


if __name__ == "__main__":
    main()
