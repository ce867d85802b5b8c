#!/usr/bin/env bash
# Checks the package built by `cargo deb -p slope-ros2`: it holds the node,
# its unit, its README and the interface package slope_msgs (every .msg of
# ros2/slope_msgs); it depends on slope; its postinst enables and starts
# nothing; the unit passes `systemd-analyze verify` with the package's own
# binary (and slope.target, which the package slope brings); the program runs.
#
#   packaging/check-ros2-deb.sh target/debian/slope-ros2_0.1.0-1_amd64.deb
#
# Needs dpkg-deb and systemd-analyze. Exits non-zero, naming what is wrong, on
# the first failed check.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 1 ] || [ ! -f "$1" ]; then
    echo "usage: $0 PACKAGE.deb" >&2
    exit 2
fi
deb=$1
fail() { echo "check-ros2-deb: $deb: $*" >&2; exit 1; }

[ "$(dpkg-deb -f "$deb" Package)" = slope-ros2 ] || fail "the package is not named slope-ros2"
# `slope` alone in the list: slope-kinect2 provides it.
dpkg-deb -f "$deb" Depends | tr ',' '\n' | grep -qx ' *slope *' || fail "it does not depend on slope"

expected=(
    /usr/bin/slope-ros2
    /usr/lib/systemd/system/slope-ros2.service
    /usr/share/doc/slope-ros2/README.md
    /usr/share/slope-ros2/slope_msgs/package.xml
    /usr/share/slope-ros2/slope_msgs/CMakeLists.txt
)
for msg in ros2/slope_msgs/msg/*.msg; do
    expected+=("/usr/share/slope-ros2/slope_msgs/msg/$(basename "$msg")")
done
listing=$(dpkg-deb -c "$deb" | awk '{ print substr($6, 2) }')
for path in "${expected[@]}"; do
    grep -qxF "$path" <<<"$listing" || fail "$path is missing (dpkg-deb -c)"
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dpkg-deb -e "$deb" "$work/control"
postinst="$work/control/postinst"
[ -f "$postinst" ] || fail "there is no postinst (cargo-deb's systemd fragments)"
# cargo-deb's "don't enable" fragment re-enables the unit only when it was
# enabled before (`debian-installed`); the "enable" fragment has no such guard.
if [ "$(grep -c 'deb-systemd-helper unmask' "$postinst")" != "$(grep -c 'deb-systemd-helper debian-installed' "$postinst")" ]; then
    fail "the postinst enables slope-ros2.service on install"
fi
grep -q 'deb-systemd-invoke start' "$postinst" && fail "the postinst starts slope-ros2.service on install"
grep -q 'slope-ros2.service' "$work/control/prerm" || fail "the prerm does not stop slope-ros2.service"

root="$work/root"
dpkg-deb -x "$deb" "$root"
unit="$root/usr/lib/systemd/system/slope-ros2.service"
grep -qx 'RestartPreventExitStatus=78 2' "$unit" || fail "slope-ros2.service lacks RestartPreventExitStatus=78 2"
grep -qx 'Type=notify' "$unit" || fail "slope-ros2.service is not Type=notify"
# slope.target is the package slope's; the default dependencies
# (sysinit.target, network-online.target, ...) this machine's.
cp systemd/slope.target "$root/usr/lib/systemd/system/"
cp -rn /usr/lib/systemd/system/. "$root/usr/lib/systemd/system/"
if ! output=$(systemd-analyze verify --root="$root" slope-ros2.service 2>&1) || [ -n "$output" ]; then
    fail "systemd-analyze verify: ${output:-failed}"
fi
version=$("$root/usr/bin/slope-ros2" --version) || fail "/usr/bin/slope-ros2 --version fails"
echo "check-ros2-deb: $deb: $version, its unit, README and slope_msgs ($((${#expected[@]} - 5)) messages) in place; unit verified"
