//! slope-replay -> slope-estimator -> slope-bridge -> Zenoh -> a subscriber
//! in this test, on the loopback only (`tcp/127.0.0.1:<free port>`, no
//! multicast scouting): every estimate arrives, in order, as versioned
//! JSON, and so do the health reports. The bridge listens only where it is
//! told, and in client mode waits for its router until stopped.
#![cfg(feature = "zenoh")]

use std::collections::HashSet;
use std::net::TcpListener;
use std::time::{Duration, Instant};

use serde_json::Value;
use slope_integration_tests::{deadline, replay_frames, unique_prefix, Proc};
use zenoh::Wait;

/// A TCP port nobody listens on now.
fn free_port() -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind a free port");
    listener.local_addr().expect("local address").port()
}

/// The TCP ports process `pid` listens on (what `ss -ltnp` shows for it):
/// its socket inodes matched against the LISTEN rows of /proc/net/tcp{,6}.
fn listening_ports(pid: u32) -> Vec<u16> {
    let inodes: HashSet<String> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .expect("the process's file descriptors")
        .filter_map(|fd| std::fs::read_link(fd.ok()?.path()).ok())
        .filter_map(|target| {
            let target = target.to_str()?;
            Some(
                target
                    .strip_prefix("socket:[")?
                    .strip_suffix(']')?
                    .to_string(),
            )
        })
        .collect();
    let mut ports = Vec::new();
    for table in ["/proc/net/tcp", "/proc/net/tcp6"] {
        let text = std::fs::read_to_string(table).unwrap_or_default();
        for row in text.lines().skip(1) {
            let fields: Vec<&str> = row.split_whitespace().collect();
            // local_address rem_address st ... inode (the 10th field).
            let (Some(local), Some(state), Some(inode)) =
                (fields.get(1), fields.get(3), fields.get(9))
            else {
                continue;
            };
            if *state == "0A" && inodes.contains(*inode) {
                let port = local.rsplit(':').next().expect("ADDR:PORT");
                ports.push(u16::from_str_radix(port, 16).expect("a hexadecimal port"));
            }
        }
    }
    ports
}

/// The next JSON sample of `subscriber`, or `None` at `until`.
fn next_json(
    subscriber: &zenoh::pubsub::Subscriber<
        zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>,
    >,
    until: Instant,
) -> Option<Value> {
    let left = until.saturating_duration_since(Instant::now());
    let sample = subscriber.recv_timeout(left).ok().flatten()?;
    let text = sample.payload().try_to_string().expect("UTF-8 payload");
    Some(serde_json::from_str(&text).unwrap_or_else(|e| panic!("{text:?}: {e}")))
}

#[test]
fn every_estimate_crosses_the_bridge_as_versioned_json() {
    let prefix = unique_prefix("bridge");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let _estimator = Proc::spawn(
        "slope-estimator",
        ["--service-prefix", &prefix, "--health-interval-s", "0.2"],
    )
    .assert_ready("estimator ready");
    let mut bridge = Proc::spawn(
        "slope-bridge",
        ["--service-prefix", &prefix, "--listen", &endpoint],
    )
    .assert_ready("bridge ready");
    let port: u16 = endpoint
        .rsplit(':')
        .next()
        .and_then(|p| p.parse().ok())
        .expect("port");
    assert_eq!(listening_ports(bridge.pid()), [port], "only --listen");

    let mut config = zenoh::Config::default();
    for (key, value) in [
        ("mode", "\"peer\"".to_string()),
        ("scouting/multicast/enabled", "false".to_string()),
        ("connect/endpoints", format!("[\"{endpoint}\"]")),
    ] {
        config.insert_json5(key, &value).expect("zenoh setting");
    }
    let session = zenoh::open(config).wait().expect("zenoh session");
    let estimates = session
        .declare_subscriber(format!("{prefix}/estimate"))
        .wait()
        .expect("estimate subscriber");
    let health = session
        .declare_subscriber(format!("{prefix}/health"))
        .wait()
        .expect("health subscriber");
    let surfaces = session
        .declare_subscriber(format!("{prefix}/surfaces"))
        .wait()
        .expect("surfaces subscriber");

    // The path is up once a health report (every 0.2 s) came across.
    let report = next_json(&health, deadline(30.0))
        .unwrap_or_else(|| panic!("no health report over Zenoh\n{}", bridge.diagnostics()));
    assert_eq!(report["schema"], "slope.health.json/1", "{report}");
    assert_eq!(report["component"], "estimator", "{report}");

    let frames = 8;
    let mut replay = replay_frames(&prefix, "ramp16", 5.0, frames, 1);
    // Every estimate the estimator published, in order, up to the last
    // frame (the newest frame is never superseded; a loaded machine may
    // make the estimator skip one before it, which it then counts).
    let until = deadline(60.0);
    let mut seen = Vec::new();
    let mut dropped = 0;
    while seen.last() != Some(&(frames - 1)) {
        let Some(e) = next_json(&estimates, until) else {
            break;
        };
        assert_eq!(e["schema"], "slope.estimate.json/1", "{e}");
        assert_eq!(e["status"], "ok", "{e}");
        let slope = e["slope_deg"].as_f64().expect("slope_deg");
        assert!((slope - 16.0).abs() < 1.0, "{e}");
        dropped = e["dropped_frames"].as_u64().expect("dropped_frames");
        seen.push(e["frame"].as_u64().expect("frame"));
    }
    assert_eq!(seen.last(), Some(&(frames - 1)), "{}", bridge.diagnostics());
    assert!(seen.windows(2).all(|w| w[0] < w[1]), "{seen:?}");
    assert_eq!(seen.len() as u64 + dropped, frames, "{seen:?}");
    // Each estimate's surfaces follow it, with its frame and a ramp road.
    for &frame in &seen {
        let s = next_json(&surfaces, deadline(10.0))
            .unwrap_or_else(|| panic!("no surfaces of frame {frame}\n{}", bridge.diagnostics()));
        assert_eq!(s["schema"], "slope.surfaces.json/1", "{s}");
        assert_eq!(s["frame"].as_u64(), Some(frame), "{s}");
        let road = s["surfaces"]
            .as_array()
            .and_then(|all| all.iter().find(|x| x["road"] == true))
            .unwrap_or_else(|| panic!("a road in {s}"));
        assert_eq!(road["role"], "ramp", "{s}");
    }
    replay.assert_exits_zero_within(Duration::from_secs(30));
    bridge.signal(nix::sys::signal::Signal::SIGTERM);
    bridge.assert_exits_zero_within(Duration::from_secs(5));
}

/// Without --listen (nor a config file saying where) the bridge listens on
/// no port at all: Zenoh's peer default would be every interface.
#[test]
fn without_listen_the_bridge_listens_on_no_port() {
    let prefix = unique_prefix("bridge-nolisten");
    let nobody = format!("tcp/127.0.0.1:{}", free_port());
    let bridge = Proc::spawn(
        "slope-bridge",
        ["--service-prefix", &prefix, "--connect", &nobody],
    )
    .assert_ready("bridge ready");
    assert_eq!(listening_ports(bridge.pid()), Vec::<u16>::new());
}

/// `--mode client` with no router up: the bridge says it waits, is still
/// running 2 s later, and a SIGTERM while it waits ends it with status 0.
#[test]
fn a_client_bridge_waits_for_its_router_until_stopped() {
    let prefix = unique_prefix("bridge-client");
    let nobody = format!("tcp/127.0.0.1:{}", free_port());
    let mut bridge = Proc::spawn(
        "slope-bridge",
        [
            "--service-prefix",
            &prefix,
            "--mode",
            "client",
            "--connect",
            &nobody,
        ],
    );
    if bridge
        .wait_stderr("waiting for Zenoh", deadline(20.0))
        .is_none()
    {
        panic!("no note that it waits\n{}", bridge.diagnostics());
    }
    if let Some(status) = bridge.wait_exit(deadline(2.0)) {
        panic!(
            "exited with {status} while waiting\n{}",
            bridge.diagnostics()
        );
    }
    bridge.signal(nix::sys::signal::Signal::SIGTERM);
    bridge.assert_exits_zero_within(Duration::from_secs(5));
}
