#!/bin/bash
# The guest half of packaging/vm-check.sh: runs at each boot of the Debian 12
# VM (its unit vm-check.service), with the package, ramp16 and the capture
# unit in /mnt/host (9p), writes what it saw to /mnt/host/out/log and the
# number of failed checks to /mnt/host/out/fails-<boot>, then powers off.
# Boot 1 installs the package and checks the estimator unit; boot 2 checks
# that the enabled slope.target came up at boot, then removes the package.
set -u
out=/mnt/host/out
mkdir -p "$out"
state=/var/lib/slope-vm-check
mkdir -p "$state"
if [ -e "$state/boot1" ]; then boot=2; else boot=1; fi
exec > >(tee -a "$out/log" >/dev/ttyS0) 2>&1
fails=0
ok() { echo "PASS: $*"; }
bad() {
    echo "FAIL: $*"
    fails=$((fails + 1))
}
step() { echo && echo "== [boot $boot] $*"; }
prop() { systemctl show -p "$2" --value "$1"; }
unit=slope-estimator
deb=$(ls /mnt/host/slope_*.deb | head -1)
# Under TCG (no KVM: systemd-detect-virt says "qemu") a frame takes ~3 s, longer
# than half of WatchdogSec=5 (the ping interval): streaming would trip the
# watchdog. A runtime drop-in gives it 60 s while clouds flow there.
slow_watchdog_on() {
    if [ "$(systemd-detect-virt)" = qemu ]; then
        mkdir -p /run/systemd/system/$unit.service.d
        printf '[Service]\nWatchdogSec=60\n' >/run/systemd/system/$unit.service.d/tcg.conf
        systemctl daemon-reload && systemctl restart $unit
        echo "(TCG: WatchdogSec=60 while streaming)"
    fi
}
slow_watchdog_off() {
    if [ -e /run/systemd/system/$unit.service.d/tcg.conf ]; then
        rm -r /run/systemd/system/$unit.service.d
        systemctl daemon-reload && systemctl restart $unit
    fi
}
# feed COUNT: slope-replay (as slope, the prefix the units use: service_prefix
# in /etc/slope/slope.toml, else "slope") until slope-echo (as slope, outside
# the unit) has COUNT estimates; prints them.
feed() {
    local count=$1 prefix
    prefix=$(sed -n 's/^[[:space:]]*service_prefix[[:space:]]*=[[:space:]]*"\([^"]*\)".*/\1/p' \
        /etc/slope/slope.toml | head -n 1)
    prefix=${prefix:-slope}
    local restarts
    restarts=$(prop $unit NRestarts)
    runuser -u slope -- slope-echo --service-prefix "$prefix" --json --count "$count" --timeout-s 120 \
        >/tmp/echo.json 2>/tmp/echo.err &
    local echo_pid=$!
    sleep 1
    runuser -u slope -- env SLOPE_SERVICE_PREFIX="$prefix" slope-replay /mnt/host/ramp16 --rate 2 --loop \
        --wait-subscribers 1 --wait-timeout-s 30 >/tmp/replay.log 2>&1 &
    local replay_pid=$!
    sleep 8
    echo "Status while streaming: $(prop $unit StatusText)"
    wait $echo_pid
    local rc=$?
    echo "Status after: $(prop $unit StatusText)"
    kill -INT $(pgrep -P $replay_pid) 2>/dev/null
    wait $replay_pid
    local slopes median n
    slopes=$(grep -o '"slope_deg":[-0-9.e]*' /tmp/echo.json | cut -d: -f2 | sort -g)
    n=$(grep -c . <<<"$slopes")
    median=$(awk '{ a[NR] = $1 } END { if (NR) printf "%.2f", a[int((NR + 1) / 2)] }' <<<"$slopes")
    echo "slope-echo exit $rc, $n estimates, slopes $(tr '\n' ' ' <<<"$slopes")"
    if [ "$rc" = 0 ] && awk -v m="$median" 'BEGIN { exit !(m > 15 && m < 17) }'; then
        ok "$n estimates from the unit, median ${median}°"
    else
        bad "estimates: exit $rc, $n, median '$median'"
        tail -3 /tmp/echo.err /tmp/replay.log
    fi
    [ "$(prop $unit NRestarts)" = "$restarts" ] && ok "no restart while streaming" ||
        bad "restarted while streaming ($restarts -> $(prop $unit NRestarts))"
}

if [ $boot = 1 ]; then
    step "guest"
    uname -r
    systemctl --version | head -1
    echo "virtualisation: $(systemd-detect-virt)"

    step "apt install ./slope_*.deb"
    DEBIAN_FRONTEND=noninteractive apt-get install -y "$deb" 2>&1 | grep -E '^(Setting up|E:|W:)'
    getent passwd slope && ok "user slope" || bad "no user slope"
    getent group slope && ok "group slope" || bad "no group slope"
    [ "$(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)" = "slope:slope 750" ] && ok "/tmp/iceoryx2 slope:slope 750" ||
        bad "/tmp/iceoryx2: $(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)"
    [ "$(systemctl is-enabled slope.target)" = disabled ] && ok "nothing enabled on install" ||
        bad "slope.target $(systemctl is-enabled slope.target) on install"
    systemctl is-active -q $unit && bad "started on install" || ok "nothing started on install"

    step "systemd-analyze verify"
    if v=$(systemd-analyze verify /usr/lib/systemd/system/slope-estimator.service \
        /usr/lib/systemd/system/slope.target 2>&1) && [ -z "$v" ]; then ok "verify: no output"; else bad "verify: $v"; fi

    # Debug logging shows each notification (READY=1, STATUS=, WATCHDOG=1, STOPPING=1).
    systemd-analyze log-level debug
    step "systemctl enable --now slope.target"
    systemctl enable --now slope.target
    systemctl status $unit --no-pager -n 0
    [ "$(systemctl is-active $unit)" = active ] && ok "estimator active" || bad "estimator $(systemctl is-active $unit)"
    start=$(prop $unit ExecMainStartTimestampMonotonic)
    active=$(prop $unit ActiveEnterTimestampMonotonic)
    echo "exec to active (READY=1): $(((active - start) / 1000)) ms"
    journalctl -b -u $unit --no-pager -o short-monotonic | grep -E 'READY=1|Started' | head -2
    journalctl -b -u $unit --no-pager | grep -q 'READY=1' && ok "active after READY=1" || bad "no READY=1"
    systemctl list-dependencies slope.target --no-pager
    ls -l /tmp/iceoryx2

    step "watchdog: kill -STOP the main PID"
    pid=$(prop $unit MainPID)
    t0=$(date +%s%N)
    kill -STOP "$pid"
    new=$pid
    for _ in $(seq 1 60); do
        sleep 0.5
        p=$(prop $unit MainPID)
        if [ "$p" != "$pid" ] && [ "$p" != 0 ] && systemctl is-active -q $unit; then
            new=$p
            break
        fi
    done
    echo "SIGSTOP to active again: $((($(date +%s%N) - t0) / 1000000)) ms, MainPID $pid -> $new, NRestarts $(prop $unit NRestarts)"
    journalctl -b -u $unit --no-pager -o short-monotonic |
        grep -E 'Watchdog timeout|Killing process|Main process exited|Failed with result|Scheduled restart' | tail -5
    [ "$new" != "$pid" ] && ok "watchdog killed and restarted it" || bad "no restart after the watchdog"

    step "replay ramp16 -> the unit -> slope-echo outside it"
    slow_watchdog_on
    feed 6
    ls -l /dev/shm | head -5
    slow_watchdog_off

    step "apt install --reinstall (an upgrade) restarts the running unit"
    pid=$(prop $unit MainPID)
    DEBIAN_FRONTEND=noninteractive apt-get install -y --reinstall "$deb" 2>&1 | grep -E '^(Setting up|E:|W:)'
    p=$(prop $unit MainPID)
    [ "$p" != "$pid" ] && systemctl is-active -q $unit && ok "restarted: MainPID $pid -> $p" ||
        bad "after reinstall: MainPID $pid -> $p, $(systemctl is-active $unit)"

    step "systemctl stop"
    since=$(date '+%Y-%m-%d %H:%M:%S')
    sleep 1
    t0=$(date +%s%N)
    systemctl stop $unit
    echo "stop took $((($(date +%s%N) - t0) / 1000000)) ms"
    journalctl -b -u $unit --no-pager -o short-monotonic --since "$since" | grep -E 'STOPPING=1|Main process exited|Stopped'
    [ "$(prop $unit Result)" = success ] && [ "$(prop $unit ExecMainStatus)" = 0 ] && ok "exit status 0" ||
        bad "stop: Result=$(prop $unit Result) status=$(prop $unit ExecMainStatus)"
    journalctl -b -u $unit --no-pager --since "$since" | grep -q 'STOPPING=1' && ok "STOPPING=1" || bad "no STOPPING=1"
    systemctl start slope.target

    step "systemd-analyze security"
    systemd-analyze security $unit --no-pager | grep -F '✗' | sort -t' ' -k2 | tail -40
    systemd-analyze security $unit --no-pager | tail -1
    # The capture unit (slope-kinect2 only) loaded without its program: its
    # score, and that it cannot start in this package.
    cp /mnt/host/slope-capture.service /run/systemd/system/
    systemctl daemon-reload
    systemd-analyze security slope-capture --no-pager | tail -1
    systemctl start slope-capture 2>&1 | tail -1
    systemctl status slope-capture --no-pager -n 3 | grep -E 'Active|Process|slope-capture\[' | head -4
    rm /run/systemd/system/slope-capture.service
    systemctl reset-failed slope-capture
    systemctl daemon-reload
    touch "$state/boot1"
else
    step "after a reboot: slope.target enabled"
    [ "$(systemctl is-active $unit)" = active ] && ok "estimator started at boot" || bad "estimator $(systemctl is-active $unit) after boot"
    systemctl status $unit --no-pager -n 0 | head -8
    [ "$(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)" = "slope:slope 750" ] && ok "/tmp/iceoryx2 made at boot" ||
        bad "/tmp/iceoryx2 after boot: $(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)"
    slow_watchdog_on
    feed 3
    slow_watchdog_off

    step "apt remove (no reboot) stops the units"
    DEBIAN_FRONTEND=noninteractive apt-get remove -y slope 2>&1 | grep -E '^(Removing|E:|W:)'
    echo "estimator $(systemctl is-active $unit), slope.target $(systemctl is-active slope.target)"
    ! systemctl is-active -q $unit && ! pgrep -x slope-estimator && ok "stopped by apt remove" ||
        bad "still running after apt remove"
fi

journalctl -b --no-pager -o short-monotonic >"$out/journal-boot$boot.txt"
echo "== [boot $boot] $fails failed"
echo "$fails" >"$out/fails-$boot"
sync
systemctl poweroff
