"""Throughput of the Ray example with 1 and 2 workers on a local Ray instance: the
repository's MIT1003 stimuli (1024x768), repeated, scored and written to Parquet.

    python ray_throughput.py [--repeat 10] [--runs 3] [--decode worker|reader] [--json]

Two figures per worker count:
- `images_per_s_N_workers`: N actors, Ray on every core of the machine. Ray's own processes
  (the driver's executor, the raylet, the read and write tasks) then run beside the actors,
  on a machine of 2 cores on the same cores;
- `images_per_s_N_cores`: the whole Ray instance, its own processes included, held to N cores
  (CPU affinity, which its processes inherit) with N actors: one worker per core, as on a
  cluster whose nodes each bring their cores. `speedup_2_cores` is the ratio of the two;
- `steady_images_per_s_N_cores`: the same held to N cores, timed over the corpus and over
  three times it; the extra images over the extra time are the rate of a running job, without
  the job's start (`job_start_s_N_cores`: new actors, imports, the first reads), which costs
  seconds whatever the corpus. `speedup_2_cores_steady` is the ratio of the two.

Every figure is the median of `--runs` timed jobs, each after a warm-up job on the same
fresh Ray instance.
"""

import argparse
import json
import os
import pathlib
import shutil
import statistics
import tempfile
import time

import ray

import ray_saliency

ROOT = pathlib.Path(__file__).resolve().parents[2]


def seconds(corpora, stimuli, workers: int, decode: str, cores=None, runs: int = 3) -> list:
    """The median seconds of `runs` timed runs of each corpus in `corpora` (lists of paths,
    taken in turn within each round) on a fresh local Ray instance (held to `cores` when
    given), after a warm-up run over `stimuli` that starts Ray's workers and loads the
    package. Each run is a whole Ray Data job, its start (new actors) included."""
    everything = os.sched_getaffinity(0)
    if cores is not None:
        os.sched_setaffinity(0, set(sorted(everything)[:cores]))
    ray.init(num_cpus=cores or len(everything), include_dashboard=False, log_to_driver=False)
    try:
        ray_saliency.run(stimuli, tempfile.mkdtemp(), workers=workers, decode=decode)
        times = [[] for _ in corpora]
        for _ in range(runs):
            for paths, t_list in zip(corpora, times):
                out = tempfile.mkdtemp()
                t = time.perf_counter()
                ray_saliency.run(paths, out, workers=workers, decode=decode)
                t_list.append(time.perf_counter() - t)
                shutil.rmtree(out)
        return [statistics.median(t) for t in times]
    finally:
        ray.shutdown()
        os.sched_setaffinity(0, everything)


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("--repeat", type=int, default=10)
    a.add_argument("--decode", default="worker", choices=["worker", "reader"])
    a.add_argument("--runs", type=int, default=3, help="timed runs per figure (their median)")
    a.add_argument("--json", action="store_true")
    args = a.parse_args()
    stimuli = sorted(str(p) for p in (ROOT / "testdata" / "mit1003" / "stimuli").iterdir())
    paths = stimuli * args.repeat
    if args.runs < 1 or args.repeat < 1:
        a.error("--runs and --repeat must be at least 1")
    figures = {
        "images": len(paths),
        "size": "1024x768",
        "decode": args.decode,
        "runs": args.runs,
        "cores": len(os.sched_getaffinity(0)),
    }
    n = len(paths)
    for workers in (1, 2):
        (t,) = seconds([paths], stimuli, workers, args.decode, runs=args.runs)
        figures[f"images_per_s_{workers}_workers"] = n / t
    for cores in (1, 2):
        # The corpus and three times it: the difference is the rate once a job is running,
        # without its start, which costs seconds whatever the corpus.
        t, t3 = seconds([paths, paths * 3], stimuli, cores, args.decode, cores, args.runs)
        figures[f"images_per_s_{cores}_cores"] = n / t
        # None (JSON null) when the longer corpus did not take longer: too short to tell.
        figures[f"steady_images_per_s_{cores}_cores"] = 2 * n / (t3 - t) if t3 > t else None
        figures[f"job_start_s_{cores}_cores"] = t - (t3 - t) / 2 if t3 > t else None
    figures["speedup_2_workers"] = figures["images_per_s_2_workers"] / figures["images_per_s_1_workers"]
    figures["speedup_2_cores"] = figures["images_per_s_2_cores"] / figures["images_per_s_1_cores"]
    steady = figures["steady_images_per_s_1_cores"], figures["steady_images_per_s_2_cores"]
    figures["speedup_2_cores_steady"] = steady[1] / steady[0] if None not in steady else None
    print(json.dumps(figures) if args.json else figures)


if __name__ == "__main__":
    main()
