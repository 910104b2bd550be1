"""The Ray Data example on a local Ray instance gives what the direct calls give."""

import os
import pathlib
import sys

import numpy as np
import pytest

import ocellus
from conftest import ROOT, TESTDATA

if os.environ.get("OCELLUS_REQUIRE_RAY") != "1":
    pytest.importorskip("ray")
import ray  # noqa: E402
from PIL import Image  # noqa: E402

sys.path.insert(0, str(ROOT / "python" / "examples"))
import ray_saliency  # noqa: E402


def test_ray_example_equals_direct_calls(tmp_path):
    stimuli = TESTDATA / "mit1003" / "stimuli"
    fixations = TESTDATA / "mit1003" / "fixation_maps"
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        # Decoded in the workers, and in Ray's reader: the same rows.
        for decode in ("worker", "reader"):
            ray_saliency.run(str(stimuli), str(tmp_path / decode), fixations=str(fixations), workers=2, decode=decode)
        with pytest.raises(ValueError):
            ray_saliency.run(str(stimuli), str(tmp_path / "x"), workers=1, decode="gpu")
    finally:
        ray.shutdown()
    import pyarrow.parquet as pq

    by_path = lambda t: sorted(t, key=lambda r: r["path"])  # noqa: E731
    import pyarrow as pa

    # The maps are stored as float32, as the engine makes them.
    assert pq.read_schema(next((tmp_path / "worker").glob("*.parquet"))).field("saliency").type == pa.list_(pa.float32())
    table = by_path(pq.read_table(tmp_path / "worker").to_pylist())
    assert table == by_path(pq.read_table(tmp_path / "reader").to_pylist())
    paths = sorted(stimuli.iterdir())
    assert sorted(pathlib.Path(r["path"]).name for r in table) == [p.name for p in paths]
    for r in table:
        path = pathlib.Path(r["path"])
        # The same pixels as Ray's reader (Pillow), through the direct API.
        image = np.asarray(Image.open(path).convert("RGB"))
        direct = ocellus.saliency(image, full_size=True)
        m = np.asarray(r["saliency"], dtype=np.float32).reshape(r["map_height"], r["map_width"])
        assert np.array_equal(m, direct["saliency"]), path.name
        density = np.asarray(Image.open(fixations / path.name).convert("L"), dtype=np.float64)
        assert r["cc"] == ocellus.cc(direct["full_size"], density)
        assert r["sim"] == ocellus.sim(direct["full_size"], density)
        assert r["kl"] == ocellus.kl(direct["full_size"], density)
        assert -1.0 <= r["cc"] <= 1.0 and 0.0 <= r["sim"] <= 1.0 and r["kl"] >= 0.0
        py, px = np.unravel_index(int(np.argmax(direct["full_size"])), direct["full_size"].shape)
        assert (r["peak_x"], r["peak_y"]) == (px, py)
