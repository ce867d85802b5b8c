//! The loop ([`run`]): every estimate, surfaces message and health report
//! of the service prefix published on ROS 2 until a stop.

use std::time::{Duration, Instant};

use ros2_client::dds::Publisher;
use serde::Serialize;
use slope_ipc_types::{ServiceNames, SlopeEstimate};
use slope_sensor::ipc::{create_node, EstimateSubscriber, HealthSubscriber, SurfacesSubscriber};
use slope_sensor::publish::StopFlag;
use slope_tools::cli::{node_name, wait_loop, SilenceNote};
use slope_tools::ros2_messages::SlopeEstimateMsg;
use slope_tools::service_manager::ServiceManager;

use super::args::Ros2Args;
use super::participant::Outputs;
use super::settings::Settings;
use crate::diagnostics::DiagnosticsRule;
use crate::markers::markers;
use crate::surfaces_msg::SurfacesMsg;
use crate::topics::{resolve, ESTIMATE_TOPIC};

/// What the node published (and dropped: a reliable reader that stopped
/// acknowledging, a send that failed).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Ros2Stats {
    pub estimates: u64,
    pub surfaces: u64,
    pub diagnostics: u64,
    pub markers: u64,
    pub dropped: u64,
}

impl Ros2Stats {
    /// The status line for systemd.
    fn status(&self) -> String {
        format!(
            "{} estimates, {} surfaces, {} markers, {} diagnostics published; {} dropped",
            self.estimates, self.surfaces, self.markers, self.diagnostics, self.dropped
        )
    }
}

/// Runs the node as a systemd notify daemon until `stop` is set:
/// `READY=1` once the DDS publishers and the iceoryx2 subscribers exist,
/// a status line a second, `STATUS=failed: <reason>` before a failed
/// exit, `STOPPING=1` on the way out.
pub fn run(args: &Ros2Args, stop: &StopFlag) -> anyhow::Result<Ros2Stats> {
    let mut manager = ServiceManager::from_env();
    let result = Settings::of(args, stop).and_then(|settings| match settings {
        Some(settings) => serve(&settings, stop, &mut manager),
        None => {
            tracing::info!("stopped before the config file was read");
            Ok(Ros2Stats::default())
        }
    });
    if let Err(err) = &result {
        manager.status(&format!("failed: {err:#}").replace('\n', " "));
    }
    manager.stopping();
    result
}

/// The iceoryx2 topics the node reads.
struct Inputs {
    estimates: EstimateSubscriber,
    surfaces: SurfacesSubscriber,
    health: HealthSubscriber,
}

/// The body of [`run`] once the settings are known: the DDS side, then
/// the iceoryx2 side, then the loop until a stop.
fn serve(
    settings: &Settings,
    stop: &StopFlag,
    manager: &mut ServiceManager,
) -> anyhow::Result<Ros2Stats> {
    if let Some(peers) = &settings.discovery.static_peers {
        tracing::warn!(peers = %peers, "ROS_STATIC_PEERS is not supported: ignored");
    }
    let outputs = Outputs::create(settings)?;
    let names = ServiceNames::new(settings.service_prefix.clone());
    let node = create_node(&node_name("slope-ros2"))?;
    let inputs = Inputs {
        estimates: EstimateSubscriber::create(&node, &names)?,
        surfaces: SurfacesSubscriber::create(&node, &names)?,
        health: HealthSubscriber::create(&node, &names)?,
    };
    let discovery = &settings.discovery;
    tracing::info!(
        estimates = %names.estimate(),
        topic = %resolve(&settings.namespace, ESTIMATE_TOPIC),
        domain_id = discovery.domain_id,
        discovery = discovery.range.name(),
        discovery_from = discovery.range_from.unwrap_or("default"),
        node = %settings.node_name,
        namespace = %settings.namespace,
        tf_static = outputs.tf_static.is_some(),
        "ros2 node ready"
    );
    manager.ready("waiting for estimates");
    let mut forwarder = Forwarder::new(settings, &outputs);
    let mut silence = SilenceNote::new("estimate", &names.estimate(), "slope-estimator");
    wait_loop(inputs.estimates.listener(), stop, || {
        silence.tick();
        manager.tick(|| forwarder.stats.status());
        if forwarder.wake(&inputs)? {
            silence.heard();
        }
        Ok(true)
    })?;
    let stats = forwarder.stats;
    tracing::info!(
        estimates = stats.estimates,
        surfaces = stats.surfaces,
        markers = stats.markers,
        diagnostics = stats.diagnostics,
        dropped = stats.dropped,
        "ros2 node stopped"
    );
    Ok(stats)
}

/// Maps and publishes what arrives, counting.
struct Forwarder<'a> {
    frame_id: &'a str,
    outputs: &'a Outputs,
    rule: DiagnosticsRule,
    /// The newest estimate: its frame's surfaces follow it (the markers'
    /// text).
    last_estimate: Option<SlopeEstimate>,
    stats: Ros2Stats,
    failures: FailureNote,
}

impl<'a> Forwarder<'a> {
    fn new(settings: &'a Settings, outputs: &'a Outputs) -> Self {
        Self {
            frame_id: &settings.frame_id,
            outputs,
            rule: DiagnosticsRule::new(&settings.node_name, &settings.service_prefix),
            last_estimate: None,
            stats: Ros2Stats::default(),
            failures: FailureNote::default(),
        }
    }

    /// Publishes everything waiting on `inputs`; true when an estimate
    /// came.
    fn wake(&mut self, inputs: &Inputs) -> anyhow::Result<bool> {
        let mut heard = false;
        while let Some(estimate) = inputs.estimates.receive()? {
            heard = true;
            self.last_estimate = Some(estimate);
            let message = SlopeEstimateMsg::new(&estimate, self.frame_id);
            let sent = send(
                &self.outputs.estimate,
                message,
                "an estimate",
                &mut self.failures,
            );
            self.count(sent, |s| &mut s.estimates);
        }
        // A frame's surfaces follow its estimate: those not here yet go
        // on the next wake (at most 100 ms later).
        while let Some(frame) = inputs.surfaces.receive()? {
            let array = markers(&frame, self.last_estimate.as_ref(), self.frame_id);
            let sent = send(
                &self.outputs.markers,
                array,
                "the markers",
                &mut self.failures,
            );
            self.count(sent, |s| &mut s.markers);
            let message = SurfacesMsg::new(&frame, self.frame_id);
            let sent = send(
                &self.outputs.surfaces,
                message,
                "the surfaces",
                &mut self.failures,
            );
            self.count(sent, |s| &mut s.surfaces);
        }
        // Reports come about once a second: looked at on every wake.
        while let Some(report) = inputs.health.receive()? {
            let message = self.rule.array(&report);
            let sent = send(
                &self.outputs.diagnostics,
                message,
                "a diagnostic",
                &mut self.failures,
            );
            self.count(sent, |s| &mut s.diagnostics);
        }
        Ok(heard)
    }

    /// One more in the counter `which` when `sent`, else one more dropped.
    fn count(&mut self, sent: bool, which: fn(&mut Ros2Stats) -> &mut u64) {
        if sent {
            *which(&mut self.stats) += 1;
        } else {
            self.stats.dropped += 1;
        }
    }
}

/// Publishes `message` (`what`, for the log); false when DDS refused it
/// (a full send window to a reader that stopped acknowledging, a socket
/// error): logged at most once every [`FAILURE_NOTE_EVERY`], the message
/// dropped, the node going on.
fn send<M: Serialize>(
    publisher: &Publisher<M>,
    message: M,
    what: &str,
    failures: &mut FailureNote,
) -> bool {
    match publisher.publish(message) {
        Ok(()) => true,
        Err(err) => {
            failures.note(what, &err.to_string());
            false
        }
    }
}

/// How often a failing publish is logged.
const FAILURE_NOTE_EVERY: Duration = Duration::from_secs(5);

/// Rate-limits the log of failed publishes.
#[derive(Debug, Default)]
struct FailureNote {
    last: Option<Instant>,
    since: u64,
}

impl FailureNote {
    fn note(&mut self, what: &str, reason: &str) {
        self.since += 1;
        if self.last.is_none_or(|t| t.elapsed() >= FAILURE_NOTE_EVERY) {
            tracing::warn!(
                dropped = self.since,
                "cannot publish {what} on ROS 2 (dropped): {reason}"
            );
            self.last = Some(Instant::now());
            self.since = 0;
        }
    }
}
