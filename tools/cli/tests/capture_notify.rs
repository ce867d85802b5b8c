//! slope-capture's side of the systemd notify protocol, without a Kinect:
//! the same notifier and publishing loop that `slope-capture` runs, fed by
//! a fake camera that first "waits for a device" and then streams. The
//! test binds the datagram socket systemd would (`NOTIFY_SOCKET`), asks for
//! a watchdog (`WATCHDOG_USEC`) and reads what the capture tells it. (The
//! wiring of the real `Kinect2Source`'s wait hook needs a device.)
//!
//! One test in this file: it sets the process's environment.

use std::os::unix::net::UnixDatagram;
use std::time::{Duration, Instant};

use slope_ipc_types::{CloudSource, HealthComponent, Intrinsics, Mount, ServiceNames};
use slope_sensor::ipc::{create_node, CloudPublisher, HealthPublisher, HealthSubscriber};
use slope_sensor::publish::{Pacing, PublishOptions, StopFlag};
use slope_sensor::recording::DepthImage;
use slope_sensor::source::{FrameSource, SourceError, SourceFrame, SourceInfo};
use slope_tools::capture_notify::{
    publish_notifying, CaptureNotifier, SharedNotifier, SourceCounters,
};
use slope_tools::health::HealthReporter;

/// Waits `waits` slices "for a device", then gives `frames` frames, one
/// every `period`, calling the wait hook as `Kinect2Source` does (every
/// slice and every frame).
struct FakeCamera {
    info: SourceInfo,
    notifier: SharedNotifier,
    waits: u32,
    frames: u64,
    period: Duration,
    counters: SourceCounters,
}

impl FrameSource for FakeCamera {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    fn next_frame(&mut self, frame: &mut SourceFrame) -> Result<bool, SourceError> {
        while self.waits > 0 {
            self.waits -= 1;
            self.counters.failed_opens += 1;
            self.notifier.borrow_mut().on_wait(self.counters);
            std::thread::sleep(Duration::from_millis(60));
        }
        self.notifier.borrow_mut().on_wait(self.counters);
        if frame.index + 1 >= self.frames {
            return Ok(false);
        }
        std::thread::sleep(self.period);
        frame.index = if frame.depth.data.is_empty() {
            0
        } else {
            frame.index + 1
        };
        frame.depth = DepthImage {
            width: 4,
            height: 2,
            data: vec![1000; 8],
        };
        frame.color = None;
        Ok(true)
    }
}

/// Reads the socket on a thread from now on (as systemd does: a sender
/// blocks once the socket's queue is full), until `until`.
fn collect(socket: UnixDatagram, until: Instant) -> std::thread::JoinHandle<Vec<String>> {
    std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut buf = [0u8; 4096];
        while Instant::now() < until {
            if let Ok(n) = socket.recv(&mut buf) {
                let message = String::from_utf8_lossy(&buf[..n]).trim_end().to_string();
                let last = message == "STOPPING=1";
                seen.push(message);
                if last {
                    break;
                }
            }
        }
        seen
    })
}

#[test]
fn the_capture_is_ready_after_its_first_cloud_and_reports_while_waiting_and_streaming() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("notify.sock");
    let socket = UnixDatagram::bind(&path).expect("bind the notify socket");
    socket
        .set_read_timeout(Some(Duration::from_millis(100)))
        .expect("timeout");
    let reader = collect(socket, Instant::now() + Duration::from_secs(30));
    // The only test in this binary: nothing else reads the environment.
    std::env::set_var("NOTIFY_SOCKET", &path);
    std::env::set_var("WATCHDOG_USEC", "100000");
    std::env::remove_var("WATCHDOG_PID");

    let notifier = CaptureNotifier::from_env();
    let info = SourceInfo {
        width: 4,
        height: 2,
        intrinsics: Intrinsics {
            fx: 2.0,
            fy: 2.0,
            cx: 1.5,
            cy: 0.5,
        },
        unit_m: 0.001,
        mount: Mount::UNKNOWN,
        source: CloudSource::Camera,
        has_color: false,
        sensor: "fake-camera".into(),
    };
    let mut camera = FakeCamera {
        info: info.clone(),
        notifier: SharedNotifier::clone(&notifier),
        waits: 4,
        frames: 40,
        period: Duration::from_millis(30),
        counters: SourceCounters::default(),
    };
    let names = ServiceNames::new(format!("slope-test-capture-notify-{}", std::process::id()));
    let node = create_node("slope-test-capture-notify").expect("node");
    let publisher = CloudPublisher::create(&node, &names, &info, 8).expect("publisher");
    let health = HealthSubscriber::create(&node, &names).expect("health subscriber");
    let reporter = HealthReporter::new(
        HealthComponent::Capture,
        Some(HealthPublisher::create(&node, &names).expect("health publisher")),
        0.2,
    );
    notifier.borrow_mut().attach_health(reporter);
    let options = PublishOptions {
        pacing: Pacing::Source,
        ..PublishOptions::default()
    };
    let stats = publish_notifying(
        &mut camera,
        &publisher,
        &options,
        &StopFlag::new(),
        &notifier,
    )
    .expect("streams");
    notifier.borrow().stopping();
    assert_eq!(stats.published, 40);
    // Health reports every 0.2 s while streaming (about 1.2 s): the last
    // one counts the clouds published by then, at about the camera's rate.
    let mut reports = Vec::new();
    while let Some(report) = health.receive().expect("receive") {
        reports.push(report);
    }
    assert!(reports.len() >= 3, "{} reports", reports.len());
    assert!(reports
        .iter()
        .all(|r| r.component() == Some(HealthComponent::Capture)));
    let last = reports.last().expect("a report");
    assert!(last.frames_out >= 30 && last.frames_out <= 40, "{last:?}");
    assert_eq!(last.frames_in, last.frames_out, "{last:?}");
    let busiest = reports.iter().map(|r| r.rate_out_hz).fold(0.0, f64::max);
    assert!(busiest > 10.0 && busiest < 40.0, "{busiest}");

    let seen = reader.join().expect("reader");
    let ready = seen
        .iter()
        .position(|m| m.lines().any(|l| l == "READY=1"))
        .unwrap_or_else(|| panic!("no READY=1: {seen:?}"));
    // Before it: waiting, with more start-up time, and the watchdog.
    let before = &seen[..ready];
    assert!(
        before
            .iter()
            .any(|m| m.contains("STATUS=waiting for a Kinect v2")
                && m.contains("EXTEND_TIMEOUT_USEC=")),
        "{seen:?}"
    );
    assert!(before.iter().any(|m| m == "WATCHDOG=1"), "{seen:?}");
    // READY=1 comes with the first published cloud, not before.
    assert!(
        seen[ready].contains("STATUS=streaming:") && seen[ready].contains(" 1 frames"),
        "{}",
        seen[ready]
    );
    let after = &seen[ready + 1..];
    assert!(after.iter().any(|m| m == "WATCHDOG=1"), "{seen:?}");
    let status = after
        .iter()
        .find(|m| m.starts_with("STATUS=streaming:") && !m.contains(" - fps"))
        .unwrap_or_else(|| panic!("no streaming status with a rate: {seen:?}"));
    assert!(
        status.contains("fps")
            && status.contains("dropped")
            && status.contains("reconnects")
            && !status.contains("EXTEND_TIMEOUT_USEC"),
        "{status}"
    );
    assert_eq!(
        seen.last().map(String::as_str),
        Some("STOPPING=1"),
        "{seen:?}"
    );
}
