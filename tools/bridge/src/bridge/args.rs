//! The flags of `slope-bridge` ([`BridgeArgs`]) and the checks of their
//! values: a Zenoh TCP endpoint ([`endpoint_arg`]) and a key prefix
//! ([`key_prefix_arg`]).

use std::path::PathBuf;
use std::str::FromStr;

use clap::Parser;
use slope_tools::cli::{CommonArgs, CLIENT_PREFIX_HELP};

use crate::payload::ESTIMATE_KEY;

#[derive(Debug, Parser)]
#[command(
    // It has no --config: the daemons' file only.
    mut_arg("service_prefix", |arg| arg.help(CLIENT_PREFIX_HELP)),
    name = "slope-bridge",
    version,
    about = "Forward slope estimates and health reports to Zenoh, for other computers",
    long_about = "Subscribes to the estimate and health topics of one service prefix on this \
host (iceoryx2) and puts every message on Zenoh as JSON, under the key expressions \
<key-prefix>/estimate and <key-prefix>/health. Each JSON object carries a `schema` key \
(slope.estimate.json/1, slope.health.json/1) beside the keys of `slope-echo --json` and \
`slope-echo --health --json`. Multicast scouting is off and nothing is listened on unless asked \
for: peers are those given with --listen and --connect (or in --zenoh-config). In client mode \
the bridge waits for its router, retrying, until it answers. Stops cleanly on SIGINT or SIGTERM.",
    after_help = "Examples:
  slope-bridge --listen tcp/0.0.0.0:7447                  # others connect to this host
  slope-bridge --connect tcp/192.168.1.10:7447            # join a peer or router elsewhere
  slope-bridge --mode client --connect tcp/router:7447    # through a Zenoh router
  slope-bridge --zenoh-config zenoh.json5                 # any Zenoh setting

On the other computer, any Zenoh subscriber on slope/estimate receives the JSON, e.g. \
`z_sub -k 'slope/**' -e tcp/ROBOT:7447` from Zenoh's examples."
)]
pub struct BridgeArgs {
    /// Zenoh mode: peer, client (through a router) or router. Default: the
    /// --zenoh-config file's `mode`, else peer.
    #[arg(long, value_parser = ["peer", "client", "router"])]
    pub mode: Option<String>,

    /// Listen for Zenoh peers on this endpoint (repeatable), e.g.
    /// tcp/0.0.0.0:7447. Default: the --zenoh-config file's
    /// `listen/endpoints`, else none.
    #[arg(long = "listen", value_name = "ENDPOINT", value_parser = endpoint_arg)]
    pub listen: Vec<String>,

    /// Connect to this Zenoh endpoint (repeatable), e.g.
    /// tcp/192.168.1.10:7447. Default: the --zenoh-config file's
    /// `connect/endpoints`, else none.
    #[arg(long = "connect", value_name = "ENDPOINT", value_parser = endpoint_arg)]
    pub connect: Vec<String>,

    /// Find peers by UDP multicast scouting as well. Without it: the
    /// --zenoh-config file's `scouting/multicast/enabled`, else off (only
    /// --listen and --connect).
    #[arg(long)]
    pub multicast_scouting: bool,

    /// A Zenoh configuration file (JSON5 or YAML); --mode, --listen,
    /// --connect and --multicast-scouting override its settings when given.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,

    /// Key expression prefix on Zenoh (default: the service prefix), e.g.
    /// robot1/slope.
    #[arg(long, value_parser = key_prefix_arg)]
    pub key_prefix: Option<String>,

    /// Forward estimates only, not health reports.
    #[arg(long)]
    pub no_health: bool,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// What a `--listen`/`--connect` value must look like (this build has
/// Zenoh's TCP transport only).
const ENDPOINT_EXPECTED: &str = "expected tcp/HOST:PORT, e.g. tcp/192.168.1.10:7447 or \
tcp/0.0.0.0:7447 (this build speaks TCP only)";

/// `--listen` and `--connect`: a Zenoh TCP endpoint, `tcp/HOST:PORT`.
pub fn endpoint_arg(text: &str) -> Result<String, String> {
    let not = |why: &str| format!("'{text}' is not a Zenoh endpoint ({why}): {ENDPOINT_EXPECTED}");
    let endpoint =
        zenoh::config::EndPoint::from_str(text).map_err(|_| not("no PROTOCOL/ADDRESS"))?;
    if endpoint.protocol().as_str() != "tcp" {
        return Err(not(&format!("protocol '{}'", endpoint.protocol().as_str())));
    }
    let address = endpoint.address();
    let port = address
        .as_str()
        .rsplit_once(':')
        .map(|(_, port)| port)
        .unwrap_or_default();
    if port.parse::<u16>().is_err() {
        return Err(not("no port"));
    }
    Ok(text.to_string())
}

/// What a key prefix must look like.
const KEY_PREFIX_EXPECTED: &str = "expected chunks separated by '/', none of them empty, without \
'*', '$', '?' or '#' and without a leading or trailing '/', e.g. robot1/slope";

/// `--key-prefix` (and the service prefix as its default): a Zenoh key
/// expression without wildcards, to which `/estimate` and `/health` are
/// added.
pub fn key_prefix_arg(text: &str) -> Result<String, String> {
    let usable = text
        .split('/')
        .all(|chunk| !chunk.is_empty() && !chunk.contains(['*', '$', '?', '#']))
        && zenoh::key_expr::KeyExpr::try_from(format!("{text}/{ESTIMATE_KEY}")).is_ok();
    if usable {
        Ok(text.to_string())
    } else {
        Err(format!(
            "'{text}' is not a Zenoh key prefix: {KEY_PREFIX_EXPECTED}"
        ))
    }
}
