"""The saliency map from Python equals the library's (the CLI's), and bad input raises."""

import subprocess
import threading

import numpy as np
import pytest

import ocellus
from conftest import TESTDATA


def test_the_map_is_the_command_line_programs_bit_for_bit(cli, tmp_path):
    for name in ["chelsea.png", "astronaut.png"]:
        subprocess.run([cli, "saliency", "--out", str(tmp_path), str(TESTDATA / name)], check=True, capture_output=True)
        from_cli = np.load(tmp_path / (name[:-4] + ".saliency.npy"))
        from_python = ocellus.saliency(ocellus.read_image(TESTDATA / name))
        assert from_python.dtype == np.float32 and from_python.shape == from_cli.shape
        assert np.array_equal(from_python, from_cli), name


def test_the_engine_and_the_function_agree_and_give_every_output(photo):
    h, w, _ = photo.shape
    engine = ocellus.SaliencyEngine(w, h)
    assert engine.frame_size == (w, h)
    m = engine.process(photo)
    assert m.shape == (engine.map_size[1], engine.map_size[0])
    out = ocellus.saliency(photo, conspicuity=True, full_size=True)
    assert np.array_equal(out["saliency"], m)
    assert set(out["conspicuity"]) == set(engine.conspicuity()) and len(out["conspicuity"]) == 3
    # The conspicuity maps, after their weights, sum to the saliency map (ace2009: no final N).
    total = sum(out["conspicuity"].values())
    assert np.allclose(total, m, rtol=1e-5, atol=1e-6)
    assert out["full_size"].shape == (h, w)
    assert set(engine.timings()) >= {"normalization", "orientation"}
    # The preset and overrides: normalization "none" changes the map.
    other = ocellus.saliency(photo, config={"normalization": {"kind": "none"}})
    assert other.shape == m.shape and not np.array_equal(other, m)
    stb = ocellus.saliency(photo, preset="stb")
    assert stb.shape == m.shape
    # Channels add by kind, as in a --config file: a skin channel joins the three.
    skin = ocellus.saliency(photo, config={"channels": [{"kind": "skin", "weight": 0.5}]}, conspicuity=True)
    assert len(skin["conspicuity"]) == 4


def test_outputs_own_the_rust_buffer(photo):
    m = ocellus.saliency(photo)
    # The array does not own a numpy allocation: its base is the Rust vector it took over.
    assert not m.flags.owndata
    assert m.base is not None and not isinstance(m.base, np.ndarray)
    assert m.flags.c_contiguous and m.flags.writeable


def test_the_engines_input_buffer_is_shared_not_copied(photo):
    h, w, _ = photo.shape
    engine = ocellus.SaliencyEngine(w, h)
    buf = engine.input
    assert buf.shape == (h, w, 3) and buf.dtype == np.uint8 and buf.flags.writeable
    # The same memory every time: what Python writes there is what the engine reads.
    assert np.shares_memory(buf, engine.input)
    buf[:] = photo
    m = engine.process_input()
    assert np.array_equal(m, ocellus.saliency(photo))
    buf[:, : w // 2] = 0
    assert not np.array_equal(engine.process_input(), m)
    # The view keeps its engine alive.
    view = ocellus.SaliencyEngine(w, h).input
    view[:] = 7
    assert view.base is not None and int(view.sum()) == 7 * h * w * 3


def test_grey_float_and_strided_inputs(photo):
    ref = ocellus.saliency(photo)
    # A strided view is read through its strides: the same map as its contiguous copy.
    view = photo[:, ::-1]
    assert not view.flags.c_contiguous
    assert np.array_equal(ocellus.saliency(view), ocellus.saliency(np.ascontiguousarray(view)))
    # float32 in [0, 1] is the same picture.
    f = ocellus.saliency(photo.astype(np.float32) / 255.0)
    assert f.shape == ref.shape and np.corrcoef(f.ravel(), ref.ravel())[0, 1] > 0.99
    grey = photo.mean(axis=2).astype(np.uint8)
    assert ocellus.saliency(grey).shape == ref.shape


@pytest.mark.parametrize(
    "bad, error",
    [
        (np.zeros((300, 400, 3), dtype=np.int64), TypeError),
        (np.zeros((300,), dtype=np.uint8), ocellus.OcellusError),
        (np.zeros((300, 400, 4), dtype=np.uint8), ocellus.OcellusError),
        (np.zeros((0, 400, 3), dtype=np.uint8), ocellus.OcellusError),
        (np.full((300, 400, 3), np.nan, dtype=np.float32), ocellus.OcellusError),
        # Too small for the nine levels of the pyramid.
        (np.zeros((100, 100, 3), dtype=np.uint8), ocellus.OcellusError),
    ],
)
def test_bad_images_raise(bad, error):
    with pytest.raises(error):
        ocellus.saliency(bad)


def test_bad_parameters_raise(photo):
    assert issubclass(ocellus.OcellusError, ValueError)
    with pytest.raises(ocellus.OcellusError, match="preset"):
        ocellus.saliency(photo, preset="nope")
    with pytest.raises(ocellus.OcellusError):
        ocellus.saliency(photo, config={"feature_range": float("nan")})
    with pytest.raises(ocellus.OcellusError):
        ocellus.saliency(photo, config={"no_such_field": 1})
    engine = ocellus.SaliencyEngine(320, 256)
    with pytest.raises(ocellus.OcellusError, match="320x256"):
        engine.process(photo)


def test_one_engine_in_two_threads_works_or_raises(photo):
    h, w, _ = photo.shape
    engine = ocellus.SaliencyEngine(w, h)
    expected = engine.process(photo).copy()
    results, errors = [], []

    def work():
        for _ in range(5):
            try:
                results.append(engine.process(photo))
            except RuntimeError as e:  # already borrowed by the other thread
                errors.append(e)

    threads = [threading.Thread(target=work) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(results) + len(errors) == 10 and results
    assert all(np.array_equal(r, expected) for r in results)


@pytest.mark.parametrize(
    "make",
    [
        lambda: ocellus.SaliencyEngine(0, 480),
        lambda: ocellus.SaliencyEngine(10**6, 10**6),  # would need terabytes: refused, not aborted
        lambda: ocellus.StreamEngine(10**6, 10**6),
        lambda: ocellus.LogPolar(10**6, 10**6),
        lambda: ocellus.LogPolar(300, 300, rings=0),
        lambda: ocellus.SaliencyEngine(640, 480, config={"map_level": -1}),
        lambda: ocellus.GroundSequence(frames=0),
        lambda: ocellus.Odometry(0.3, float("inf")),
    ],
)
def test_impossible_engines_raise_instead_of_crashing(make):
    with pytest.raises(ocellus.OcellusError):
        make()
