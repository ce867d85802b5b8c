#!/usr/bin/env bash
# A manual check, not run by CI (it takes 10-20 minutes, more with
# slope-ros2): the package under a real systemd. Boots a Debian 12 VM twice
# with the package and tests/recordings/ramp16 shared in;
# packaging/vm-check-guest.sh runs at each boot and checks, as systemd sees
# them: the user and /tmp/iceoryx2, the units' verify, READY=1, the status
# line, estimates near 16° from slope-replay through the unit to slope-echo
# outside it, the watchdog restart, the restart on upgrade, stop with status 0
# and STOPPING=1, the security score, start at boot once enabled, and apt
# remove stopping the units. With the package slope-ros2 as well (the second
# argument), at the first boot after those: its install (nothing enabled or
# started), its unit's verify, READY=1 and the status line with
# ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, estimates from slope-replay through
# the estimator unit published by it over DDS with no restart (its sandbox and
# RustDDS), its journal, stop with status 0, its security score; at the
# second, its start at boot by slope.target once enabled, and apt remove
# stopping it.
#
#   sudo packaging/vm-check.sh target/debian/slope_0.1.0-1_amd64.deb \
#       [target/debian/slope-ros2_0.1.0-1_amd64.deb]
#
# Needs root and Debian's qemu-system-x86, debootstrap and e2fsprogs (installed
# when missing); downloads nothing but Debian packages (the guest's, once, by
# debootstrap). The guest image is built once and kept in $VM_DIR
# (default /tmp/slope-vm); each run boots a fresh copy of it.
#   VM_ACCEL=kvm|tcg   default kvm when /dev/kvm works with kvm_intel or kvm_amd
#   QEMU=...           the qemu-system-x86_64 to run; QEMU_ARGS extra arguments
#   MIRROR=...         the Debian mirror for debootstrap
# Prints the guest's log; exits non-zero when a check failed or the VM did not finish.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -lt 1 ] || [ $# -gt 2 ] || [ ! -f "$1" ] || { [ $# -eq 2 ] && [ ! -f "$2" ]; }; then
    echo "usage: $0 PACKAGE.deb [SLOPE-ROS2-PACKAGE.deb]" >&2
    exit 2
fi
deb=$(realpath "$1")
ros2_deb=
[ $# -lt 2 ] || ros2_deb=$(realpath "$2")
vm=${VM_DIR:-/tmp/slope-vm}
qemu=${QEMU:-qemu-system-x86_64}
mirror=${MIRROR:-http://deb.debian.org/debian}
if [ -z "${VM_ACCEL:-}" ]; then
    VM_ACCEL=tcg
    if [ -w /dev/kvm ] && { [ -d /sys/module/kvm_intel ] || [ -d /sys/module/kvm_amd ]; }; then VM_ACCEL=kvm; fi
fi
[ "$(id -u)" -eq 0 ] || {
    echo "vm-check: run as root (debootstrap, the image's owners)" >&2
    exit 2
}
need=()
command -v "$qemu" >/dev/null || need+=(qemu-system-x86)
command -v debootstrap >/dev/null || need+=(debootstrap)
command -v mkfs.ext4 >/dev/null || need+=(e2fsprogs)
if [ ${#need[@]} -gt 0 ]; then
    apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${need[@]}"
fi
mkdir -p "$vm"

# The guest: Debian 12 with systemd as PID 1, root logged in on the serial
# console, /mnt/host shared from the host (9p), and a unit that runs
# /mnt/host/guest.sh once the boot is done.
if [ ! -f "$vm/base.img" ]; then
    root="$vm/root"
    if [ ! -x "$root/bin/systemctl" ]; then
        rm -rf "$root"
        debootstrap --variant=minbase \
            --include=systemd-sysv,udev,dbus,linux-image-amd64,initramfs-tools,procps,kmod \
            bookworm "$root" "$mirror"
    fi
    echo slope-vm >"$root/etc/hostname"
    printf '/dev/vda / ext4 rw 0 1\nhost /mnt/host 9p trans=virtio,version=9p2000.L,msize=262144,nofail 0 0\n' \
        >"$root/etc/fstab"
    mkdir -p "$root/mnt/host" "$root/etc/systemd/system/serial-getty@ttyS0.service.d"
    chroot "$root" passwd -d root
    printf '[Service]\nExecStart=\nExecStart=-/sbin/agetty --autologin root --noclear %%I 115200 $TERM\n' \
        >"$root/etc/systemd/system/serial-getty@ttyS0.service.d/autologin.conf"
    cat >"$root/etc/systemd/system/vm-check.service" <<'EOF'
[Unit]
Description=slope vm-check: run /mnt/host/guest.sh
After=multi-user.target
RequiresMountsFor=/mnt/host
ConditionPathExists=/mnt/host/guest.sh
[Service]
Type=exec
ExecStart=/mnt/host/guest.sh
[Install]
WantedBy=multi-user.target
EOF
    chroot "$root" systemctl enable vm-check.service
    printf '9p\n9pnet_virtio\n' >>"$root/etc/modules"
    cp "$root"/boot/vmlinuz-* "$vm/vmlinuz"
    cp "$root"/boot/initrd.img-* "$vm/initrd.img"
    mkfs.ext4 -q -F -L root -d "$root" "$vm/base.img" 3G
fi

share="$vm/share"
rm -rf "$share"
mkdir -p "$share/out"
cp "$deb" "$share/"
[ -z "$ros2_deb" ] || cp "$ros2_deb" "$share/"
cp -r tests/recordings/ramp16 "$share/ramp16"
cp systemd/slope-capture.service "$share/"
install -m 755 packaging/vm-check-guest.sh "$share/guest.sh"
cp --sparse=always "$vm/base.img" "$vm/run.img"

accel=(-accel kvm -cpu host)
[ "$VM_ACCEL" = kvm ] || accel=(-accel tcg,thread=multi -cpu max)
for boot in 1 2; do
    echo "vm-check: boot $boot ($VM_ACCEL)" >&2
    # shellcheck disable=SC2086 # QEMU_ARGS is a list of arguments
    timeout 2400 "$qemu" "${accel[@]}" -m 2048 -smp 2 -nographic -vga none -no-reboot \
        -kernel "$vm/vmlinuz" -initrd "$vm/initrd.img" -append "root=/dev/vda rw console=ttyS0 quiet" \
        -drive "file=$vm/run.img,if=virtio,format=raw" \
        -virtfs "local,path=$share,mount_tag=host,security_model=none,id=host" \
        -nic none ${QEMU_ARGS:-} </dev/null >"$vm/console-$boot.log" 2>&1 || true
    [ -f "$share/out/fails-$boot" ] || {
        cat "$share/out/log" 2>/dev/null
        echo "vm-check: boot $boot did not finish (console: $vm/console-$boot.log)" >&2
        exit 1
    }
done
cat "$share/out/log"
failed=$(($(cat "$share/out/fails-1") + $(cat "$share/out/fails-2")))
echo "vm-check: $failed failed (log and journals in $share/out)"
[ "$failed" -eq 0 ]
