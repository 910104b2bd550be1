"""Attention over a generated sequence from Python equals the command-line program's."""

import csv
import subprocess

import numpy as np
import pytest

import ocellus


def test_the_scanpath_and_context_are_the_command_lines(cli, tmp_path):
    seq, out = tmp_path / "seq", tmp_path / "attend"
    subprocess.run([cli, "generate", "attention", "--scenario", "sudden", "--frames", "16", "--event-frame", "8",
                    "--out", str(seq)], check=True, capture_output=True)
    subprocess.run([cli, "attend", str(seq / "frames"), "--pan-tilt", str(seq / "pan_tilt.csv"), "--no-overlays",
                    "--no-video", "--workers", "1", "--out", str(out)], check=True, capture_output=True)
    pan_tilt = list(csv.DictReader(open(seq / "pan_tilt.csv")))
    frames = sorted((seq / "frames").glob("frame_*.png"))
    engine = None
    saccades, chaos = [], []
    for k, path in enumerate(frames):
        img = ocellus.read_image(path)
        if engine is None:
            engine = ocellus.StreamEngine(img.shape[1], img.shape[0])
        r = engine.process(img, float(pan_tilt[k]["pan_deg"]), float(pan_tilt[k]["tilt_deg"]))
        assert r["frame"] == k and r["surprise"].shape == r["saliency"].shape
        f = r["fixation"]
        if f is not None and f["saccade"]:
            saccades.append((k, f["x"], f["y"], f["reason"]))
        chaos.append(r["chaos"])
    assert engine.frames == len(frames)
    expected = [(int(r["frame"]), float(r["x"]), float(r["y"]), r["reason"]) for r in csv.DictReader(open(out / "scanpath.csv"))]
    assert saccades == expected
    # The event at frame 8 wins by surprise, as the CLI saw.
    assert any(s[0] == 8 and s[3] == "surprising" for s in saccades)
    context = list(csv.DictReader(open(out / "context.csv")))
    for c, row in zip(chaos, context):
        if row["chaos_bits"] == "":
            assert c is None
        else:
            assert c == pytest.approx(float(row["chaos_bits"]), abs=1e-4)
    with pytest.raises(ocellus.OcellusError):
        engine.process(img, float("nan"), 0.0)
    with pytest.raises(ocellus.OcellusError):
        ocellus.StreamEngine(640, 480, config={"deg_per_px": "wide"})
