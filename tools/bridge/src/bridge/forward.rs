//! The forwarding loop ([`run`]): iceoryx2 estimates, surfaces and health
//! reports put on Zenoh as JSON until a stop.

use anyhow::Context;
use slope_sensor::ipc::{create_node, EstimateSubscriber, HealthSubscriber, SurfacesSubscriber};
use slope_sensor::publish::StopFlag;
use slope_tools::cli::{node_name, wait_loop, SilenceNote};
use zenoh::bytes::Encoding;
use zenoh::pubsub::Publisher;
use zenoh::Wait;

use super::args::{key_prefix_arg, BridgeArgs};
use super::config::zenoh_config;
use super::reason::zenoh_reason;
use super::session::{open_session, Network};
use crate::payload::{
    estimate_json, health_json, surfaces_json, ESTIMATE_KEY, HEALTH_KEY, SURFACES_KEY,
};

/// What the bridge forwarded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BridgeStats {
    pub estimates: u64,
    pub surfaces: u64,
    pub health_reports: u64,
}

/// Forwards the estimates (and, unless `--no-health`, the health reports)
/// of `args`' service prefix to Zenoh until `stop` is set; returns how many
/// were forwarded.
pub fn run(args: &BridgeArgs, stop: &StopFlag) -> anyhow::Result<BridgeStats> {
    let names = args.common.service_names(stop)?;
    let key_prefix = key_prefix(args, names.prefix())?;
    let config = zenoh_config(args)?;
    let network = Network::of(&config);
    let Some(session) = open_session(config, &network, stop)? else {
        return Ok(BridgeStats::default());
    };
    let outputs = Outputs {
        estimate: declare(&session, &key_prefix, ESTIMATE_KEY)?,
        surfaces: declare(&session, &key_prefix, SURFACES_KEY)?,
        health: declare(&session, &key_prefix, HEALTH_KEY)?,
    };

    let node = create_node(&node_name("slope-bridge"))?;
    let estimates = EstimateSubscriber::create(&node, &names)?;
    let surfaces = SurfacesSubscriber::create(&node, &names)?;
    let health = if args.no_health {
        None
    } else {
        Some(HealthSubscriber::create(&node, &names)?)
    };
    tracing::info!(
        estimates = %names.estimate(),
        key_prefix = %key_prefix,
        zid = %session.zid(),
        mode = %network.mode,
        listen = %network.listen,
        connect = %network.connect,
        "bridge ready"
    );
    let service = names.estimate();
    let inputs = Inputs {
        estimates: &estimates,
        surfaces: &surfaces,
        health: health.as_ref(),
    };
    let stats = forward(&inputs, &outputs, &service, stop)?;
    tracing::info!(
        estimates = stats.estimates,
        surfaces = stats.surfaces,
        health_reports = stats.health_reports,
        "bridge stopped"
    );
    Ok(stats)
}

/// `--key-prefix`, else the service prefix if it is a usable key prefix.
fn key_prefix(args: &BridgeArgs, service_prefix: &str) -> anyhow::Result<String> {
    Ok(match &args.key_prefix {
        Some(prefix) => prefix.clone(),
        None => key_prefix_arg(service_prefix).map_err(|e| {
            anyhow::anyhow!("{e} (the service prefix is the default key prefix: give --key-prefix)")
        })?,
    })
}

/// The iceoryx2 topics forwarded.
struct Inputs<'a> {
    estimates: &'a EstimateSubscriber,
    surfaces: &'a SurfacesSubscriber,
    health: Option<&'a HealthSubscriber>,
}

/// The Zenoh publishers of the three topics.
struct Outputs {
    estimate: Publisher<'static>,
    surfaces: Publisher<'static>,
    health: Publisher<'static>,
}

/// A JSON publisher on `<key_prefix>/<suffix>`.
fn declare(
    session: &zenoh::Session,
    key_prefix: &str,
    suffix: &str,
) -> anyhow::Result<Publisher<'static>> {
    let key = format!("{key_prefix}/{suffix}");
    session
        .declare_publisher(key.clone())
        .encoding(Encoding::APPLICATION_JSON)
        .wait()
        .map_err(|e| anyhow::anyhow!("cannot publish on Zenoh key {key}: {}", zenoh_reason(&e)))
}

/// Puts every estimate, surfaces message and health report that arrives
/// on Zenoh until `stop` is set; `service` is the estimate service, named
/// when it stays silent.
fn forward(
    inputs: &Inputs<'_>,
    outputs: &Outputs,
    service: &str,
    stop: &StopFlag,
) -> anyhow::Result<BridgeStats> {
    let mut stats = BridgeStats::default();
    let mut silence = SilenceNote::new("estimate", service, "slope-estimator");
    wait_loop(inputs.estimates.listener(), stop, || {
        silence.tick();
        while let Some(estimate) = inputs.estimates.receive()? {
            silence.heard();
            let json = estimate_json(&estimate).context("cannot write an estimate as JSON")?;
            put(&outputs.estimate, json, "an estimate")?;
            stats.estimates += 1;
        }
        // A frame's surfaces follow its estimate: those not here yet go
        // on the next wake (at most 100 ms later).
        while let Some(surfaces) = inputs.surfaces.receive()? {
            let json = surfaces_json(&surfaces).context("cannot write the surfaces as JSON")?;
            put(&outputs.surfaces, json, "the surfaces")?;
            stats.surfaces += 1;
        }
        // Reports come once a second: looked at on every wake (100 ms).
        if let Some(health) = inputs.health {
            while let Some(report) = health.receive()? {
                let json = health_json(&report).context("cannot write a health report")?;
                put(&outputs.health, json, "a health report")?;
                stats.health_reports += 1;
            }
        }
        Ok(true)
    })?;
    Ok(stats)
}

/// Puts `json` (`what`, for the error) on `publisher`.
fn put(publisher: &Publisher<'static>, json: String, what: &str) -> anyhow::Result<()> {
    publisher
        .put(json)
        .wait()
        .map_err(|e| anyhow::anyhow!("cannot put {what} on Zenoh: {}", zenoh_reason(&e)))
}
