//! A program waiting on a silent topic says so after a few seconds, naming
//! the service (with its prefix) and what should publish on it; the
//! estimator logs its throughput every 10 s all the same.

use nix::sys::signal::Signal;
use slope_integration_tests::{deadline, unique_prefix, Proc};

#[test]
fn silent_topics_are_named_in_the_log() {
    let prefix = unique_prefix("silence");
    for (program, note) in [
        (
            "slope-echo",
            format!("no estimate for 5 s on service {prefix}/estimate"),
        ),
        (
            "slope-estimator",
            format!("no cloud for 5 s on service {prefix}/cloud"),
        ),
    ] {
        let mut proc = Proc::spawn(program, ["--service-prefix", prefix.as_str()]);
        let line = proc.wait_stderr(&note, deadline(20.0));
        assert!(line.is_some(), "{program}: {}", proc.diagnostics());
        if program == "slope-estimator" {
            // Its throughput summary every 10 s, for the journal.
            let summary =
                proc.wait_stderr("in 0.0/s out 0.0/s, 0 in, 0 out, 0 dropped", deadline(20.0));
            assert!(summary.is_some(), "{}", proc.diagnostics());
        }
        proc.signal(Signal::SIGTERM);
        let status = proc.wait_exit(deadline(2.0));
        assert!(
            status.is_some_and(|s| s.success()),
            "{}",
            proc.diagnostics()
        );
    }
}
