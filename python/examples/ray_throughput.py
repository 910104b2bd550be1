"""Throughput of the Ray example with 1 and 2 workers on a local Ray instance: the
repository's MIT1003 stimuli (1024x768), repeated, scored and written to Parquet.

    python ray_throughput.py [--repeat 10] [--json]
"""

import argparse
import json
import pathlib
import shutil
import tempfile
import time

import ray

import ray_saliency

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--repeat", type=int, default=10)
    a.add_argument("--json", action="store_true")
    args = a.parse_args()
    stimuli = sorted(str(p) for p in (ROOT / "testdata" / "mit1003" / "stimuli").iterdir())
    paths = stimuli * args.repeat
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    figures = {"images": len(paths), "size": "1024x768"}
    try:
        # A first run starts the workers' processes and loads the package.
        ray_saliency.run(stimuli, tempfile.mkdtemp(), workers=2)
        for workers in (1, 2):
            out = tempfile.mkdtemp()
            t = time.perf_counter()
            ray_saliency.run(paths, out, workers=workers)
            figures[f"images_per_s_{workers}_workers"] = len(paths) / (time.perf_counter() - t)
            shutil.rmtree(out)
    finally:
        ray.shutdown()
    figures["speedup_2_workers"] = figures["images_per_s_2_workers"] / figures["images_per_s_1_workers"]
    print(json.dumps(figures) if args.json else figures)


if __name__ == "__main__":
    main()
