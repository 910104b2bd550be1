"""Saliency maps of an image corpus on a Ray cluster: one ocellus engine per worker.

    python ray_saliency.py IMAGES OUT [--fixations DIR] [--address ADDRESS] [--preset ace2009]

IMAGES is a folder, a file, or several of them (anything `ray.data.read_images` reads: local
paths, or s3:// and gs:// URIs on a cluster that can reach them). For each image it writes one
Parquet row to OUT: the path, the image size, the saliency map (float32, flattened, with its
width and height), its peak in image pixels, and, when --fixations names a folder of human
fixation density maps with the same file stems (e.g. MIT1003's), the CC, SIM and KL of the
full-size saliency map against them.

On an existing cluster pass its address (`--address auto` on a cluster node, or
`--address ray://HEAD:10001` from outside); without one, Ray starts a local instance on this
machine's cores. Each worker keeps one `ocellus.SaliencyEngine` per image size, so a corpus of
one size builds one engine per worker.
"""

from __future__ import annotations

import argparse
import pathlib
from typing import Dict, List, Optional

import numpy as np

import ocellus


def density_for(fixations: Optional[str], image_path: str) -> Optional[np.ndarray]:
    """The fixation density map with the image's file stem in `fixations`, as float64, or None."""
    if not fixations:
        return None
    matches = sorted(pathlib.Path(fixations).glob(pathlib.Path(image_path).stem + ".*"))
    if not matches:
        return None
    from PIL import Image  # Ray's image reader needs Pillow anyway

    return np.asarray(Image.open(matches[0]).convert("L"), dtype=np.float64)


def score_image(
    image: np.ndarray, engines: Dict[tuple, ocellus.SaliencyEngine], preset: str, density: Optional[np.ndarray]
) -> dict:
    """The saliency map of one H x W x 3 uint8 image and, with a density map, CC / SIM / KL."""
    h, w = image.shape[:2]
    engine = engines.get((w, h))
    if engine is None:
        engine = engines[(w, h)] = ocellus.SaliencyEngine(w, h, preset=preset)
    m = engine.process(np.ascontiguousarray(image))
    full = engine.full_size()
    py, px = np.unravel_index(int(np.argmax(full)), full.shape)
    row = {
        "width": w,
        "height": h,
        "map_width": m.shape[1],
        "map_height": m.shape[0],
        "saliency": m.ravel(),
        "peak_x": int(px),
        "peak_y": int(py),
        "cc": float("nan"),
        "sim": float("nan"),
        "kl": float("nan"),
    }
    if density is not None:
        if density.shape != full.shape:
            raise ocellus.OcellusError(f"fixation map of {density.shape} for an image of {full.shape}")
        row["cc"] = ocellus.cc(full, density)
        row["sim"] = ocellus.sim(full, density)
        row["kl"] = ocellus.kl(full, density)
    return row


# The extensions `ray.data.read_images` reads.
IMAGE_EXTENSIONS = ["png", "jpg", "jpeg", "tif", "tiff", "bmp", "gif"]


def decode_image(data: bytes) -> np.ndarray:
    """An encoded image file's pixels as H x W x 3 uint8 (Pillow, as Ray's image reader)."""
    import io

    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGB"))


class SaliencyWorker:
    """A Ray Data UDF: one worker's engines, applied to batches of images."""

    def __init__(self, preset: str = "ace2009", fixations: Optional[str] = None):
        self.preset = preset
        self.fixations = fixations
        self.engines: Dict[tuple, ocellus.SaliencyEngine] = {}

    def __call__(self, batch: Dict[str, np.ndarray]):
        rows: List[dict] = []
        # Encoded files (decode="worker") are decoded here, on this worker's CPU.
        images = (decode_image(b) for b in batch["bytes"]) if "bytes" in batch else iter(batch["image"])
        for image, path in zip(images, batch["path"]):
            row = score_image(image, self.engines, self.preset, density_for(self.fixations, str(path)))
            row["path"] = str(path)
            rows.append(row)
        if not rows:
            return {}
        import pyarrow as pa

        columns = {k: [r[k] for r in rows] for k in rows[0]}
        # The maps as one float32 list column built from the arrays: as Python lists of
        # floats they were stored as float64, twice the bytes, and converted value by value.
        columns["saliency"] = pa.array(columns["saliency"], type=pa.list_(pa.float32()))
        return pa.table(columns)


def run(
    images,
    out: str,
    fixations: Optional[str] = None,
    preset: str = "ace2009",
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    workers: int = 2,
    blocks: Optional[int] = None,
    decode: str = "worker",
) -> None:
    """Reads `images` with Ray Data in `blocks` read tasks (default 2 per worker; more for
    corpora too large for a worker's memory in two blocks), scores them on `workers` actors,
    writes Parquet to `out`.

    `decode="worker"` (default) reads the files' bytes (`ray.data.read_binary_files`) and
    decodes them in the actors; `"reader"` decodes in Ray's reader (`ray.data.read_images`).
    Decoding in the actors ships the compressed files (15 to 22 times smaller than their
    pixels) through the object store and keeps all the per-image work on the workers, which
    are what the cluster scales: with one worker, 57 images/s on one core against 39
    (`ray_throughput.py`, 800 images of 1024x768)."""
    import sys

    import ray

    if decode not in ("worker", "reader"):
        raise ValueError(f"decode {decode!r}: 'worker' or 'reader'")
    # Workers may not have this file: ship its code with the task (a script run as
    # __main__ is shipped so anyway).
    if __name__ != "__main__":
        ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    if not ray.is_initialized():
        ray.init(address=address, num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)
    # The read tasks reserve no CPU: with the actors holding every CPU they would otherwise
    # never be scheduled, and the pipeline would wait forever.
    # Few, large read tasks: a read task costs about 0.1 s of scheduling on a small machine,
    # ten times the work of one 1024x768 image (one task per file gave 11 images/s against
    # 39 with 2 per worker, in ray_throughput.py).
    read = dict(include_paths=True, num_cpus=0, override_num_blocks=blocks or 2 * workers)
    if decode == "worker":
        # Only image files, as `read_images` picks them.
        ds = ray.data.read_binary_files(images, file_extensions=IMAGE_EXTENSIONS, **read)
    else:
        ds = ray.data.read_images(images, mode="RGB", **read)
    scored = ds.map_batches(
        SaliencyWorker,
        fn_constructor_kwargs={"preset": preset, "fixations": fixations},
        batch_size=16,
        batch_format="numpy",
        compute=ray.data.ActorPoolStrategy(size=workers),
        num_cpus=1,
        # One CPU per actor, one thread per engine: the actors are the parallelism.
        runtime_env={"env_vars": {"RAYON_NUM_THREADS": "1"}},
    )
    # The write tasks reserve no CPU either: reserving one, they waited until the actors
    # released theirs at the end and then ran one after the other (about a second of 6 for
    # 400 images on 2 cores, ray_throughput.py); with none they write each block as it comes.
    scored.write_parquet(out, ray_remote_args={"num_cpus": 0})


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("images", nargs="+", help="image folders, files or URIs")
    p.add_argument("out", help="output folder for the Parquet files")
    p.add_argument("--fixations", help="folder of fixation density maps named like the images")
    p.add_argument("--preset", default="ace2009", choices=ocellus.presets())
    p.add_argument("--address", help="an existing Ray cluster (e.g. auto or ray://HEAD:10001)")
    p.add_argument("--workers", type=int, default=2, help="actors, each with its own engines")
    p.add_argument("--blocks", type=int, help="read tasks (default: 2 per worker)")
    p.add_argument(
        "--decode",
        default="worker",
        choices=["worker", "reader"],
        help="where images are decoded: in the workers (default) or in Ray's reader",
    )
    a = p.parse_args()
    run(a.images, a.out, a.fixations, a.preset, a.address, workers=a.workers, blocks=a.blocks, decode=a.decode)


if __name__ == "__main__":
    main()
