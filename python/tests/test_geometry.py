"""Geometry from Python against closed forms and against the command-line program."""

import json
import subprocess

import numpy as np
import pytest

import ocellus
from conftest import TESTDATA


def camera(rng):
    k = np.array([[800.0, 0.0, 320.0], [0.0, 780.0, 240.0], [0.0, 0.0, 1.0]])
    a = 0.2
    r = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    t = np.array([0.1, -0.2, 3.0])
    return k, r, t, k @ np.hstack([r, t[:, None]])


def project(p, x):
    h = (p @ np.hstack([x, np.ones((len(x), 1))]).T).T
    return h[:, :2] / h[:, 2:]


def test_dlt_recovers_the_camera_and_decomposes_it():
    rng = np.random.default_rng(1)
    k, r, t, p = camera(rng)
    x3 = rng.uniform(-1, 1, (20, 3))
    x2 = project(p, x3)
    for method in ["svd", "linear"]:
        out = ocellus.dlt(x3, x2, method=method)
        est = out["P"] / out["P"][2, 3] * p[2, 3]
        assert np.allclose(est, p, rtol=1e-6, atol=1e-6) and out["rms_px"] < 1e-6
    d = ocellus.decompose(p)
    assert np.allclose(d["K"], k, atol=1e-6) and np.allclose(d["R"], r, atol=1e-9)
    assert np.allclose(d["t"], t, atol=1e-9)
    with pytest.raises(ocellus.OcellusError):
        ocellus.dlt(x3[:5], x2[:5])  # fewer than 6 points
    with pytest.raises(ocellus.OcellusError):
        ocellus.dlt(x3, x2[:, :1])


def test_triangulation_from_two_and_three_views():
    rng = np.random.default_rng(2)
    _, _, _, p1 = camera(rng)
    p2 = p1.copy()
    p2[:, 3] += p1[:, :3] @ np.array([-0.5, 0.0, 0.0])  # the camera moved 0.5 to the right
    p3 = p1.copy()
    p3[:, 3] += p1[:, :3] @ np.array([0.0, 0.4, 0.1])
    x = np.array([[0.3, -0.1, 0.5]])
    for ps in ([p1, p2], [p1, p2, p3]):
        t = ocellus.triangulate(ps, np.vstack([project(p, x) for p in ps]))
        assert np.allclose(t["point"], x[0], atol=1e-9) and t["in_front"]
    with pytest.raises(ocellus.OcellusError):
        ocellus.triangulate([p1, p1], np.vstack([project(p1, x)] * 2))  # one centre


def test_undistort_without_distortion_is_the_grey_image(photo):
    k = np.array([[400.0, 0.0, 225.0], [0.0, 400.0, 150.0], [0.0, 0.0, 1.0]])
    grey = photo.mean(axis=2).astype(np.uint8)
    out = ocellus.undistort(grey, k, [0.0, 0.0, 0.0, 0.0])
    assert out.shape == grey.shape and np.allclose(out, grey, atol=1e-3)
    bent = ocellus.undistort(grey, k, [-0.3, 0.1, 0.0, 0.0, 0.0])
    assert not np.allclose(bent, out, atol=1.0)
    with pytest.raises(ocellus.OcellusError):
        ocellus.undistort(grey, k, [0.0, float("nan"), 0.0, 0.0])


def test_chessboard_calibration_equals_the_command_line(cli, tmp_path):
    boards, calib = tmp_path / "boards", tmp_path / "calib"
    subprocess.run([cli, "generate", "chessboard", "--views", "6", "--seed", "3", "--out", str(boards)], check=True,
                   capture_output=True)
    subprocess.run([cli, "calibrate", "chessboard", str(boards), "--board", "9x6", "--square", "25mm", "--out",
                    str(calib)], check=True, capture_output=True)
    views = sorted(boards.glob("view_*.png"))
    out = ocellus.calibrate_chessboard([ocellus.read_image(v) for v in views], 9, 6, square=25.0)
    report = json.loads((calib / "calibration.json").read_text())
    assert out["used"] == list(range(len(views)))
    assert out["rms_px"] == pytest.approx(report["rms_px"], rel=1e-9)
    assert abs(out["K"][0, 0] - 640.0) < 5.0  # the generator's true fx
    with pytest.raises(ocellus.OcellusError):
        ocellus.calibrate_chessboard([ocellus.read_image(views[0])], 9, 6)


def test_stereo_on_the_motorcycle_pair():
    left = ocellus.read_image(TESTDATA / "motorcycle_left.png")
    right = ocellus.read_image(TESTDATA / "motorcycle_right.png")
    for d in [ocellus.stereo_sgm(left, right, max_disparity=128), ocellus.stereo_bm(left, right, max_disparity=128)]:
        assert d.shape == left.shape[:2] and d.dtype == np.float32
        valid = np.isfinite(d)
        assert valid.mean() > 0.5 and d[valid].min() >= 0.0 and d[valid].max() < 128.0
    with pytest.raises(ocellus.OcellusError):
        ocellus.stereo_sgm(left, right[:, :100])


def test_odometry_on_a_generated_floor_equals_the_command_line(cli, tmp_path):
    seq = ocellus.GroundSequence(frames=40, seed=2)
    assert len(seq) == 40
    subprocess.run([cli, "generate", "ground", "--frames", "40", "--seed", "2", "--out", str(tmp_path / "g")],
                   check=True, capture_output=True)
    # The same frames as the generator's PNGs, bit for bit.
    first = ocellus.read_image(tmp_path / "g" / "frames" / "frame_00000.png")[:, :, 0]
    assert np.array_equal(seq.frame(0), first)
    cam = seq.camera
    vo = ocellus.Odometry(cam["height_m"], cam["focal_px"], mount=cam["mount"])
    poses = [vo.step(seq.frame(k))["pose"] for k in range(len(seq))]
    truth = [seq.pose(k) for k in range(len(seq))]
    path = sum(np.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(truth, truth[1:]))
    drift = np.hypot(poses[-1][0] - truth[-1][0], poses[-1][1] - truth[-1][1]) / path
    assert path > 0.05 and drift < 0.01
    subprocess.run([cli, "odometry", str(tmp_path / "g" / "frames"), "--camera", str(tmp_path / "g" / "camera.toml"),
                    "--out", str(tmp_path / "o")], check=True, capture_output=True)
    tum = np.loadtxt(tmp_path / "o" / "trajectory.tum", comments="#")
    assert np.allclose(tum[:, 1:3], np.array(poses)[:, :2], atol=2e-9)
    with pytest.raises(ocellus.OcellusError):
        ocellus.Odometry(-0.3, 600.0)
    with pytest.raises(IndexError):
        seq.frame(40)
