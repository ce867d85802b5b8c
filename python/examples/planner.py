#!/usr/bin/env python3
"""A planner's view of slope: reads estimates and decides a speed.

    python3 python/examples/planner.py --service-prefix slope
    python3 python/examples/planner.py --json --count 10   # one JSON object per estimate

The speed rule is an example, not advice: slower on steeper ramps, stop above
--max-slope or when the estimate is not trusted, and --no-ramp-speed when no
ramp is seen (`no_inclined_plane`): the camera sees no surface where the floor
drops away, so a step or slope down beyond the floor's edge reads the same as
a flat floor. What differs is how far ahead the floor was seen
(`ground_seen_to_m`): where it ends closer than --min-ground-ahead, stop. Only
other sensors (cliff sensors, a map) allow full speed there.
The slope is the tracked one while this frame agrees with the track; when it
does not (the track is about to follow a new surface, or this frame is an
outlier), the steeper of the two.
"""

import argparse
import json
import os
import sys

import slope_client


def speed_for(
    estimate,
    max_slope_deg: float,
    min_confidence: float,
    no_ramp_speed: float,
    min_ground_ahead_m: float,
) -> float:
    """Fraction of full speed for this estimate."""
    if estimate.status_name == "no_inclined_plane":
        # No ramp seen: a flat floor, or a drop-off the camera cannot see.
        seen = estimate.ground_seen_to
        if seen is not None and seen < min_ground_ahead_m:
            return 0.0  # the floor ends close ahead: stop before its edge
        return no_ramp_speed
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


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not at least 1")
    return value


def positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{text} is not a number above 0")
    return value


def fraction(text: str) -> float:
    value = float(text)
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"{text} is not in [0, 1]")
    return value


def service_prefix(text: str) -> str:
    """The rules of the Rust programs' --service-prefix."""
    if not text:
        raise argparse.ArgumentTypeError(
            "the service prefix is empty (check SLOPE_SERVICE_PREFIX); the default is 'slope'"
        )
    if text.startswith("/") or text.endswith("/") or any(ord(c) < 32 for c in text):
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a usable service prefix: no leading or trailing '/', "
            "no control characters"
        )
    return text


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default_prefix = os.environ.get("SLOPE_SERVICE_PREFIX", slope_client.DEFAULT_PREFIX)
    parser.add_argument(
        "--service-prefix",
        "--prefix",
        dest="prefix",
        type=service_prefix,
        default=default_prefix,
        help="service prefix of the slope processes (default: $SLOPE_SERVICE_PREFIX, else slope)",
    )
    parser.add_argument("--count", type=positive_int, help="stop after this many estimates")
    parser.add_argument(
        "--timeout-s", type=positive_float, help="stop after this many seconds without one"
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per estimate")
    parser.add_argument(
        "--max-slope", type=positive_float, default=20.0, help="degrees (default 20)"
    )
    parser.add_argument("--min-confidence", type=fraction, default=0.5, help="(default 0.5)")
    parser.add_argument(
        "--no-ramp-speed",
        type=fraction,
        default=0.5,
        help="fraction of full speed when no ramp is seen (default 0.5): a drop-off the camera "
        "cannot see looks the same",
    )
    parser.add_argument(
        "--min-ground-ahead",
        type=positive_float,
        default=1.0,
        help="metres (default 1.0): with no ramp seen, stop when the floor was seen to end closer "
        "than this (ground_seen_to_m), a drop-off",
    )
    args = parser.parse_args()

    seen = 0
    try:
        estimates = slope_client.subscribe(args.prefix, timeout_s=args.timeout_s)
        print(f"subscribed to {estimates.name}", file=sys.stderr, flush=True)
        for estimate in estimates:
            speed = speed_for(
                estimate,
                args.max_slope,
                args.min_confidence,
                args.no_ramp_speed,
                args.min_ground_ahead,
            )
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
    except slope_client.SlopeClientError as err:
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
