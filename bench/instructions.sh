#!/usr/bin/env bash
# Instruction counts of the estimator (callgrind: deterministic, unlike the
# time on a shared machine): `Estimator::run` inclusive, one frame each of
# kinect2-stairs-front, kinect1-office (../shared/data) and ramp16 frame 0
# (tests/recordings), with the default configuration. Fails when a frame
# costs more than its budget in bench/instruction-budgets.txt (the counts
# reached when the budget was set, plus 5 %).
#
#   bench/instructions.sh            # measure and check
#   CONFIG='<toml>' bench/instructions.sh   # another estimator config (checked too)
#
# Needs valgrind (Debian: apt-get install valgrind). Builds the release
# example eval_recordings into the workspace's target directory.
set -euo pipefail
cd "$(dirname "$0")/.."

data=${SLOPE_SHARED_DATA:-../shared/data}
budgets=bench/instruction-budgets.txt
if ! command -v valgrind >/dev/null 2>&1 || ! command -v callgrind_annotate >/dev/null 2>&1; then
    echo "instructions: valgrind is not installed (Debian: apt-get install valgrind)" >&2
    exit 1
fi
cargo build --release --quiet -p slope-pipeline --example eval_recordings
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# ramp16 frame 0 alone: a recording of its first frame.
mkdir -p "$tmp/ramp16/depth" "$tmp/ramp16/color"
cp tests/recordings/ramp16/recording.toml "$tmp/ramp16/"
head -n 2 tests/recordings/ramp16/frames.csv >"$tmp/ramp16/frames.csv"
cp tests/recordings/ramp16/depth/000000.png "$tmp/ramp16/depth/"
cp tests/recordings/ramp16/color/000000.png "$tmp/ramp16/color/"

# Instructions of Estimator::run, inclusive, in recording $2 (millions).
count() {
    local out="$tmp/cg.$1"
    METHODS=paper REPEAT=1 valgrind --tool=callgrind --callgrind-out-file="$out" \
        target/release/examples/eval_recordings "$2" >/dev/null 2>"$tmp/valgrind.log" || {
        cat "$tmp/valgrind.log" >&2
        return 1
    }
    callgrind_annotate --inclusive=yes "$out" |
        awk '!done && /Estimator::run[ (]/ { gsub(",", "", $1); printf "%.1f\n", $1 / 1e6; done = 1 }'
}

failed=0
printf '%-22s %10s %10s\n' frame "M instr" "budget M"
for frame in kinect2-stairs-front:"$data/kinect2-stairs-front" \
    kinect1-office:"$data/kinect1-office" ramp16-frame0:"$tmp/ramp16"; do
    name=${frame%%:*}
    dir=${frame#*:}
    if [ ! -f "$dir/recording.toml" ]; then
        echo "instructions: $dir is missing" >&2
        exit 1
    fi
    m=$(count "$name" "$dir")
    if [ -z "$m" ]; then
        echo "instructions: no Estimator::run in the callgrind output of $name" >&2
        exit 1
    fi
    budget=$(awk -v n="$name" '$1 == n { print $2 }' "$budgets")
    printf '%-22s %10s %10s\n' "$name" "$m" "${budget:--}"
    if [ -n "$budget" ] && awk -v m="$m" -v b="$budget" 'BEGIN { exit !(m > b) }'; then
        echo "instructions: $name costs $m M instructions, over its budget of $budget M ($budgets)" >&2
        failed=1
    fi
done
exit "$failed"
