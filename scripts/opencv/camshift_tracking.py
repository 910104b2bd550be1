#!/usr/bin/env python3
"""The 2D ball tracker an OpenCV user would write (issue 16's baseline), against `ocellus track`.

For each generated sequence (`ocellus generate ball`: thrown, bouncing, approaching balls with
both occluders and noise, seeds 1-3, as `ocellus track study`), OpenCV follows the ball by
CamShift on a hue back-projection: the hue histogram (30 bins, pixels with S >= 60 and
V >= 32, the OpenCV tutorial's mask) of the same first-frame patch ocellus gets, the search
window started on it, cv2.CamShift per frame with 10 iterations or 1 px. Both trackers are
scored on the same frames by the median image-centre error over frames with at least half the
ball visible (the frames `ocellus track eval` scores), and by the frames more than the ball's
radius off. CamShift is 2D only: it has no depth to score.

Usage: scripts/opencv/run_camshift.sh (builds ocellus, makes the OpenCV virtual environment).
Not part of CI.
"""
import csv
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

OCELLUS = sys.argv[1] if len(sys.argv) > 1 else "target/release/ocellus"
SEEDS = [int(s) for s in (sys.argv[2] if len(sys.argv) > 2 else "1,2,3").split(",")]


def read_csv(path):
    with open(path) as f:
        return [dict((k, float(v)) for k, v in row.items()) for row in csv.DictReader(f)]


def camshift(frames_dir, patch):
    x, y, r = patch
    files = sorted(os.listdir(frames_dir))
    first = cv2.imread(os.path.join(frames_dir, files[0]))
    hsv = cv2.cvtColor(first, cv2.COLOR_BGR2HSV)
    mask = cv2.inRange(hsv, np.array((0.0, 60.0, 32.0)), np.array((180.0, 255.0, 255.0)))
    disc = np.zeros(mask.shape, np.uint8)
    cv2.circle(disc, (int(round(x)), int(round(y))), int(round(r)), 255, -1)
    hist = cv2.calcHist([hsv], [0], cv2.bitwise_and(mask, disc), [30], [0, 180])
    cv2.normalize(hist, hist, 0, 255, cv2.NORM_MINMAX)
    window = (int(x - r), int(y - r), int(2 * r) + 1, int(2 * r) + 1)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 1)
    centres = []
    for name in files:
        hsv = cv2.cvtColor(cv2.imread(os.path.join(frames_dir, name)), cv2.COLOR_BGR2HSV)
        back = cv2.calcBackProject([hsv], [0], hist, [0, 180], 1)
        box, window = cv2.CamShift(back, window, crit)
        if window[2] <= 0 or window[3] <= 0:  # lost: restart on the whole frame
            window = (0, 0, back.shape[1], back.shape[0])
        centres.append(box[0])
    return centres


def scores(truth, centres):
    errs, off = [], 0
    for t, c in zip(truth, centres):
        if t["visible_fraction"] < 0.5 or t["r_px"] <= 0:
            continue
        e = float(np.hypot(c[0] - t["u_px"], c[1] - t["v_px"]))
        errs.append(e)
        off += e > t["r_px"]
    return float(np.median(errs)), off, len(errs)


def main():
    cv2.setNumThreads(1)
    print("sequence     seed   CamShift: median px, frames off   ocellus track: median px, frames off")
    with tempfile.TemporaryDirectory() as tmp:
        for traj in ["throw", "bounce", "approach"]:
            for seed in SEEDS:
                world = os.path.join(tmp, f"{traj}{seed}")
                subprocess.run([OCELLUS, "generate", "ball", "--trajectory", traj, "--seed", str(seed), "--out", world],
                               check=True, capture_output=True)
                truth = read_csv(os.path.join(world, "truth.csv"))
                t0 = truth[0]
                patch = (t0["u_px"], t0["v_px"], 0.8 * t0["r_px"])
                cs = scores(truth, camshift(os.path.join(world, "frames"), patch))
                out = os.path.join(tmp, f"track{traj}{seed}")
                gravity = "0" if traj == "approach" else "9.81"
                subprocess.run([OCELLUS, "track", os.path.join(world, "frames"), "--camera", os.path.join(world, "camera.toml"),
                                "--radius-m", "0.05", "--patch", ",".join(f"{v:.3f}" for v in patch), "--gravity", gravity,
                                "--seed", str(seed), "--no-overlays", "--out", out], check=True, capture_output=True)
                track = {int(r["frame"]): r for r in read_csv(os.path.join(out, "track.csv"))}
                ours = [(track[k]["u_px"], track[k]["v_px"]) if k in track else (-1e4, -1e4) for k in range(len(truth))]
                oc = scores(truth, ours)
                print(f"{traj:<12} {seed:>4}   {cs[0]:>8.2f} px, {cs[1]:>2} of {cs[2]}            {oc[0]:>8.2f} px, {oc[1]:>2} of {oc[2]}")


if __name__ == "__main__":
    main()
