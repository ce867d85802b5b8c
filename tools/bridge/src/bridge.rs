//! The forwarding loop: iceoryx2 `<prefix>/estimate` and `<prefix>/health`
//! to Zenoh `<key prefix>/estimate` and `<key prefix>/health`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use slope_sensor::ipc::{create_node, EstimateSubscriber, HealthSubscriber};
use slope_sensor::publish::StopFlag;
use slope_tools::cli::{node_name, wait_loop, CommonArgs, SilenceNote};
use zenoh::bytes::Encoding;
use zenoh::Wait;

use crate::payload::{estimate_json, health_json, ESTIMATE_KEY, HEALTH_KEY};

#[derive(Debug, Parser)]
#[command(
    name = "slope-bridge",
    version,
    about = "Forward slope estimates and health reports to Zenoh, for other computers",
    long_about = "Subscribes to the estimate and health topics of one service prefix on this \
host (iceoryx2) and puts every message on Zenoh as JSON, under the key expressions \
<key-prefix>/estimate and <key-prefix>/health. Each JSON object carries a `schema` key \
(slope.estimate.json/1, slope.health.json/1) beside the keys of `slope-echo --json` and \
`slope-echo --health --json`. Multicast scouting is off unless asked for: peers are those \
given with --listen and --connect. Stops cleanly on SIGINT or SIGTERM.",
    after_help = "Examples:
  slope-bridge --listen tcp/0.0.0.0:7447                  # others connect to this host
  slope-bridge --connect tcp/192.168.1.10:7447            # join a peer or router elsewhere
  slope-bridge --mode client --connect tcp/router:7447    # through a Zenoh router
  slope-bridge --zenoh-config zenoh.json5                 # any Zenoh setting

On the other computer, any Zenoh subscriber on slope/estimate receives the JSON, e.g. \
`z_sub -k 'slope/**' -e tcp/ROBOT:7447` from Zenoh's examples."
)]
pub struct BridgeArgs {
    /// Zenoh mode: peer, client (through a router) or router.
    #[arg(long, default_value = "peer", value_parser = ["peer", "client", "router"])]
    pub mode: String,

    /// Listen for Zenoh peers on this endpoint (repeatable), e.g.
    /// tcp/0.0.0.0:7447.
    #[arg(long = "listen", value_name = "ENDPOINT")]
    pub listen: Vec<String>,

    /// Connect to this Zenoh endpoint (repeatable), e.g.
    /// tcp/192.168.1.10:7447.
    #[arg(long = "connect", value_name = "ENDPOINT")]
    pub connect: Vec<String>,

    /// Find peers by UDP multicast scouting as well (off by default: only
    /// --listen and --connect).
    #[arg(long)]
    pub multicast_scouting: bool,

    /// A Zenoh configuration file (JSON5); the flags above override its
    /// mode, endpoints and scouting.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,

    /// Key expression prefix on Zenoh (default: the service prefix).
    #[arg(long)]
    pub key_prefix: Option<String>,

    /// Forward estimates only, not health reports.
    #[arg(long)]
    pub no_health: bool,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// What the bridge forwarded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BridgeStats {
    pub estimates: u64,
    pub health_reports: u64,
}

/// The Zenoh configuration of `args`.
pub fn zenoh_config(args: &BridgeArgs) -> anyhow::Result<zenoh::Config> {
    let mut config = match &args.zenoh_config {
        Some(path) => zenoh::Config::from_file(path)
            .map_err(|e| anyhow::anyhow!("invalid Zenoh config {}: {e}", path.display()))?,
        None => zenoh::Config::default(),
    };
    let mut set = |key: &str, value: String| {
        config
            .insert_json5(key, &value)
            .map_err(|e| anyhow::anyhow!("cannot set Zenoh {key} to {value}: {e}"))
    };
    set("mode", format!("{:?}", args.mode))?;
    set(
        "scouting/multicast/enabled",
        args.multicast_scouting.to_string(),
    )?;
    if !args.listen.is_empty() {
        set("listen/endpoints", endpoint_list(&args.listen))?;
    }
    if !args.connect.is_empty() {
        set("connect/endpoints", endpoint_list(&args.connect))?;
    }
    Ok(config)
}

/// `["tcp/a:1","tcp/b:2"]`.
fn endpoint_list(endpoints: &[String]) -> String {
    let quoted: Vec<String> = endpoints.iter().map(|e| format!("{e:?}")).collect();
    format!("[{}]", quoted.join(","))
}

pub fn run(args: &BridgeArgs, stop: &StopFlag) -> anyhow::Result<BridgeStats> {
    let names = args.common.service_names()?;
    let config = zenoh_config(args)?;
    let session = zenoh::open(config)
        .wait()
        .map_err(|e| anyhow::anyhow!("cannot open the Zenoh session: {e}"))?;
    let key_prefix = args
        .key_prefix
        .clone()
        .unwrap_or_else(|| names.prefix().to_string());
    let declare = |suffix: &str| {
        let key = format!("{key_prefix}/{suffix}");
        session
            .declare_publisher(key.clone())
            .encoding(Encoding::APPLICATION_JSON)
            .wait()
            .map_err(|e| anyhow::anyhow!("cannot publish on Zenoh key {key}: {e}"))
    };
    let estimate_out = declare(ESTIMATE_KEY)?;
    let health_out = declare(HEALTH_KEY)?;

    let node = create_node(&node_name("slope-bridge"))?;
    let estimates = EstimateSubscriber::create(&node, &names)?;
    let health = if args.no_health {
        None
    } else {
        Some(HealthSubscriber::create(&node, &names)?)
    };
    tracing::info!(
        estimates = %names.estimate(),
        key_prefix = %key_prefix,
        zid = %session.zid(),
        listen = ?args.listen,
        connect = ?args.connect,
        "bridge ready"
    );
    let mut stats = BridgeStats::default();
    let service = names.estimate();
    let mut silence = SilenceNote::new("estimate", &service, "slope-estimator");
    wait_loop(estimates.listener(), stop, || {
        silence.tick();
        while let Some(estimate) = estimates.receive()? {
            silence.heard();
            let json = estimate_json(&estimate).context("cannot write an estimate as JSON")?;
            estimate_out
                .put(json)
                .wait()
                .map_err(|e| anyhow::anyhow!("cannot put an estimate on Zenoh: {e}"))?;
            stats.estimates += 1;
        }
        // Reports come once a second: looked at on every wake (100 ms).
        if let Some(health) = &health {
            while let Some(report) = health.receive()? {
                let json = health_json(&report).context("cannot write a health report")?;
                health_out
                    .put(json)
                    .wait()
                    .map_err(|e| anyhow::anyhow!("cannot put a health report on Zenoh: {e}"))?;
                stats.health_reports += 1;
            }
        }
        Ok(true)
    })?;
    tracing::info!(
        estimates = stats.estimates,
        health_reports = stats.health_reports,
        "bridge stopped"
    );
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::BridgeArgs;

    /// slope-bridge speaks with the voice of every slope program
    /// (`slope_tools::flag_rules`).
    #[test]
    fn the_bridge_follows_the_flag_rules() {
        let found = slope_tools::flag_rules::violations(&BridgeArgs::command());
        assert!(found.is_empty(), "{}", found.join("\n"));
    }
}
