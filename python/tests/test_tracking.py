"""Particle filters from Python: resampling by its definition, the ball tracker as the CLI."""

import csv
import subprocess

import numpy as np
import pytest

import ocellus


def test_resampling_schemes_keep_the_expected_offspring():
    rng = np.random.default_rng(4)
    w = rng.random(50) ** 4
    n = len(w)
    for scheme in ["systematic", "stratified", "multinomial", "residual"]:
        idx = ocellus.resample(w, scheme=scheme, seed=7)
        assert len(idx) == n and idx == sorted(idx) and 0 <= idx[0] and idx[-1] < n
        assert idx == ocellus.resample(w, scheme=scheme, seed=7)  # seeded
    # Systematic: each particle gets floor(N w) or ceil(N w) copies.
    counts = np.bincount(ocellus.resample(w, seed=3), minlength=n)
    expected = n * w / w.sum()
    assert np.all(counts >= np.floor(expected)) and np.all(counts <= np.ceil(expected))
    assert ocellus.effective_sample_size([1, 1, 1, 1]) == pytest.approx(4.0)
    assert ocellus.effective_sample_size([1, 0, 0, 0]) == pytest.approx(1.0)
    for bad in ([], [1.0, -1.0], [0.0, 0.0], [float("nan")]):
        with pytest.raises(ocellus.OcellusError):
            ocellus.resample(bad)
    with pytest.raises(ocellus.OcellusError):
        ocellus.resample([1.0], scheme="roulette")


def test_the_ball_tracker_follows_the_command_line(cli, tmp_path):
    ball, track = tmp_path / "ball", tmp_path / "track"
    subprocess.run([cli, "generate", "ball", "--trajectory", "throw", "--frames", "20", "--seed", "1", "--out",
                    str(ball)], check=True, capture_output=True)
    subprocess.run([cli, "track", str(ball / "frames"), "--camera", str(ball / "camera.toml"), "--radius-m", "0.05",
                    "--patch", "143,319.2,8.5", "--gravity", "9.81", "--floor-y", "0.55", "--particles", "1000",
                    "--no-overlays", "--out", str(track)], check=True, capture_output=True)
    rows = list(csv.DictReader(open(track / "track.csv")))
    frames = sorted((ball / "frames").glob("frame_*.png"))
    first = ocellus.read_image(frames[0])
    k = np.array([[600.0, 0.0, 319.5], [0.0, 600.0, 239.5], [0.0, 0.0, 1.0]])
    tracker = ocellus.BallTracker(k, 0.05, patch=(first, 143.0, 319.2, 8.5), distortion=[-0.12, 0.02, 0.0005, -0.0003, 0.0],
                                  particles=1000, gravity=9.81, floor_y=0.55)
    truth = list(csv.DictReader(open(ball / "truth.csv")))
    for path, row, t in zip(frames, rows, truth):
        e = tracker.process(ocellus.read_image(path))
        assert e["frame"] == int(row["frame"]) and e["lost"] == (row["lost"] == "1")
        assert np.allclose(e["position"], [float(row[c]) for c in ("x_m", "y_m", "z_m")], atol=1e-6)
        # And on the ball in the image wherever it is in view (the tracker's 3D accuracy is
        # reported by `ocellus track study`).
        if float(t["visible_fraction"]) > 0.5:
            u, v, _ = e["circle"]
            assert np.hypot(u - float(t["u_px"]), v - float(t["v_px"])) < 3.0, path.name
    assert tracker.particles.shape == (1000, 6)
    with pytest.raises(ocellus.OcellusError):
        ocellus.BallTracker(k, 0.05, colour=(128, 128, 128))  # grey: no hue
    with pytest.raises(ocellus.OcellusError):
        ocellus.BallTracker(k, 0.05, colour=(250, 120, 20), particles=0)


def test_a_numpy_model_in_the_particle_filter_tracks_as_the_kalman_filter():
    # x_t = x_(t-1) + N(0, q), z_t = x_t + N(0, r): the posterior is the Kalman filter's.
    q, r, n = 0.5, 1.0, 20000
    rng = np.random.default_rng(11)
    truth = np.cumsum(rng.normal(0, np.sqrt(q), 10))
    zs = truth + rng.normal(0, np.sqrt(r), 10)
    pf = ocellus.ParticleFilter(rng.normal(0.0, 1.0, (n, 1)), resample_below=1.0)
    m, p = 0.0, 1.0
    for z in zs:
        pf.step(lambda s: s + rng.normal(0, np.sqrt(q), s.shape), lambda s: -0.5 * (s[:, 0] - z) ** 2 / r)
        p = p + q
        k = p / (p + r)
        m, p = m + k * (z - m), (1 - k) * p
        assert pf.mean()[0] == pytest.approx(m, abs=0.05)
    assert pf.states.shape == (n, 1) and pf.ess == pytest.approx(n)  # resampled every step


def test_the_sis_weight_update_is_the_hand_computation():
    pf = ocellus.ParticleFilter([[0.0], [1.0], [2.0], [3.0]], resample_below=0.0)
    report = pf.step(lambda s: (s + 0.5, [0.0, 0.0, 0.0, -1.0]), lambda s: -0.5 * (s[:, 0] - 2.0) ** 2)
    x = np.array([0.5, 1.5, 2.5, 3.5])
    w = np.exp(-0.5 * (x - 2.0) ** 2 - [0.0, 0.0, 0.0, 1.0])
    assert np.allclose(pf.weights, w / w.sum(), atol=1e-12) and not report["resampled"]
    assert report["ess"] == pytest.approx(1.0 / np.sum((w / w.sum()) ** 2))
    with pytest.raises(ocellus.OcellusError):
        pf.step(lambda s: s[:2], lambda s: np.zeros(len(s)))  # lost particles
    with pytest.raises(ocellus.OcellusError):
        pf.step(lambda s: s, lambda s: np.full(len(s), np.nan))
    with pytest.raises(ocellus.OcellusError):
        ocellus.ParticleFilter(np.zeros((0, 2)))
