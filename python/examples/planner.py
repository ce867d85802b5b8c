#!/usr/bin/env python3
"""A planner's view of slope: reads estimates and decides a speed.

    python3 python/examples/planner.py --service-prefix slope
    python3 python/examples/planner.py --json --count 10   # one JSON object per estimate

The speed rule is an example, not advice: full speed on flat ground, slower
on steeper ramps, stop above --max-slope or when the estimate is not trusted.
The slope is the tracked one while this frame agrees with the track; when it
does not (the track is about to follow a new surface, or this frame is an
outlier), the steeper of the two.
"""

import argparse
import json
import os
import sys

import slope_client


def speed_for(estimate, max_slope_deg: float, min_confidence: float) -> float:
    """Fraction of full speed for this estimate."""
    if estimate.status_name == "no_inclined_plane":
        return 1.0  # flat floor ahead
    if not estimate.ok or estimate.confidence < min_confidence:
        return 0.0  # not sure: stop
    slope = estimate.slope_deg
    tracked = estimate.tracked_slope_deg
    if tracked == tracked:  # not NaN: there is a track
        if estimate.tracked_accepted:
            slope = tracked  # this frame agrees with the track: its steadier value
        else:
            slope = max(slope, tracked, key=abs)  # they disagree: the steeper one
    if abs(slope) >= max_slope_deg:
        return 0.0
    return 1.0 - abs(slope) / max_slope_deg


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default_prefix = os.environ.get("SLOPE_SERVICE_PREFIX") or slope_client.DEFAULT_PREFIX
    parser.add_argument(
        "--service-prefix",
        "--prefix",
        dest="prefix",
        default=default_prefix,
        help="service prefix of the slope processes (default: $SLOPE_SERVICE_PREFIX, else slope)",
    )
    parser.add_argument("--count", type=int, help="stop after this many estimates")
    parser.add_argument("--timeout-s", type=float, help="stop after this many seconds without one")
    parser.add_argument("--json", action="store_true", help="one JSON object per estimate")
    parser.add_argument("--max-slope", type=float, default=20.0, help="degrees (default 20)")
    parser.add_argument("--min-confidence", type=float, default=0.5)
    args = parser.parse_args()

    seen = 0
    try:
        estimates = slope_client.subscribe(args.prefix, timeout_s=args.timeout_s)
        print(f"subscribed to {estimates.name}", file=sys.stderr, flush=True)
        for estimate in estimates:
            speed = speed_for(estimate, args.max_slope, args.min_confidence)
            if args.json:
                record = estimate.to_dict()
                record["speed"] = speed
                print(json.dumps(record), flush=True)
            else:
                slope = f"{estimate.slope_deg:+6.2f}" if estimate.ok else estimate.status_name
                print(
                    f"frame {estimate.frame_index:6d}  slope {slope}  "
                    f"confidence {estimate.confidence:.2f}  speed {speed:.2f}",
                    flush=True,
                )
            seen += 1
            if args.count is not None and seen >= args.count:
                break
    except slope_client.ServiceNotFound as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        pass
    if args.count is not None and seen < args.count:
        print(f"error: only {seen} of {args.count} estimates arrived", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
