//! The Zenoh configuration the bridge opens its session with
//! ([`zenoh_config`]): the `--zenoh-config` file, the flags over it, and
//! the bridge's defaults for what neither says.

use std::path::Path;

use super::args::BridgeArgs;
use super::reason::zenoh_reason;

/// The Zenoh configuration of `args`: the `--zenoh-config` file (else
/// Zenoh's defaults), then each flag that was given; then, for what
/// neither says, the bridge's defaults: peer mode, no multicast scouting,
/// no listening, and in client mode a connection retried until the router
/// answers.
pub fn zenoh_config(args: &BridgeArgs) -> anyhow::Result<zenoh::Config> {
    let mut config = match &args.zenoh_config {
        Some(path) => config_file(path)?,
        None => zenoh::Config::default(),
    };
    let unset = |config: &zenoh::Config, key: &str| {
        config.get_json(key).map_or(true, |value| value == "null")
    };
    let file_listen = config.get_json("listen/endpoints").ok();
    let default_listen = zenoh::Config::default().get_json("listen/endpoints").ok();

    let mut settings: Vec<(&str, String)> = Vec::new();
    match &args.mode {
        Some(mode) => settings.push(("mode", format!("{mode:?}"))),
        None if unset(&config, "mode") => settings.push(("mode", "\"peer\"".into())),
        None => {}
    }
    if args.multicast_scouting {
        settings.push(("scouting/multicast/enabled", "true".into()));
    } else if unset(&config, "scouting/multicast/enabled") {
        settings.push(("scouting/multicast/enabled", "false".into()));
    }
    if !args.listen.is_empty() {
        settings.push(("listen/endpoints", endpoint_list(&args.listen)));
    } else if file_listen == default_listen {
        // Zenoh's own default listens on every interface (tcp/[::]:0 for
        // a peer, tcp/[::]:7447 for a router).
        settings.push(("listen/endpoints", "[]".into()));
    }
    if !args.connect.is_empty() {
        settings.push(("connect/endpoints", endpoint_list(&args.connect)));
    }
    if unset(&config, "connect/timeout_ms") {
        // Zenoh's default (client: 0) gives up at once when the router
        // is not up; a robot's bridge waits for it (-1: retry for ever,
        // every connect/retry period). Peers and routers keep Zenoh's.
        settings.push(("connect/timeout_ms", "{ client: -1 }".into()));
    }
    for (key, value) in settings {
        config.insert_json5(key, &value).map_err(|e| {
            anyhow::anyhow!("cannot set Zenoh {key} to {value}: {}", zenoh_reason(&e))
        })?;
    }
    Ok(config)
}

/// The `--zenoh-config` file, with a one-line reason when it cannot be
/// read or is not a Zenoh configuration.
fn config_file(path: &Path) -> anyhow::Result<zenoh::Config> {
    std::fs::metadata(path)
        .map_err(|e| anyhow::anyhow!("cannot read the Zenoh config {}: {e}", path.display()))?;
    zenoh::Config::from_file(path).map_err(|e| {
        anyhow::anyhow!(
            "{} is not a usable Zenoh config (a .json5, .json or .yaml file with Zenoh's keys): {}",
            path.display(),
            zenoh_reason(&e)
        )
    })
}

/// `["tcp/a:1","tcp/b:2"]`.
fn endpoint_list(endpoints: &[String]) -> String {
    let quoted: Vec<String> = endpoints.iter().map(|e| format!("{e:?}")).collect();
    format!("[{}]", quoted.join(","))
}
