#!/usr/bin/env python3
"""Focal-length error of ocellus and OpenCV calibration on the same synthetic data.

Zhang: 10 views of a 9x6 board (25 mm squares), 0.5 px Gaussian noise on the corners,
cv2.calibrateCamera (default flags: k1, k2, p1, p2, k3) against `ocellus calibrate planar`.
DLT: 100 non-coplanar points in millimetres with the target 2 m away, 0.5 px noise; the
normalized DLT in numpy (Hartley-Zisserman alg. 7.1, what OpenCV users write; OpenCV has no
3D DLT calibration) against `ocellus calibrate dlt`.

Run scripts/opencv/run.sh (it makes a virtual environment with opencv-python-headless);
needs network once. Not part of CI.
"""
import json
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

OCELLUS = sys.argv[1] if len(sys.argv) > 1 else "target/release/ocellus"
TRIALS = int(sys.argv[2]) if len(sys.argv) > 2 else 20
K = np.array([[812.0, 0, 318.0], [0, 806.0, 243.0], [0, 0, 1]])
DIST = np.array([-0.25, 0.08, 0.001, -0.0008, 0.0])  # k1 k2 p1 p2 k3 (OpenCV order)


def rot(rx, ry, rz):
    r, _ = cv2.Rodrigues(np.array([rx, ry, rz], dtype=np.float64))
    return r


def zhang_views(rng):
    obj = np.array([[c * 25.0, r * 25.0, 0.0] for r in range(6) for c in range(9)])
    views = []
    while len(views) < 10:
        r = rot(*(rng.uniform(-0.5, 0.5, 2)), rng.uniform(-0.3, 0.3))
        t = np.array([rng.uniform(-40, 40), rng.uniform(-30, 30), rng.uniform(350, 550)]) - r @ np.array([100.0, 62.5, 0.0])
        rvec, _ = cv2.Rodrigues(r)
        img, _ = cv2.projectPoints(obj, rvec, t, K, DIST)
        img = img.reshape(-1, 2)
        if (img < 0).any() or (img[:, 0] > 639).any() or (img[:, 1] > 479).any():
            continue
        views.append(img + rng.normal(0, 0.5, img.shape))
    return obj, views


def run(args):
    out = subprocess.run([OCELLUS] + args, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(out.stderr)


def zhang_trial(seed, tmp):
    rng = np.random.default_rng(seed)
    obj, views = zhang_views(rng)
    _, kcv, _, _, _ = cv2.calibrateCamera([obj.astype(np.float32)] * 10, [v.astype(np.float32) for v in views], (640, 480), None, None)
    path = os.path.join(tmp, "views.csv")
    with open(path, "w") as f:
        f.write("view,X,Y,u,v\n")
        for i, v in enumerate(views):
            for o, p in zip(obj, v):
                f.write(f"{i},{o[0]},{o[1]},{p[0]:.9f},{p[1]:.9f}\n")
    run(["calibrate", "planar", path, "--out", os.path.join(tmp, "z")])
    with open(os.path.join(tmp, "z", "calibration.json")) as f:
        fx = json.load(f)["intrinsics"]["fx"]
    return abs(kcv[0, 0] - K[0, 0]) / K[0, 0], abs(fx - K[0, 0]) / K[0, 0]


def numpy_dlt(p3, p2):
    def norm(p, target):
        c = p.mean(0)
        s = target / np.linalg.norm(p - c, axis=1).mean()
        t = np.eye(p.shape[1] + 1)
        t[:-1, :-1] *= s
        t[:-1, -1] = -s * c
        return t
    t3, t2 = norm(p3, np.sqrt(3)), norm(p2, np.sqrt(2))
    x = (t3 @ np.c_[p3, np.ones(len(p3))].T).T
    u = (t2 @ np.c_[p2, np.ones(len(p2))].T).T
    rows = []
    for (X, Y, Z, W), (a, b, _) in zip(x, u):
        rows.append([X, Y, Z, W, 0, 0, 0, 0, -a * X, -a * Y, -a * Z, -a * W])
        rows.append([0, 0, 0, 0, X, Y, Z, W, -b * X, -b * Y, -b * Z, -b * W])
    _, _, vt = np.linalg.svd(np.array(rows))
    p = np.linalg.inv(t2) @ vt[-1].reshape(3, 4) @ t3
    k, _, _, _, _, _, _ = cv2.decomposeProjectionMatrix(p)
    # The sign of P is arbitrary and OpenCV does not make the diagonal positive.
    return abs(k[0, 0] / k[2, 2])


def dlt_trial(seed, tmp):
    rng = np.random.default_rng(seed)
    r = rot(0.2, -0.3, 0.1)
    t = np.array([50.0, -100.0, 2000.0])
    p3, p2 = [], []
    while len(p3) < 100:
        x = rng.uniform(-400, 400, 3)
        xc = r @ x + t
        p = K @ xc
        p3.append(x)
        p2.append(p[:2] / p[2] + rng.normal(0, 0.5, 2))
    p3, p2 = np.array(p3), np.array(p2)
    f_np = numpy_dlt(p3, p2)
    path = os.path.join(tmp, "pts.csv")
    np.savetxt(path, np.c_[p3, p2], delimiter=",", fmt="%.9f")
    errs = [abs(f_np - K[0, 0]) / K[0, 0]]
    for extra in ([], ["--linear"]):
        run(["calibrate", "dlt", path, "--out", os.path.join(tmp, "cam.json")] + extra)
        with open(os.path.join(tmp, "cam.json")) as f:
            errs.append(abs(json.load(f)["intrinsics"]["fx"] - K[0, 0]) / K[0, 0])
    return errs


def main():
    with tempfile.TemporaryDirectory() as tmp:
        z = np.array([zhang_trial(s, tmp) for s in range(TRIALS)])
        d = np.array([dlt_trial(s, tmp) for s in range(TRIALS)])
    print(f"OpenCV {cv2.__version__}, {TRIALS} trials each, mean focal-length error (fx), same data:")
    print(f"  Zhang, 10 views of 9x6, 0.5 px:      OpenCV calibrateCamera {100 * z[:, 0].mean():.3f} %   ocellus {100 * z[:, 1].mean():.3f} %")
    print(f"  DLT, 100 points, mm at 2 m, 0.5 px:  numpy normalized DLT   {100 * d[:, 0].mean():.3f} %   ocellus {100 * d[:, 1].mean():.3f} %   (ocellus seed form p34 = 1: {100 * d[:, 2].mean():.3f} %)")


if __name__ == "__main__":
    main()
