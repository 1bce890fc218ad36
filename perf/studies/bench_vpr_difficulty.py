"""What makes a VPR dataset easy or hard: per-split image statistics, the pairs' viewpoint and
appearance change, and where in the image SIFT-VLAD finds its places (issue 36).

Run: ``python perf/run.py vpr_difficulty --datasets DIR[,DIR ...]`` (folders of ``marsscene
benchmark vpr``). Per dataset it prints:

* per split (every ``STRIDE``-th frame): mean grey level, RMS contrast of the ground (rows below
  the horizon band: std / mean), grey-level entropy (bits), SIFT keypoints per image (no cap)
  and the share of them in the lower half (ground within ~5 m of the rover);
* per query and its nearest database frame (by position): distance (m), heading difference
  (deg), normalised cross-correlation of 64 x 48 grey thumbnails, RootSIFT matches passing the
  ratio test (0.8) and the RANSAC fundamental-matrix inliers among them;
* SIFT-VLAD Recall@1/5 (2 m) from all keypoints, from the lower half's only (the ground near
  the rover) and from the upper third's only (horizon, far terrain, the habitat when in view);
  and R@1 among queries that show the landmark (``poses.csv`` ``landmark_px`` >= 20) and the
  others.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

from perf.suite import Param, names

STRIDE = 4
PARAMS = (Param("datasets", names, "VPR dataset folders, comma-separated (needed)", quick=(),
                full=()),)
RADIUS_M = 2.0


def _frames(dataset: Path) -> dict[str, list[dict[str, str]]]:
    with open(dataset / "poses.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    out: dict[str, list[dict[str, str]]] = {"database": [], "queries": []}
    for r in rows:
        out[r["split"]].append(r)
    for split in out:
        out[split].sort(key=lambda r: r["file"])
    return out


def _features(dataset: Path, rows: list[dict[str, str]]):  # type: ignore[no-untyped-def]
    import cv2

    sift = cv2.SIFT_create(nfeatures=500)  # type: ignore[attr-defined]
    out = []
    for r in rows:
        grey = cv2.imread(str(dataset / r["file"]), cv2.IMREAD_GRAYSCALE)
        kp, d = sift.detectAndCompute(grey, None)
        d = np.zeros((0, 128), np.float32) if d is None else d.astype(np.float32)
        y = np.array([k.pt[1] for k in kp], np.float32) / grey.shape[0]
        out.append((np.sqrt(d / (d.sum(axis=1, keepdims=True) + 1e-7)), y))
    return out


def _stats(dataset: Path, rows: list[dict[str, str]]) -> dict[str, float]:
    import cv2

    sift = cv2.SIFT_create()  # type: ignore[attr-defined]
    mean, contrast, entropy, kps, low = [], [], [], [], []
    for r in rows[::STRIDE]:
        g = cv2.imread(str(dataset / r["file"]), cv2.IMREAD_GRAYSCALE)
        ground = g[g.shape[0] // 4:].astype(np.float64)
        mean.append(g.mean() / 255.0)
        contrast.append(ground.std() / max(ground.mean(), 1e-6))
        p = np.bincount(g.ravel(), minlength=256) / g.size
        entropy.append(float(-(p[p > 0] * np.log2(p[p > 0])).sum()))
        kp = sift.detect(g, None)
        kps.append(len(kp))
        low.append(np.mean([k.pt[1] > g.shape[0] / 2 for k in kp]) if kp else 0.0)
    return {"mean": float(np.mean(mean)), "contrast": float(np.mean(contrast)),
            "entropy": float(np.mean(entropy)), "sift": float(np.median(kps)),
            "lower_share": float(np.mean(low))}


def _pairs(dataset: Path, db: list[dict[str, str]], q: list[dict[str, str]],
           feats_db, feats_q) -> dict[str, float]:  # type: ignore[no-untyped-def]
    import cv2
    from PIL import Image
    from scipy.spatial import cKDTree

    xy_db = np.array([[float(r["x_m"]), float(r["y_m"])] for r in db])
    xy_q = np.array([[float(r["x_m"]), float(r["y_m"])] for r in q])
    dist, nearest = cKDTree(xy_db).query(xy_q)
    yaw = np.array([float(r["yaw_deg"]) for r in q]) - np.array(
        [float(db[i]["yaw_deg"]) for i in nearest])
    dyaw = np.abs((yaw + 180.0) % 360.0 - 180.0)
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    ncc, good, inliers = [], [], []
    for qi in range(0, len(q), STRIDE):
        di = int(nearest[qi])
        thumbs = []
        for r in (q[qi], db[di]):
            with Image.open(dataset / r["file"]) as im:
                t = np.asarray(im.convert("L").resize((64, 48)), np.float64)
            thumbs.append((t - t.mean()) / (t.std() + 1e-6))
        ncc.append(float((thumbs[0] * thumbs[1]).mean()))
        a, b = feats_q[qi][0], feats_db[di][0]
        if len(a) < 2 or len(b) < 2:
            good.append(0)
            inliers.append(0)
            continue
        m = [x for x, y in matcher.knnMatch(a, b, k=2) if x.distance < 0.8 * y.distance]
        good.append(len(m))
        inliers.append(0)
        if len(m) >= 8:
            kq = _kp(dataset / q[qi]["file"])
            kd = _kp(dataset / db[di]["file"])
            pa = np.float32([kq[x.queryIdx] for x in m])
            pb = np.float32([kd[x.trainIdx] for x in m])
            _, mask = cv2.findFundamentalMat(pa, pb, cv2.FM_RANSAC, 1.0, 0.99)
            inliers[-1] = int(mask.sum()) if mask is not None else 0
    return {"dist_m": float(np.median(dist)), "dyaw_deg": float(np.median(dyaw)),
            "ncc": float(np.median(ncc)), "matches": float(np.median(good)),
            "inliers": float(np.median(inliers))}


_KP: dict[Path, np.ndarray] = {}


def _kp(path: Path) -> np.ndarray:
    import cv2

    if path not in _KP:
        sift = cv2.SIFT_create(nfeatures=500)  # type: ignore[attr-defined]
        kp = sift.detect(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE), None)
        _KP[path] = np.float32([k.pt for k in kp])
    return _KP[path]


def _recall(feats_db, feats_q, db, q, keep) -> tuple[float, float, np.ndarray]:  # type: ignore[no-untyped-def]
    from scipy.cluster.vq import kmeans2

    from marsscene.benchmark.vpr.eval import recall_at, retrieve
    from marsscene.benchmark.vpr.vlad import vlad

    sel_db = [d[keep(y)] for d, y in feats_db]
    sel_q = [d[keep(y)] for d, y in feats_q]
    pool = np.concatenate([d for d in sel_db if len(d)])
    rng = np.random.default_rng(0)
    sample = pool[rng.choice(len(pool), size=min(len(pool), 50_000), replace=False)]
    centres, _ = kmeans2(sample.astype(np.float64), 64, iter=20, minit="++", seed=rng)
    ranked = retrieve(vlad(sel_db, centres.astype(np.float32)),
                      vlad(sel_q, centres.astype(np.float32)), k=20)
    xy_db = np.array([[float(r["x_m"]), float(r["y_m"])] for r in db])
    xy_q = np.array([[float(r["x_m"]), float(r["y_m"])] for r in q])
    rec = recall_at(ranked, xy_db, xy_q, RADIUS_M)
    top1 = np.hypot(*(xy_db[ranked[:, 0]] - xy_q).T) <= RADIUS_M
    return rec.recall[1], rec.recall[5], top1


def main(datasets: tuple[str, ...]) -> list[dict[str, object]]:
    if not datasets:
        raise SystemExit("vpr_difficulty: --datasets DIR[,DIR] (marsscene benchmark vpr) needed")
    rows: list[dict[str, object]] = []
    for arg in datasets:
        ds = Path(arg)
        t0 = time.perf_counter()
        frames = _frames(ds)
        db, q = frames["database"], frames["queries"]
        for split in ("database", "queries"):
            s = _stats(ds, frames[split])
            r = frames[split][0]
            print(f"vpr difficulty {ds.name} {split:8s} (tau {r['tau']}, sun "
                  f"{r['sun_elevation_deg']} deg, {len(frames[split])} frames): mean grey "
                  f"{s['mean']:.3f}, ground RMS contrast {s['contrast']:.3f}, entropy "
                  f"{s['entropy']:.2f} bits, SIFT keypoints {s['sift']:.0f} "
                  f"({100 * s['lower_share']:.0f} % in the lower half)", flush=True)
            rows.append({"dataset": ds.name, "split": split, **s})
        feats_db, feats_q = _features(ds, db), _features(ds, q)
        p = _pairs(ds, db, q, feats_db, feats_q)
        print(f"vpr difficulty {ds.name} pairs (query, nearest database frame): "
              f"{p['dist_m']:.2f} m apart, heading {p['dyaw_deg']:.1f} deg, thumbnail NCC "
              f"{p['ncc']:.2f}, RootSIFT ratio-test matches {p['matches']:.0f}, RANSAC inliers "
              f"{p['inliers']:.0f} (medians)", flush=True)
        rows.append({"dataset": ds.name, "split": "pairs", **p})
        parts = {"all keypoints": lambda y: y >= 0.0, "lower half": lambda y: y >= 0.5,
                 "upper third": lambda y: y < 1.0 / 3.0}
        landmark = np.array([float(r.get("landmark_px") or 0.0) >= 20.0 for r in q])
        for label, keep in parts.items():
            r1, r5, top1 = _recall(feats_db, feats_q, db, q, keep)
            extra = ""
            if landmark.any() and label == "all keypoints":
                extra = (f"; R@1 with the landmark in view (>= 20 px, {landmark.sum()} queries) "
                         f"{100 * top1[landmark].mean():.1f}, without "
                         f"{100 * top1[~landmark].mean():.1f}")
            print(f"vpr difficulty {ds.name} SIFT-VLAD from {label}: R@1 {100 * r1:.1f}, R@5 "
                  f"{100 * r5:.1f}{extra}", flush=True)
            rows.append({"dataset": ds.name, "split": f"SIFT-VLAD, {label}", "r1_pct": 100 * r1,
                         "r5_pct": 100 * r5})
        print(f"vpr difficulty {ds.name}: {time.perf_counter() - t0:.0f} s", flush=True)
    return rows

