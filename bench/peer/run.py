#!/usr/bin/env python3
"""Peer bench: `slope-eval --method paper` (ours) against peer_open3d.py (the paper in Open3D).

For each recording, both run on the same frames (the first --frames, a shorter recording's frames
repeated) in --rounds interleaved rounds (ours, Open3D, Open3D, ours, ...), each process pinned to
one core with taskset and single-threaded (OMP_NUM_THREADS=1 etc.). Timed per frame on both sides:
the stages only, from a cloud in memory to the slope; reading and projecting the depth PNG, and
Open3D's copy of the points into its PointCloud, are left out. Prints the median ms/frame, the
ratio and both median slopes against the recording's truth.

    python3 bench/peer/run.py                       # bundled + shared recordings
    python3 bench/peer/run.py --core 0 --rounds 5 DIR...
"""
import argparse
import atexit
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
SHARED_DATA = ROOT.parent / "shared" / "data"
DEFAULT_RECORDINGS = sorted(p.parent for p in (ROOT / "tests" / "recordings").glob("*/recording.toml")) + [
    SHARED_DATA / name for name in ("kinect2-stairs-front", "kinect2-stairs-top", "kinect1-office")]
SLOPE_EVAL = ROOT / "target/release/slope-eval"
SINGLE_THREAD = {v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS")}


def frames_view(recording, frames, into):
    """A recording in `into` whose frames.csv lists exactly `frames` rows: the recording's first
    frames, repeated when it has fewer; every other file is a symlink to the original."""
    for entry in recording.iterdir():
        if entry.name != "frames.csv":
            (into / entry.name).symlink_to(entry.resolve())
    with open(recording / "frames.csv", newline="") as f:
        reader = csv.DictReader(f)
        fields, rows = reader.fieldnames, list(reader)
    with open(into / "frames.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        for i in range(frames):
            writer.writerow({**rows[i % len(rows)], "index": i, "timestamp_ns": i * 33_333_333})
    return into


def run_pinned(core, command):
    out = subprocess.run(["taskset", "-c", str(core), *map(str, command)], capture_output=True, text=True,
                         env={**os.environ, **SINGLE_THREAD})
    if out.returncode != 0:
        sys.exit(f"failed: {' '.join(map(str, command))}\n{out.stderr}")
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def ours(core, recording):
    """Per frame {"ms": {"total": ..., stage: ...}, "slope_deg": ...}, and the recording's truth."""
    (result,) = run_pinned(core, [SLOPE_EVAL, "--json", "--method", "paper", "-q", recording])
    return [f for f in result["estimates"] if f["ms"]], result["truth_deg"]


def open3d(core, recording):
    return run_pinned(core, [sys.executable, HERE / "peer_open3d.py", "--json", recording])


def median_ms(frames, stage="total"):
    return statistics.median(f["ms"][stage] for f in frames)


def median_abs_slope(frames):
    slopes = [abs(f["slope_deg"]) for f in frames if f["slope_deg"] is not None]
    return statistics.median(slopes) if slopes else float("nan")


def table(header, rows):
    print("\n| " + " | ".join(header) + " |\n|" + "---|" * len(header))
    for row in rows:
        print("| " + " | ".join(row) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("recordings", nargs="*", type=Path, default=DEFAULT_RECORDINGS)
    parser.add_argument("--core", type=int, default=(os.cpu_count() or 1) - 1, help="CPU both run on (last)")
    parser.add_argument("--frames", type=int, default=10, help="frames per recording and round (10)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds per recording (3)")
    parser.add_argument("--no-build", action="store_true", help="skip `cargo build --release -p slope-tools`")
    args = parser.parse_args()
    if not args.no_build and subprocess.run(["cargo", "build", "--release", "-q", "-p", "slope-tools"], cwd=ROOT).returncode:
        sys.exit("run.py: `cargo build --release -p slope-tools` failed (--no-build uses target/release as it is)")
    global SLOPE_EVAL  # a copy, so that a rebuild during the run cannot change the binary under test
    copy_dir = tempfile.mkdtemp()
    atexit.register(shutil.rmtree, copy_dir)
    SLOPE_EVAL = Path(shutil.copy(ROOT / "target/release/slope-eval", Path(copy_dir) / "slope-eval"))
    print(f"taskset -c {args.core}, {' '.join(f'{k}=1' for k in SINGLE_THREAD)}; {args.frames} frames x "
          f"{args.rounds} interleaved rounds per recording; ms = stages only (no PNG reading or projection)", flush=True)

    results = []
    for recording in args.recordings:
        with tempfile.TemporaryDirectory() as tmp:
            view = frames_view(recording, args.frames, Path(tmp))
            our_frames, peer_frames = [], []
            for round_ in range(args.rounds):
                for side in ("ours", "open3d") if round_ % 2 == 0 else ("open3d", "ours"):
                    if side == "ours":
                        frames, truth = ours(args.core, view)
                        our_frames += frames
                    else:
                        peer_frames += open3d(args.core, view)
        results.append((recording.name, our_frames, peer_frames, truth))
        print(f"  {recording.name}: done", file=sys.stderr, flush=True)

    table(("recording", "ours ms/frame", "Open3D ms/frame", "Open3D / ours", "ours slope", "Open3D slope", "truth"),
          [(name, f"{median_ms(o):.1f}", f"{median_ms(p):.1f}", f"{median_ms(p) / median_ms(o):.0f}x",
            f"{median_abs_slope(o):.2f}", f"{median_abs_slope(p):.2f}", f"{truth:g}") for name, o, p, truth in results])
    stages = ("outlier", "ransac", "pass_through", "normals", "kmeans", "cumulative")
    table(("median ms, ours / Open3D", *stages),
          [(name, *(f"{median_ms(o, s):.1f} / {median_ms(p, s):.1f}" for s in stages)) for name, o, p, _ in results])
    print("(ours also spends time in selection, confidence and tracking, included in its ms/frame; "
          "Open3D's copy into a PointCloud is not, median "
          f"{statistics.median(f['ms']['convert'] for _, _, p, _ in results for f in p):.1f} ms)")


if __name__ == "__main__":
    main()
