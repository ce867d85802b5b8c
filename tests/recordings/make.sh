#!/bin/sh
# Re-creates the recordings in this directory with slope-synth (tools/synth).
# Output is byte-identical for the same commands (seeded noise).
#
#   tests/recordings/make.sh                                # builds slope-synth with cargo
#   SLOPE_SYNTH=/path/to/slope-synth tests/recordings/make.sh
set -eu
here=$(cd "$(dirname "$0")" && pwd)
if [ -z "${SLOPE_SYNTH:-}" ]; then
    cargo build --quiet -p slope-synth --manifest-path "$here/../../Cargo.toml"
    SLOPE_SYNTH="${CARGO_TARGET_DIR:-$here/../../target}/debug/slope-synth"
fi
export RUST_LOG="${RUST_LOG:-warn}"

rm -rf "$here/ramp16" "$here/ramp16-clean"

# 16° ascending ramp 1.5 m ahead, default mount, realistic Kinect v2 noise, 30 frames.
"$SLOPE_SYNTH" --slope 16 --distance 1.5 --mount-height-m 0.5 --mount-pitch-deg -20 --frames 30 --seed 7 \
    --compression high -o "$here/ramp16"

# The same scene with every sensor effect off (exact geometry, mm quantisation), 10 frames.
"$SLOPE_SYNTH" --slope 16 --distance 1.5 --mount-height-m 0.5 --mount-pitch-deg -20 --frames 10 --seed 7 \
    --clean --compression high -o "$here/ramp16-clean"

du -sh "$here"
