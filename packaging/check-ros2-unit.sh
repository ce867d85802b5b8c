#!/usr/bin/env bash
# CI: systemd/slope-ros2.service passes `systemd-analyze verify` with the
# slope-ros2 program given (it is not in the Debian package, so
# check-deb.sh does not see it): the unit's settings, its ExecStart= binary,
# RestartPreventExitStatus=78 2 like the package's units.
# usage: packaging/check-ros2-unit.sh path/to/slope-ros2
set -euo pipefail
cd "$(dirname "$0")/.."
binary=${1:?usage: packaging/check-ros2-unit.sh path/to/slope-ros2}
fail() { echo "check-ros2-unit: $*" >&2; exit 1; }
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/usr/bin" "$root/usr/lib/systemd/system"
cp "$binary" "$root/usr/bin/slope-ros2"
cp systemd/slope-ros2.service systemd/slope.target "$root/usr/lib/systemd/system/"
# The default dependencies (sysinit.target, network-online.target, ...).
cp -rn /usr/lib/systemd/system/. "$root/usr/lib/systemd/system/"
if ! output=$(systemd-analyze verify --root="$root" slope-ros2.service 2>&1) || [ -n "$output" ]; then
    fail "systemd-analyze verify: ${output:-failed}"
fi
grep -qx 'RestartPreventExitStatus=78 2' systemd/slope-ros2.service ||
    fail "slope-ros2.service lacks RestartPreventExitStatus=78 2"
grep -qx 'Type=notify' systemd/slope-ros2.service || fail "slope-ros2.service is not Type=notify"
echo "check-ros2-unit: systemd/slope-ros2.service verified"
