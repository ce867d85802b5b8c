#!/usr/bin/env python3
"""The paper's road-slope method, as written, in Open3D: a peer for `slope-eval --method paper`.

Stages (paper section, parameters): statistical outlier removal (2.1: 20 neighbours, 2 std);
two RANSAC planes, one after the other (2.2); a pass-through that caps each plane at 10,000 points
(3.1); PCA normals over K = 100 nearest neighbours, oriented towards the camera (2.3); cosine k-means
on each plane's normals, farthest-first centres, the dominant cluster kept (3.1); the mean angle
over 100 random ramp/ground normal pairs (3.2), angle = atan2(|n1 x n2|, n1 . n2).

Reads recordings in the project's format (shared/spec/recording-format.md). Only the stages are
timed: reading the PNG, projecting it and copying the points into Open3D are not.

    python3 bench/peer/peer_open3d.py tests/recordings/ramp16 [--json] [--max-frames N] [--seed S]
"""
import argparse
import csv
import ctypes
import json
import time
import tomllib
from pathlib import Path

import numpy as np
from PIL import Image

try:  # open3d's wheel links libusb-1.0.so.0; libusb-package ships one, so no apt package is needed
    import libusb_package

    ctypes.CDLL(str(libusb_package.get_library_path()), mode=ctypes.RTLD_GLOBAL)
except (ImportError, OSError):
    pass
import open3d as o3d

SOR_NEIGHBOURS, SOR_STD_RATIO = 20, 2.0  # paper 2.1: m = 20, alpha = 2
RANSAC_THRESHOLD_M, RANSAC_ITERATIONS, RANSAC_CONFIDENCE = 0.02, 500, 0.999  # not in the paper; ours
MAX_PLANE_POINTS = 10_000  # paper 3.1
NORMAL_NEIGHBOURS = 100  # paper 4.2: K = 100
KMEANS_CLUSTERS, KMEANS_ITERATIONS = 3, 30  # the paper gives no k; ours
PAIR_DRAWS = 100  # paper 4.2


def read_recording(path):
    """recording.toml and frames.csv -> (depth table, up vector in camera coordinates, frame rows)."""
    meta = tomllib.loads((path / "recording.toml").read_text())
    if meta.get("format") != "slope-recording" or meta.get("version") != 1:
        raise SystemExit(f"{path}/recording.toml: not a version 1 slope recording")
    mount = meta.get("mount", {})
    if "pitch_deg" in mount:  # the ground's upward normal, as the spec gives it
        p, r = np.radians(mount["pitch_deg"]), np.radians(mount.get("roll_deg", 0.0))
        up = np.array([-np.sin(r) * np.cos(p), -np.cos(r) * np.cos(p), np.sin(p)])
    else:  # an upright camera: -y
        up = np.array([0.0, -1.0, 0.0])
    with open(path / "frames.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    truth = meta.get("truth", {}).get("slope_deg")
    for row in rows:
        row["truth_deg"] = float(row["slope_deg"]) if row.get("slope_deg") else truth
    return meta["depth"], up, rows


def project(png, depth):
    """16-bit depth PNG -> N x 3 points (x right, y down, z forward), metres; no-reading pixels dropped."""
    z = np.asarray(Image.open(png), dtype=np.float64) * depth["unit_m"]
    v, u = np.indices(z.shape)
    ok = z > 0
    z = z[ok]
    x = (u[ok] - depth["cx"]) * z / depth["fx"]
    y = (v[ok] - depth["cy"]) * z / depth["fy"]
    return np.column_stack([x, y, z])


def pass_through(plane, max_points):
    """PCL-style pass-through on depth: keep the points nearer than the depth that leaves max_points."""
    z = np.asarray(plane.points)[:, 2]
    if len(z) <= max_points:
        return plane
    return plane.select_by_index(np.argpartition(z, max_points - 1)[:max_points].tolist())


def cosine_kmeans(normals, k, iterations):
    """Cosine k-means on unit normals; centres chosen farthest-first by cosine distance 1 - cos;
    returns the normals of the largest cluster."""
    centres = [normals[np.argmax(normals @ normals.mean(axis=0))]]  # the most typical normal
    while len(centres) < k:  # next: the normal farthest (cosine distance) from every chosen centre
        centres.append(normals[np.argmin((normals @ np.array(centres).T).max(axis=1))])
    centres, labels = np.array(centres), None
    for _ in range(iterations):
        new = np.argmax(normals @ centres.T, axis=1)  # nearest centre = largest cosine
        if labels is not None and np.array_equal(new, labels):
            break
        labels = new
        sums = np.stack([np.bincount(labels, weights=normals[:, j], minlength=k) for j in range(3)], axis=1)
        filled = np.linalg.norm(sums, axis=1) > 0  # an empty cluster keeps its centre
        centres[filled] = sums[filled] / np.linalg.norm(sums[filled], axis=1, keepdims=True)
    return normals[labels == np.bincount(labels, minlength=k).argmax()]


def estimate(points, up, seed):
    """One frame: returns (slope in degrees, ms per stage, the two planes [a, b, c, d])."""
    ms, t = {}, time.perf_counter()

    def lap(stage):
        nonlocal t
        now = time.perf_counter()
        ms[stage] = (now - t) * 1e3
        t = now

    o3d.utility.random.seed(seed)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    lap("convert")  # not a stage: the copy into Open3D, reported but left out of the total

    cloud, _ = cloud.remove_statistical_outlier(nb_neighbors=SOR_NEIGHBOURS, std_ratio=SOR_STD_RATIO)
    lap("outlier")

    planes, rest = [], cloud
    for _ in range(2):  # the largest plane, then the largest of what is left
        model, inliers = rest.segment_plane(
            RANSAC_THRESHOLD_M, ransac_n=3, num_iterations=RANSAC_ITERATIONS, probability=RANSAC_CONFIDENCE)
        planes.append((np.array(model), rest.select_by_index(inliers)))
        rest = rest.select_by_index(inliers, invert=True)
    # ground: the plane whose normal is closest to up (either sign); the other is the inclined plane
    ground, inclined = sorted(planes, key=lambda plane: -abs(plane[0][:3] @ up))
    lap("ransac")

    ground_cloud, inclined_cloud = (pass_through(plane, MAX_PLANE_POINTS) for _, plane in (ground, inclined))
    lap("pass_through")

    normals = []
    for plane in (ground_cloud, inclined_cloud):
        plane.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(NORMAL_NEIGHBOURS))
        plane.orient_normals_towards_camera_location(np.zeros(3))
        normals.append(np.asarray(plane.normals))
    lap("normals")

    ground_normals, inclined_normals = (cosine_kmeans(n, KMEANS_CLUSTERS, KMEANS_ITERATIONS) for n in normals)
    lap("kmeans")

    rng = np.random.default_rng(seed)
    a = inclined_normals[rng.integers(len(inclined_normals), size=PAIR_DRAWS)]
    b = ground_normals[rng.integers(len(ground_normals), size=PAIR_DRAWS)]
    slope_deg = float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), (a * b).sum(axis=1))).mean())
    lap("cumulative")

    ms["total"] = sum(v for stage, v in ms.items() if stage != "convert")
    return slope_deg, ms, [ground[0].tolist(), inclined[0].tolist()]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("recordings", nargs="+", type=Path)
    parser.add_argument("--json", action="store_true", help="one JSON object per frame")
    parser.add_argument("--max-frames", type=int, help="at most this many frames of each recording")
    parser.add_argument("--seed", type=int, default=0, help="RANSAC and pair draws use seed + frame index")
    args = parser.parse_args()
    for path in args.recordings:
        depth, up, rows = read_recording(path)
        for row in rows[: args.max_frames]:
            points = project(path / row["depth"], depth)
            slope_deg, ms, planes = estimate(points, up, args.seed + int(row["index"]))
            if args.json:
                print(json.dumps(dict(recording=str(path), index=int(row["index"]), slope_deg=slope_deg,
                                      truth_deg=row["truth_deg"], points=len(points), ms=ms, planes=planes)),
                      flush=True)
            else:
                stages = "  ".join(f"{stage} {v:.1f}" for stage, v in ms.items())
                print(f"{path.name} frame {row['index']}: slope {slope_deg:.2f} deg (truth {row['truth_deg']}), "
                      f"ms: {stages}", flush=True)


if __name__ == "__main__":
    main()
