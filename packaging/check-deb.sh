#!/usr/bin/env bash
# Checks a slope package built by `cargo deb -p slope-tools [--variant kinect2]`:
# it holds every program, unit, conffile, the sysusers, tmpfiles and udev
# files and the documents; /etc files are conffiles; the postinst creates the
# user but enables and starts no unit; and the units pass `systemd-analyze
# verify` with the package's own binaries.
#
#   packaging/check-deb.sh target/debian/slope_0.1.0-1_amd64.deb
#
# Needs dpkg-deb and systemd-analyze (package systemd). Exits non-zero, naming
# what is wrong, on the first failed check.
set -euo pipefail

if [ $# -ne 1 ] || [ ! -f "$1" ]; then
    echo "usage: $0 PACKAGE.deb" >&2
    exit 2
fi
deb=$1
fail() {
    echo "check-deb: $deb: $*" >&2
    exit 1
}

package=$(dpkg-deb -f "$deb" Package)
programs=(slope-estimator slope-replay slope-echo slope-record slope-eval slope-demo slope-convert slope-synth)
units=(slope-estimator.service slope.target)
case "$package" in
slope) ;;
slope-kinect2)
    programs+=(slope-capture)
    units+=(slope-capture.service)
    ;;
*) fail "unknown package name '$package'" ;;
esac

expected=(
    /etc/slope/slope.toml
    /etc/default/slope
    /usr/lib/sysusers.d/slope.conf
    /usr/lib/tmpfiles.d/slope.conf
    /usr/lib/udev/rules.d/60-slope-kinect2.rules
    /usr/share/doc/slope/README.md
    /usr/share/doc/slope/systemd/README.md
    /usr/share/doc/slope/pipeline/README.md
    /usr/share/doc/slope/ipc-types/README.md
    /usr/share/doc/slope/sensor/README.md
)
for program in "${programs[@]}"; do expected+=("/usr/bin/$program"); done
for unit in "${units[@]}"; do expected+=("/usr/lib/systemd/system/$unit"); done

# `dpkg-deb -c` lists `./usr/bin/slope-estimator`; keep the path only.
listing=$(dpkg-deb -c "$deb" | awk '{ print substr($6, 2) }')
for path in "${expected[@]}"; do
    grep -qxF "$path" <<<"$listing" || fail "$path is missing (dpkg-deb -c)"
done
if [ "$package" = slope ] && grep -q '^/usr/bin/slope-capture$\|slope-capture.service$' <<<"$listing"; then
    fail "slope-capture belongs in slope-kinect2 only"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dpkg-deb -e "$deb" "$work/control"
for conffile in /etc/slope/slope.toml /etc/default/slope; do
    grep -qxF "$conffile" "$work/control/conffiles" || fail "$conffile is not a conffile"
done
postinst="$work/control/postinst"
# Once each: the debhelper token appears once in packaging/debian/postinst.
[ "$(grep -c '^ *systemd-sysusers .* slope.conf$' "$postinst")" = 1 ] ||
    fail "the postinst does not run systemd-sysusers slope.conf exactly once"
grep -q 'systemd-tmpfiles --create slope.conf' "$postinst" || fail "the postinst does not run systemd-tmpfiles"
grep -q 'udevadm control --reload-rules' "$postinst" || fail "the postinst does not reload the udev rules"
# cargo-deb's "don't enable" fragment re-enables a unit only when it was
# enabled before (`debian-installed`); the "enable" fragment has no such guard.
if [ "$(grep -c 'deb-systemd-helper unmask' "$postinst")" != "$(grep -c 'deb-systemd-helper debian-installed' "$postinst")" ]; then
    fail "the postinst enables units on install"
fi
if grep -q 'deb-systemd-invoke start' "$postinst"; then
    fail "the postinst starts units on install"
fi

# systemd-analyze verify checks each unit's settings and that its ExecStart=
# binary is there and executable. With --root=DIR it reads units and binaries
# under DIR, so verify against the unpacked package. The units' default
# dependencies (sysinit.target, ...) must be found there too: copy this
# machine's system units beside ours (systemd 252, Debian 12; verifying the
# unit files by path without --root checks ExecStart= on the host instead).
# Unknown keys are only warnings, so any output is a failure.
root="$work/root"
dpkg-deb -x "$deb" "$root"
cp -rn /usr/lib/systemd/system/. "$root/usr/lib/systemd/system/"
if ! output=$(systemd-analyze verify --root="$root" "${units[@]}" 2>&1) || [ -n "$output" ]; then
    fail "systemd-analyze verify: ${output:-failed}"
fi

# A daemon whose config file is wrong exits 78 (EX_CONFIG); its unit must not
# restart it forever.
for unit in "${units[@]}"; do
    case "$unit" in
    *.service)
        grep -qx 'RestartPreventExitStatus=78 2' "$root/usr/lib/systemd/system/$unit" ||
            fail "$unit lacks RestartPreventExitStatus=78 2 (a config or usage error would restart forever)"
        ;;
    esac
    # The capture is ready only with its first cloud: a unit ordered after it
    # would not start while no Kinect is plugged in.
    if grep -Eq '^After=.*slope-capture' "$root/usr/lib/systemd/system/$unit"; then
        fail "$unit is ordered After=slope-capture.service: it would wait for the Kinect"
    fi
done

# The sysusers and tmpfiles entries parse and do what the units need, in the
# unpacked root (its /etc/passwd, /etc/group and /tmp): the user and group slope,
# /tmp/iceoryx2.
output=$(systemd-sysusers --root="$root" "$root/usr/lib/sysusers.d/slope.conf" 2>&1) ||
    fail "systemd-sysusers refuses /usr/lib/sysusers.d/slope.conf: $output"
grep -q '^slope:' "$root/etc/passwd" || fail "sysusers.d creates no user slope"
grep -q '^slope:' "$root/etc/group" || fail "sysusers.d creates no group slope"
systemd-tmpfiles --root="$root" --create "$root/usr/lib/tmpfiles.d/slope.conf" ||
    fail "systemd-tmpfiles refuses /usr/lib/tmpfiles.d/slope.conf"
[ -d "$root/tmp/iceoryx2" ] || fail "tmpfiles.d creates no /tmp/iceoryx2"
rules="$root/usr/lib/udev/rules.d/60-slope-kinect2.rules"
for product in 02c4 02d8 02d9; do
    grep -q "ATTR{idVendor}==\"045e\", ATTR{idProduct}==\"$product\", GROUP=\"slope\", MODE=\"0660\"" "$rules" ||
        fail "the udev rule does not give 045e:$product to the group slope"
done

echo "check-deb: $deb: $package holds ${#programs[@]} programs and ${#units[@]} units; conffiles, user, tmpfiles, udev rule, docs in place; units verified"
