"""Throughput of the Ray example with 1 and 2 workers on a local Ray instance: the
repository's MIT1003 stimuli (1024x768), repeated, scored and written to Parquet.

    python ray_throughput.py [--repeat 10] [--decode worker|reader] [--json]

Two figures per worker count:
- `images_per_s_N_workers`: N actors, Ray on every core of the machine. Ray's own processes
  (the driver's executor, the raylet, the read and write tasks) then run beside the actors,
  on a machine of 2 cores on the same cores;
- `images_per_s_N_cores`: the whole Ray instance, its own processes included, held to N cores
  (CPU affinity, which its processes inherit) with N actors: one worker per core, as on a
  cluster whose nodes each bring their cores. `speedup_2_cores` is the ratio of the two.
"""

import argparse
import json
import os
import pathlib
import shutil
import tempfile
import time

import ray

import ray_saliency

ROOT = pathlib.Path(__file__).resolve().parents[2]


def images_per_s(paths, stimuli, workers: int, decode: str, cores=None) -> float:
    """One timed run of `paths` on a fresh local Ray instance (held to `cores` when given),
    after a warm-up run over `stimuli` that starts the workers and loads the package."""
    everything = os.sched_getaffinity(0)
    if cores is not None:
        os.sched_setaffinity(0, set(sorted(everything)[:cores]))
    ray.init(num_cpus=cores or len(everything), include_dashboard=False, log_to_driver=False)
    try:
        ray_saliency.run(stimuli, tempfile.mkdtemp(), workers=workers, decode=decode)
        out = tempfile.mkdtemp()
        t = time.perf_counter()
        ray_saliency.run(paths, out, workers=workers, decode=decode)
        rate = len(paths) / (time.perf_counter() - t)
        shutil.rmtree(out)
        return rate
    finally:
        ray.shutdown()
        os.sched_setaffinity(0, everything)


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--repeat", type=int, default=10)
    a.add_argument("--decode", default="worker", choices=["worker", "reader"])
    a.add_argument("--json", action="store_true")
    args = a.parse_args()
    stimuli = sorted(str(p) for p in (ROOT / "testdata" / "mit1003" / "stimuli").iterdir())
    paths = stimuli * args.repeat
    figures = {"images": len(paths), "size": "1024x768", "decode": args.decode, "cores": len(os.sched_getaffinity(0))}
    for workers in (1, 2):
        figures[f"images_per_s_{workers}_workers"] = images_per_s(paths, stimuli, workers, args.decode)
    for cores in (1, 2):
        figures[f"images_per_s_{cores}_cores"] = images_per_s(paths, stimuli, cores, args.decode, cores)
    figures["speedup_2_workers"] = figures["images_per_s_2_workers"] / figures["images_per_s_1_workers"]
    figures["speedup_2_cores"] = figures["images_per_s_2_cores"] / figures["images_per_s_1_cores"]
    print(json.dumps(figures) if args.json else figures)


if __name__ == "__main__":
    main()
