#!/usr/bin/env python3
"""OpenCV StereoSGBM / StereoBM on Middlebury Aloe, under protogist's protocol.

Run by `cargo xtask bench` in a venv with scripts/requirements-opencv.txt.
Prints one JSON object per line: matcher, block size, width, max disparity,
bad-1/2/4 over estimated and over all GT pixels, MAE, density, ms.

The protocol mirrors `protogist stereo` (host/src/ground_truth.rs):
- images area-averaged (INTER_AREA) to the working width, aspect kept,
  height rounded;
- GT: 0 = unknown; downscaled as the overlap-weighted mean of the known
  pixels, unknown when less than half of the footprint is known, times the
  width ratio;
- bad-k: |error| > k px; "all" counts a missing estimate as an error.
"""
import argparse
import json
import time

import cv2
import numpy as np


def area(img, w, h):
    return cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)


def gt_at(gt_full, w, h):
    known = (gt_full > 0).astype(np.float32)
    s = area(gt_full.astype(np.float32) * known, w, h)
    k = area(known, w, h)
    out = np.full((h, w), np.nan, np.float32)
    valid = k >= 0.5
    out[valid] = s[valid] / k[valid] * (w / gt_full.shape[1])
    return out


def metrics(est, gt):
    g = ~np.isnan(gt)
    e = g & ~np.isnan(est)
    n_gt, n_est = int(g.sum()), int(e.sum())
    err = np.abs(est[e] - gt[e])
    res = {"gt_pixels": n_gt, "estimated": n_est}
    for k in (1, 2, 4):
        bad = int((err > k).sum())
        res[f"bad{k}_estimated"] = 100.0 * bad / max(n_est, 1)
        res[f"bad{k}_all"] = 100.0 * (bad + n_gt - n_est) / max(n_gt, 1)
    res["mae"] = float(err.mean()) if n_est else 0.0
    res["density"] = 100.0 * n_est / max(n_gt, 1)
    return res


def run(matcher, left, right, d, bs):
    nd = ((d + 1 + 15) // 16) * 16  # disparities 0..d, a multiple of 16
    if matcher == "sgbm":
        m = cv2.StereoSGBM_create(minDisparity=0, numDisparities=nd, blockSize=bs,
                                  P1=8 * 3 * bs * bs, P2=32 * 3 * bs * bs)
        a, b = left, right
    else:
        m = cv2.StereoBM_create(numDisparities=nd, blockSize=bs)
        a, b = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY), cv2.cvtColor(right, cv2.COLOR_BGR2GRAY)
    t = time.perf_counter()
    disp = m.compute(a, b)
    ms = 1e3 * (time.perf_counter() - t)
    est = disp.astype(np.float32) / 16.0
    est[disp < 0] = np.nan
    est[est > d] = np.nan
    return est, ms


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--data", required=True, help="folder with aloeL.jpg, aloeR.jpg, aloeGT.png")
    p.add_argument("--config", action="append", required=True, help="WIDTH:MAXDISP")
    a = p.parse_args()
    cv2.setNumThreads(1)
    l_full = cv2.imread(f"{a.data}/aloeL.jpg", cv2.IMREAD_COLOR)
    r_full = cv2.imread(f"{a.data}/aloeR.jpg", cv2.IMREAD_COLOR)
    gt_full = cv2.imread(f"{a.data}/aloeGT.png", cv2.IMREAD_GRAYSCALE)
    if l_full is None or r_full is None or gt_full is None:
        raise SystemExit("cannot read the Aloe files in " + a.data)
    H, W = gt_full.shape
    for c in a.config:
        w, d = (int(v) for v in c.split(":"))
        h = max(1, round(H * w / W))
        left, right, gt = area(l_full, w, h), area(r_full, w, h), gt_at(gt_full, w, h)
        for matcher, sizes in (("sgbm", (3, 5)), ("bm", (5,))):
            for bs in sizes:
                est, ms = run(matcher, left, right, d, bs)
                row = {"matcher": matcher, "block": bs, "width": w, "max_disp": d, "ms": ms,
                       "opencv": cv2.__version__}
                row.update(metrics(est, gt))
                print(json.dumps(row))


if __name__ == "__main__":
    main()
