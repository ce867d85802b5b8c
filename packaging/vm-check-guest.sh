#!/bin/bash
# The guest half of packaging/vm-check.sh: runs at each boot of the Debian 12
# VM (its unit vm-check.service), with the package, ramp16 and the capture
# unit in /mnt/host (9p), writes what it saw to /mnt/host/out/log and the
# number of failed checks to /mnt/host/out/fails-<boot>, then powers off.
# Boot 1 installs the package and checks the estimator unit; boot 2 checks
# that the enabled slope.target came up at boot, then removes the package.
# When /mnt/host holds slope-ros2_*.deb too: boot 1 then installs it and
# checks its unit (the estimator's clouds replayed to it through the
# estimator), and enables it; boot 2 checks slope.target started it, and
# removes it before the package slope.
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
ros2_deb=$(ls /mnt/host/slope-ros2_*.deb 2>/dev/null | head -1)
r2=slope-ros2
# The count of estimates slope-ros2 published, from its status line
# ("120 estimates, 120 surfaces, ... published; 0 dropped"); empty without one.
r2_count() { prop $r2 StatusText | sed -n 's/^\([0-9][0-9]*\) estimates,.*/\1/p'; }
# What the sandbox could do to slope-ros2, in this boot's journal: panics,
# EPERM/EACCES, systemd's kills, failures and watchdog timeouts of the unit,
# seccomp kills (audit type 1326).
r2_denials() {
    journalctl -b -u $r2 --no-pager -o short-monotonic |
        grep -E 'panicked|Operation not permitted|Permission denied|os error (1|13)\b|code: (1|13),|code=killed|code=dumped|status=31|Failed with result|Watchdog timeout|Main process exited, code=exited, status=[1-9]'
    journalctl -b -k --no-pager -o short-monotonic | grep -E 'type=1326|audit.*seccomp' | grep -F slope-ros2
}
# The ERROR lines slope-ros2 (and RustDDS, at -v) logged in the unit this
# boot, without times and GUIDs: one line per kind.
r2_error_kinds() {
    journalctl -b -u $r2 --no-pager -o cat | grep -E '^[0-9TZ:.-]+ +ERROR ' |
        sed -E 's/.* ERROR //; s/GUID \{.*\}/GUID {...}/' | sort -u
}
# r2_journal_checks BOOT: the checks above, once the unit stopped; its ERROR
# lines against those of slope-ros2 run outside the unit (boot 1, saved in
# $state/ros2-errors-outside): those the sandbox did not cause.
r2_journal_checks() {
    echo "$r2 journal: sandbox denials, kills, watchdog, seccomp:"
    local denials kinds extra
    denials=$(r2_denials)
    [ -z "$denials" ] && ok "no denial, kill or watchdog timeout in the journal of $r2" || {
        echo "$denials"
        bad "denials or kills in the journal of $r2"
    }
    journalctl -b -u $r2 --no-pager -o short-monotonic | grep -E "$r2\\[[0-9]+\\]: [0-9TZ:.-]+ +(ERROR|WARN) " | tail -8
    kinds=$(r2_error_kinds)
    echo "ERROR kinds in the unit: ${kinds:-none}"
    echo "ERROR kinds outside the unit (boot 1, the same start and SIGTERM): $(cat "$state/ros2-errors-outside" 2>/dev/null)"
    extra=$(comm -23 <(echo "$kinds") "$state/ros2-errors-outside" | grep .)
    [ -z "$extra" ] && ok "no ERROR in the unit that slope-ros2 does not log outside it too" ||
        bad "ERROR only in the unit: $extra"
    journalctl -b -u $r2 --no-pager -o short-monotonic >"$out/journal-ros2-boot$1.txt"
}
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
    systemctl is-active -q $r2 && echo "$r2 status while streaming: $(prop $r2 StatusText)"
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

    if [ -n "$ros2_deb" ]; then
        step "apt install ./slope-ros2_*.deb (slope installed, no network)"
        enabled_units() { systemctl list-unit-files --state=enabled --no-legend --no-pager | awk '{ print $1 }' | sort; }
        active_units() { systemctl list-units --state=active --no-legend --no-pager --plain | awk '{ print $1 }' | sort; }
        enabled_before=$(enabled_units)
        active_before=$(active_units)
        DEBIAN_FRONTEND=noninteractive apt-get install -y "$ros2_deb" 2>&1 | grep -E '^(Setting up|E:|W:)'
        dpkg-query -W -f '${Package} ${Version} ${Status}; Depends: ${Depends}\n' slope-ros2
        [ "$(dpkg-query -W -f '${Status}' slope-ros2 2>/dev/null)" = "install ok installed" ] && ok "slope-ros2 installed" ||
            bad "slope-ros2 not installed"
        new_enabled=$(comm -13 <(echo "$enabled_before") <(enabled_units))
        new_active=$(comm -13 <(echo "$active_before") <(active_units))
        [ -z "$new_enabled" ] && [ "$(systemctl is-enabled $r2)" = disabled ] && ok "nothing enabled on install ($r2 $(systemctl is-enabled $r2))" ||
            bad "enabled on install: $new_enabled ($r2 $(systemctl is-enabled $r2))"
        [ -z "$new_active" ] && ! systemctl is-active -q $r2 && ok "nothing started on install ($r2 $(systemctl is-active $r2))" ||
            bad "started on install: $new_active ($r2 $(systemctl is-active $r2))"

        step "systemd-analyze verify slope-ros2.service"
        if v=$(systemd-analyze verify /usr/lib/systemd/system/$r2.service 2>&1) && [ -z "$v" ]; then ok "verify: no output"; else bad "verify: $v"; fi

        # The loopback only (the VM has no NIC), as tools/ros2/README.md says:
        # in /etc/default/slope; -v: RustDDS's errors in the journal too.
        step "systemctl start slope-ros2 (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, SLOPE_ROS2_ARGS=-v in /etc/default/slope)"
        sed -i 's/^#\?ROS_AUTOMATIC_DISCOVERY_RANGE=.*/ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST/; s/^SLOPE_ROS2_ARGS=.*/SLOPE_ROS2_ARGS=-v/' /etc/default/slope
        grep -q '^ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST$' /etc/default/slope ||
            echo ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST >>/etc/default/slope
        grep -q '^SLOPE_ROS2_ARGS=-v$' /etc/default/slope || echo SLOPE_ROS2_ARGS=-v >>/etc/default/slope
        grep -E '^(ROS_|SLOPE_ROS2_ARGS)' /etc/default/slope
        # The estimator's TCG watchdog (it restarts it) before the node
        # subscribes; the node's own WatchdogSec=5 as shipped.
        slow_watchdog_on
        t0=$(date +%s%N)
        systemctl start $r2
        echo "systemctl start took $((($(date +%s%N) - t0) / 1000000)) ms"
        systemctl status $r2 --no-pager -n 0
        [ "$(systemctl is-active $r2)" = active ] && ok "$r2 active" || bad "$r2 $(systemctl is-active $r2)"
        start=$(prop $r2 ExecMainStartTimestampMonotonic)
        active=$(prop $r2 ActiveEnterTimestampMonotonic)
        echo "exec to active (READY=1): $(((active - start) / 1000)) ms"
        echo "Status: $(prop $r2 StatusText)"
        journalctl -b -u $r2 --no-pager -o short-monotonic | grep -E 'READY=1|Started|ros2 node ready' | head -3
        journalctl -b -u $r2 --no-pager | grep -q 'READY=1' && ok "active after READY=1" || bad "no READY=1"
        pid=$(prop $r2 MainPID)
        env=$(tr '\0' '\n' </proc/"$pid"/environ | grep -E '^ROS_')
        echo "its environment: $env; command line: $(tr '\0' ' ' </proc/"$pid"/cmdline)"
        [ "$env" = ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ] && ok "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST in its environment" ||
            bad "its ROS_ environment: '$env'"
        sleep 3
        echo "Status 3 s later: $(prop $r2 StatusText)"
        uid=$(id -u slope)
        ports=$(awk -v uid="$uid" 'NR > 1 && $8 == uid { split($2, a, ":"); print a[2] }' /proc/net/udp |
            while read -r hex; do echo $((16#$hex)); done | sort -n | tr '\n' ' ')
        echo "UDP ports bound by user slope (RTPS: 7400, 7401, 7410 + 2p, 7411 + 2p): $ports"

        step "replay ramp16 -> the estimator unit -> the slope-ros2 unit (published over DDS)"
        r2_feed() {
            local restarts count
            restarts=$(prop $r2 NRestarts)
            count=$(r2_count)
            feed 6
            sleep 2
            echo "$r2 status after: $(prop $r2 StatusText), NRestarts $(prop $r2 NRestarts), MainPID $(prop $r2 MainPID)"
            [ "$(r2_count)" -gt "${count:-0}" ] 2>/dev/null && ok "$r2 published estimates (${count:-0} -> $(r2_count))" ||
                bad "$r2 published no estimates (status '$(prop $r2 StatusText)')"
            [ "$(prop $r2 NRestarts)" = "$restarts" ] && systemctl is-active -q $r2 && ok "$r2 not restarted while streaming (NRestarts $(prop $r2 NRestarts))" ||
                bad "$r2 restarted while streaming (NRestarts $restarts -> $(prop $r2 NRestarts), $(systemctl is-active $r2))"
        }
        r2_feed
        if journalctl -b -u $r2 --no-pager | grep -q 'Watchdog timeout' && [ "$(systemd-detect-virt)" = qemu ]; then
            # Its main loop starved under TCG: again with the estimator's
            # kind of drop-in, to see the sandbox apart from the watchdog.
            echo "(TCG: $r2's watchdog fired; again with WatchdogSec=60 in a runtime drop-in)"
            mkdir -p /run/systemd/system/$r2.service.d
            printf '[Service]\nWatchdogSec=60\n' >/run/systemd/system/$r2.service.d/tcg.conf
            systemctl daemon-reload && systemctl restart $r2
            r2_feed
        fi

        step "systemctl stop slope-ros2"
        since=$(date '+%Y-%m-%d %H:%M:%S')
        sleep 1
        t0=$(date +%s%N)
        systemctl stop $r2
        echo "stop took $((($(date +%s%N) - t0) / 1000000)) ms"
        journalctl -b -u $r2 --no-pager -o short-monotonic --since "$since" |
            grep -E 'STOPPING=1|ros2 node stopped|Main process exited|Deactivated|Stopped'
        [ "$(prop $r2 Result)" = success ] && [ "$(prop $r2 ExecMainStatus)" = 0 ] && ok "exit status 0, Result=success" ||
            bad "stop: Result=$(prop $r2 Result) status=$(prop $r2 ExecMainStatus) code=$(prop $r2 ExecMainCode)"
        journalctl -b -u $r2 --no-pager --since "$since" | grep -q 'STOPPING=1' && ok "STOPPING=1" || bad "no STOPPING=1"

        # The same program outside the unit (no sandbox), started and
        # stopped the same way: which of its ERROR lines are its own.
        step "slope-ros2 -v outside the unit (as slope, no sandbox), SIGTERM after 20 s"
        runuser -u slope -- env ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST timeout --preserve-status -s TERM 20 slope-ros2 -v 2>/tmp/ros2-outside.log
        echo "exit $?"
        grep -E ' (ERROR|WARN) ' /tmp/ros2-outside.log | tail -8
        grep -E ' ERROR ' /tmp/ros2-outside.log | sed -E 's/.* ERROR //; s/GUID \{.*\}/GUID {...}/' | sort -u >"$state/ros2-errors-outside"
        r2_journal_checks 1
        rm -rf /run/systemd/system/$r2.service.d
        slow_watchdog_off

        step "systemd-analyze security slope-ros2"
        systemd-analyze security $r2 --no-pager >"$out/security-ros2.txt" 2>&1
        grep -F '✗' "$out/security-ros2.txt" | sort -t' ' -k2 | tail -40
        tail -1 "$out/security-ros2.txt"

        step "systemctl enable slope-ros2 (WantedBy=slope.target)"
        systemctl enable $r2 2>&1
        [ "$(systemctl is-enabled $r2)" = enabled ] && ok "$r2 enabled" || bad "$r2 $(systemctl is-enabled $r2)"
    fi
    touch "$state/boot1"
else
    step "after a reboot: slope.target enabled"
    [ "$(systemctl is-active $unit)" = active ] && ok "estimator started at boot" || bad "estimator $(systemctl is-active $unit) after boot"
    systemctl status $unit --no-pager -n 0 | head -8
    [ "$(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)" = "slope:slope 750" ] && ok "/tmp/iceoryx2 made at boot" ||
        bad "/tmp/iceoryx2 after boot: $(stat -c '%U:%G %a' /tmp/iceoryx2 2>&1)"
    ros2=
    if [ -n "$ros2_deb" ] && [ -e /usr/lib/systemd/system/$r2.service ]; then
        ros2=yes
        step "after a reboot: slope-ros2 enabled (WantedBy=slope.target)"
        [ "$(systemctl is-active $r2)" = active ] && ok "$r2 started at boot" || bad "$r2 $(systemctl is-active $r2) after boot"
        systemctl status $r2 --no-pager -n 0 | head -8
        systemctl list-dependencies slope.target --no-pager --plain | grep -qw $r2.service &&
            ok "$r2 wanted by slope.target ($(prop $r2 WantedBy))" || bad "$r2 not in slope.target's dependencies"
        journalctl -b -u $r2 --no-pager -o short-monotonic | grep -E 'Started|ros2 node ready' | head -2
        echo "Status: $(prop $r2 StatusText), NRestarts $(prop $r2 NRestarts)"
        r2_restarts=$(prop $r2 NRestarts)
        r2_before=$(r2_count)
    fi
    slow_watchdog_on
    feed 3
    slow_watchdog_off
    if [ -n "$ros2" ]; then
        # The estimator was restarted (its TCG drop-in, on and off) while
        # the node ran: it goes on reading the new estimator.
        sleep 2
        echo "$r2 status after: $(prop $r2 StatusText), NRestarts $(prop $r2 NRestarts)"
        [ "$(r2_count)" -gt "${r2_before:-0}" ] 2>/dev/null && ok "$r2 (started at boot) published estimates (${r2_before:-0} -> $(r2_count))" ||
            bad "$r2 (started at boot) published no estimates ('$(prop $r2 StatusText)')"
        [ "$(prop $r2 NRestarts)" = "$r2_restarts" ] && ok "$r2 not restarted (NRestarts $r2_restarts)" ||
            bad "$r2 restarted (NRestarts $r2_restarts -> $(prop $r2 NRestarts))"

        step "apt remove slope-ros2 (no reboot) stops its unit"
        DEBIAN_FRONTEND=noninteractive apt-get remove -y $r2 2>&1 | grep -E '^(Removing|E:|W:)'
        echo "$r2 $(systemctl is-active $r2), estimator $(systemctl is-active $unit)"
        ! systemctl is-active -q $r2 && ! pgrep -x $r2 && ok "$r2 stopped by apt remove" ||
            bad "$r2 still running after apt remove"
        echo "its stop: Result=$(prop $r2 Result), status $(prop $r2 ExecMainStatus)"
        r2_journal_checks 2
    fi

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
