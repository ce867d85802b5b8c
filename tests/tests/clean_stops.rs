//! Programs stopped with SIGINT or SIGTERM end with status 0, whether they
//! were waiting for data or streaming it (a signal that interrupts an
//! iceoryx2 wait is a stop request, not an error).

use std::time::Duration;

use nix::sys::signal::Signal;
use slope_integration_tests::{deadline, recording, unique_prefix, Proc};

/// slope-record waiting for clouds that never come.
#[test]
fn a_waiting_recorder_stops_cleanly() {
    for signal in [Signal::SIGINT, Signal::SIGTERM] {
        let prefix = unique_prefix(&format!("record-wait-{signal}"));
        let out = tempfile::tempdir().expect("temp dir");
        let out_dir = out.path().join("scene");
        let mut record = Proc::spawn(
            "slope-record",
            [
                out_dir.to_str().expect("utf-8 path"),
                "--service-prefix",
                &prefix,
            ],
        );
        assert!(
            record
                .wait_stderr("recording the cloud topic", deadline(20.0))
                .is_some(),
            "{}",
            record.diagnostics()
        );
        record.signal(signal);
        record.assert_exits_zero_within(Duration::from_secs(2));
    }
}

/// slope-demo while estimates stream: it ends with status 0 and its summary.
#[test]
fn a_streaming_demo_stops_cleanly_with_its_summary() {
    let dir = recording("ramp16-clean");
    let prefix = unique_prefix("demo-stream");
    let mut demo = Proc::spawn(
        "slope-demo",
        [
            "--recording",
            dir.to_str().expect("utf-8 path"),
            "--rate",
            "2",
            "--service-prefix",
            &prefix,
        ],
    );
    let first = demo.stdout_line(deadline(30.0));
    let mut frame = first.clone();
    while let Some(line) = &frame {
        if line.starts_with("frame") {
            break;
        }
        frame = demo.stdout_line(deadline(30.0));
    }
    assert!(frame.is_some(), "no estimate line\n{}", demo.diagnostics());
    demo.signal(Signal::SIGINT);
    demo.assert_exits_zero_within(Duration::from_secs(3));
    let mut rest = Vec::new();
    while let Some(line) = demo.stdout_line(deadline(1.0)) {
        rest.push(line);
    }
    assert!(
        rest.iter().any(|l| l.starts_with("summary:")),
        "no summary after the stop: {rest:?}"
    );
}

/// slope-demo stopped while it waits for its first estimate: status 0 and
/// a summary of nothing. The signal comes as the demo announces the chain,
/// before its children have started; the summary's "0 estimates" shows it
/// was still waiting (a first estimate needs both children started and a
/// frame through the estimator).
#[test]
fn a_waiting_demo_stops_cleanly_with_an_empty_summary() {
    let dir = recording("ramp16-clean");
    for signal in [Signal::SIGINT, Signal::SIGTERM] {
        let prefix = unique_prefix(&format!("demo-wait-{signal}"));
        let mut demo = Proc::spawn(
            "slope-demo",
            [
                "--recording",
                dir.to_str().expect("utf-8 path"),
                "--service-prefix",
                &prefix,
            ],
        );
        let header = demo.stdout_line(deadline(20.0));
        assert!(
            header
                .as_deref()
                .is_some_and(|l| l.starts_with("slope-demo:")),
            "{header:?}\n{}",
            demo.diagnostics()
        );
        demo.signal(signal);
        demo.assert_exits_zero_within(Duration::from_secs(5));
        let mut rest = Vec::new();
        while let Some(line) = demo.stdout_line(deadline(1.0)) {
            rest.push(line);
        }
        let summary = rest
            .iter()
            .find(|l| l.starts_with("summary:"))
            .unwrap_or_else(|| panic!("no summary after the stop: {rest:?}"));
        assert!(summary.contains(" 0 estimates"), "{summary}");
    }
}
