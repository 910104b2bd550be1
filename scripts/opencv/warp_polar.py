# Times OpenCV's warpPolar (point sampling) at 640x480 -> 128x128 on one thread, for
# comparison with `ocellus bench logpolar`. Run: target/opencv-venv/bin/python
# scripts/opencv/warp_polar.py assets/astronaut.png (the venv comes from scripts/opencv/run.sh).
import cv2, numpy as np, time, sys
img = cv2.imread(sys.argv[1])
img = cv2.resize(img, (640, 480), interpolation=cv2.INTER_NEAREST)
grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
cv2.setNumThreads(1)
centre = (319.5, 239.5)
for name, src in [("grey", grey), ("rgb", img)]:
    for flags in [cv2.INTER_LINEAR + cv2.WARP_POLAR_LOG, cv2.INTER_NEAREST + cv2.WARP_POLAR_LOG]:
        ts = []
        for _ in range(2000):
            t = time.perf_counter()
            cv2.warpPolar(src, (128, 128), centre, 240.0, flags)
            ts.append((time.perf_counter() - t) * 1e6)
        ts.sort()
        print(name, "linear" if flags & 1 else "nearest", "%.1f us" % ts[len(ts)//2])
