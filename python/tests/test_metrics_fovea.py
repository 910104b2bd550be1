"""Metrics against their definitions, and the log-polar fovea against known transformations."""

import numpy as np
import pytest

import ocellus


def test_metrics_against_numpy():
    rng = np.random.default_rng(3)
    s = rng.random((30, 40))
    d = rng.random((30, 40))
    assert ocellus.cc(s, d) == pytest.approx(np.corrcoef(s.ravel(), d.ravel())[0, 1], abs=1e-12)
    assert ocellus.cc(s, s) == pytest.approx(1.0)
    assert ocellus.sim(s, s) == pytest.approx(1.0)
    assert ocellus.kl(s, s) == pytest.approx(0.0, abs=1e-9)
    fix = np.array([[5, 7], [20, 3], [39, 29]])
    z = (s - s.mean()) / s.std(ddof=1)  # MATLAB std, as the MIT benchmark code
    assert ocellus.nss(s, fix) == pytest.approx(np.mean([z[y, x] for x, y in fix]), rel=1e-9)
    # A map that peaks exactly at the fixations.
    peaked = np.zeros((30, 40))
    for x, y in fix:
        peaked[y, x] = 1.0
    assert ocellus.auc_judd(peaked, fix) > 0.99
    assert ocellus.auc_borji(peaked, fix) > 0.95
    assert 0.0 <= ocellus.sauc(s, fix, [[1, 1], [2, 2], [3, 3]]) <= 1.0
    assert ocellus.ig(s, s, fix) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ocellus.OcellusError):
        ocellus.cc(s, d[:, :10])
    with pytest.raises(ocellus.OcellusError):
        ocellus.nss(s, [[-1, 2]])
    with pytest.raises(ocellus.OcellusError):
        ocellus.nss(s, np.zeros((3, 3)))


def test_logpolar_maps_rotation_to_a_cyclic_shift(photo):
    grey = photo.mean(axis=2).astype(np.uint8)[:300, :300]
    lp = ocellus.LogPolar(300, 300, rings=64, sectors=128)
    c = lp.forward(grey)
    assert c.shape == (lp.rows, lp.sectors) and c.dtype == np.float32
    assert lp.compression_ratio > 5
    assert np.array_equal(ocellus.logpolar(grey, rings=64, sectors=128), c)
    # A quarter turn about the centre shifts the sectors by a quarter of them.
    turned = lp.forward(np.ascontiguousarray(np.rot90(grey, k=-1)))
    shifted = np.roll(c, 32, axis=1)
    rows = slice(lp.rows // 4, lp.rows)  # away from the fovea's few pixels
    assert np.corrcoef(turned[rows].ravel(), shifted[rows].ravel())[0, 1] > 0.95
    back = lp.inverse(c)
    assert back.shape == (300, 300)
    rgb = lp.forward(photo[:300, :300])
    assert rgb.shape == (lp.rows, lp.sectors, 3)


def test_register_and_vergence(photo):
    grey = photo.mean(axis=2).astype(np.float32)[:256, :256]
    r = ocellus.register(grey, np.ascontiguousarray(np.rot90(grey)))
    assert abs(abs(r["angle_deg"]) - 90.0) < 1.0 and r["scale"] == pytest.approx(1.0, abs=0.02)
    left = photo.mean(axis=2).astype(np.uint8)
    right = np.roll(left, -9, axis=1)  # x_right = x_left - 9
    v = ocellus.vergence(left, right, (220.0, 150.0))
    assert v["disparity_px"] == pytest.approx(9.0, abs=0.5) and v["score"] > 0.9
    with pytest.raises(ocellus.OcellusError):
        ocellus.vergence(left, right[:, :100], (220.0, 150.0))
    with pytest.raises(ocellus.OcellusError):
        ocellus.LogPolar(300, 300, fields="square")
