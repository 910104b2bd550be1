# The odometry an OpenCV user would write (issue 7's baseline): pyramidal Lucas-Kanade on a
# 20x20 grid of 400 points over the central 400x400 pixels, then RANSAC partial affine (a
# rotation, translation and scale) between consecutive frames, integrated with the same
# camera mount kinematics as ocellus. A lens with distortion in the camera file (k1 k2 p1 p2
# k3) is undistorted as an OpenCV user would: the tracked points through cv2.undistortPoints.
# Writes a TUM trajectory and prints the median ms per frame (LK + undistortion + RANSAC, one
# thread).
#
# Usage: python lk_odometry.py FRAMES_DIR CAMERA.toml OUT.tum [RATE_HZ]
import math
import os
import sys
import time

import cv2
import numpy as np


def read_camera(path):
    vals = {}
    for line in open(path):
        line = line.split("#")[0].strip()
        if "=" in line and not line.startswith("["):
            k, v = [t.strip() for t in line.split("=", 1)]
            try:
                vals[k] = float(v)
            except ValueError:
                pass
    return vals


def main():
    frames_dir, cam_path, out_path = sys.argv[1:4]
    rate = float(sys.argv[4]) if len(sys.argv) > 4 else 200.0
    cam = read_camera(cam_path)
    scale = cam["height_m"] / (0.5 * (cam["fx"] + cam["fy"]))
    mount_r, mount_f = cam.get("mount_right_m", 0.0), cam.get("mount_forward_m", 0.0)
    cx, cy = cam["cx"], cam["cy"]
    K = np.array([[cam["fx"], 0.0, cx], [0.0, cam["fy"], cy], [0.0, 0.0, 1.0]])
    dist = np.array([cam.get(k, 0.0) for k in ("k1", "k2", "p1", "p2", "k3")])
    lens = bool(np.any(dist != 0.0))

    def ideal(pts):
        if not lens:
            return pts
        return cv2.undistortPoints(pts.reshape(-1, 1, 2), K, dist, P=K).reshape(-1, 2)

    cv2.setNumThreads(1)
    names = sorted(n for n in os.listdir(frames_dir) if n.endswith(".png"))
    frames = [cv2.imread(os.path.join(frames_dir, n), cv2.IMREAD_GRAYSCALE) for n in names]
    h, w = frames[0].shape
    x0, y0 = (w - 400) // 2, (h - 400) // 2
    grid = np.array([[x0 + 10 + 20 * i, y0 + 10 + 20 * j] for j in range(20) for i in range(20)], np.float32)
    # Pose: x right, y down, theta clockwise; forward is -y at theta 0 (ocellus Pose2).
    px, py, th = 0.0, 0.0, 0.0

    def point(px, py, th, right, forward):
        s, c = math.sin(th), math.cos(th)
        return px + c * right + s * forward, py + s * right - c * forward

    poses = [(px, py, th)]
    times = []
    for prev, cur in zip(frames, frames[1:]):
        t = time.perf_counter()
        nxt, st, _ = cv2.calcOpticalFlowPyrLK(prev, cur, grid, None, winSize=(21, 21), maxLevel=3)
        ok = st.ravel() == 1
        a = ideal(grid[ok]) - (cx, cy)
        b = ideal(nxt[ok]) - (cx, cy)
        m, _ = cv2.estimateAffinePartial2D(a, b, method=cv2.RANSAC, ransacReprojThreshold=1.0)
        times.append((time.perf_counter() - t) * 1e3)
        if m is None:
            poses.append(poses[-1])
            continue
        # next = A (p + (-r, f)) with A = [[cos w, sin w], [-sin w, cos w]] (ocellus robust.rs).
        wz = -math.atan2(m[1, 0], m[0, 0])
        c, s = math.cos(wz), math.sin(wz)
        t0, t1 = m[0, 2], m[1, 2]
        r = -(c * t0 - s * t1)
        f = s * t0 + c * t1
        cam_r, cam_f = r * scale, f * scale
        # The camera moves, the robot follows (ocellus kinematics::moved_by_camera).
        cxw, cyw = point(px, py, th, mount_r + cam_r, mount_f + cam_f)
        th = th + wz
        px, py = point(cxw, cyw, th, -mount_r, -mount_f)
        poses.append((px, py, th))
    with open(out_path, "w") as fo:
        fo.write("# timestamp tx ty tz qx qy qz qw\n")
        for k, (x, y, a) in enumerate(poses):
            fo.write("%.6f %.9f %.9f 0 0 0 %.9f %.9f\n" % (k / rate, x, y, math.sin(a / 2), math.cos(a / 2)))
    times.sort()
    print("%.3f ms per frame (LK + RANSAC, one thread)" % times[len(times) // 2])


main()
