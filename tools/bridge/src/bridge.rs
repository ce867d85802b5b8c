//! The forwarding loop: iceoryx2 `<prefix>/estimate` and `<prefix>/health`
//! to Zenoh `<key prefix>/estimate` and `<key prefix>/health`.

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Parser;
use slope_sensor::ipc::{create_node, EstimateSubscriber, HealthSubscriber};
use slope_sensor::publish::StopFlag;
use slope_tools::cli::{
    node_name, wait_loop, CommonArgs, SilenceNote, CLIENT_PREFIX_HELP, WAKE_INTERVAL,
};
use zenoh::bytes::Encoding;
use zenoh::Wait;

use crate::payload::{estimate_json, health_json, ESTIMATE_KEY, HEALTH_KEY};

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

/// What the bridge forwarded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BridgeStats {
    pub estimates: u64,
    pub health_reports: u64,
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

/// Zenoh's message of `err` without the source locations it appends to
/// each part (` at /root/.cargo/registry/src/.../config.rs:86.`).
pub fn zenoh_reason(err: &dyn std::fmt::Display) -> String {
    let text = err.to_string();
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(at) = rest.find(" at ") {
        out.push_str(&rest[..at]);
        let after = &rest[at + " at ".len()..];
        // `<path>.rs:<line>.`: no spaces in the path.
        let location = after
            .find(".rs:")
            .filter(|&rs| !after[..rs].contains(char::is_whitespace))
            .and_then(|rs| {
                let digits = after[rs + 4..]
                    .find(|c: char| !c.is_ascii_digit())
                    .unwrap_or(after.len() - rs - 4);
                let end = rs + 4 + digits;
                (digits > 0).then(|| end + usize::from(after[end..].starts_with('.')))
            });
        match location {
            Some(end) => rest = &after[end..],
            None => {
                out.push_str(" at ");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    one_line(out.trim())
}

/// A parser's multi-line report (JSON5 in a config file: ` --> 1:9`, the
/// line quoted with `|` margins, `= expected ...`) as one line: where, and
/// what was expected.
fn one_line(text: &str) -> String {
    if !text.contains('\n') {
        return text.to_string();
    }
    let mut parts = Vec::new();
    for line in text.lines().map(str::trim) {
        if let Some(place) = line.strip_prefix("--> ") {
            let (row, column) = place.split_once(':').unwrap_or((place, "?"));
            parts.push(format!("at line {row}, column {column}"));
        } else if let Some(message) = line.strip_prefix("= ") {
            parts.push(message.to_string());
        } else if !line.is_empty() && !line.contains('|') {
            parts.push(line.to_string());
        }
    }
    parts.join(": ")
}

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

/// What a Zenoh configuration says about the network, for the log and
/// for error messages (JSON, as Zenoh gives it).
#[derive(Debug, Clone, Default)]
struct Network {
    mode: String,
    listen: String,
    connect: String,
}

impl Network {
    fn of(config: &zenoh::Config) -> Self {
        let get = |key: &str| config.get_json(key).unwrap_or_default();
        Network {
            mode: get("mode"),
            listen: get("listen/endpoints"),
            connect: get("connect/endpoints"),
        }
    }
}

/// How long the session may take to open before the log says that the
/// bridge waits.
const WAITING_NOTE_AFTER: Duration = Duration::from_secs(1);

/// Opens the Zenoh session of `config` on a thread of its own, so that a
/// stop (SIGINT, SIGTERM) ends the wait: in client mode Zenoh retries the
/// router until it answers. `None` when stopped first.
fn open_session(
    config: zenoh::Config,
    network: &Network,
    stop: &StopFlag,
) -> anyhow::Result<Option<zenoh::Session>> {
    let Network {
        mode,
        listen,
        connect,
    } = network;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("zenoh-open".into())
        .spawn(move || {
            // The receiver is gone only when the bridge stopped waiting.
            let _ = tx.send(zenoh::open(config).wait());
        })
        .context("cannot start the thread that opens the Zenoh session")?;
    let started = Instant::now();
    let mut noted = false;
    loop {
        match rx.recv_timeout(WAKE_INTERVAL) {
            Ok(Ok(session)) => return Ok(Some(session)),
            Ok(Err(e)) => {
                anyhow::bail!(
                    "cannot open the Zenoh session (mode {mode}, listen {listen}, connect \
                     {connect}): {}",
                    zenoh_reason(&e)
                )
            }
            Err(RecvTimeoutError::Timeout) => {
                if stop.is_stopped() {
                    tracing::info!("stopped while waiting for Zenoh");
                    return Ok(None);
                }
                if !noted && started.elapsed() >= WAITING_NOTE_AFTER {
                    noted = true;
                    tracing::info!(
                        mode = %mode,
                        connect = %connect,
                        "waiting for Zenoh to connect (client mode retries the router until it \
                         answers; SIGINT or SIGTERM stops)"
                    );
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                anyhow::bail!("the thread opening the Zenoh session ended without an answer")
            }
        }
    }
}

pub fn run(args: &BridgeArgs, stop: &StopFlag) -> anyhow::Result<BridgeStats> {
    let names = args.common.service_names()?;
    let key_prefix = match &args.key_prefix {
        Some(prefix) => prefix.clone(),
        None => key_prefix_arg(names.prefix()).map_err(|e| {
            anyhow::anyhow!("{e} (the service prefix is the default key prefix: give --key-prefix)")
        })?,
    };
    let config = zenoh_config(args)?;
    let network = Network::of(&config);
    let Some(session) = open_session(config, &network, stop)? else {
        return Ok(BridgeStats::default());
    };
    let declare = |suffix: &str| {
        let key = format!("{key_prefix}/{suffix}");
        session
            .declare_publisher(key.clone())
            .encoding(Encoding::APPLICATION_JSON)
            .wait()
            .map_err(|e| anyhow::anyhow!("cannot publish on Zenoh key {key}: {}", zenoh_reason(&e)))
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
        mode = %network.mode,
        listen = %network.listen,
        connect = %network.connect,
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
            estimate_out.put(json).wait().map_err(|e| {
                anyhow::anyhow!("cannot put an estimate on Zenoh: {}", zenoh_reason(&e))
            })?;
            stats.estimates += 1;
        }
        // Reports come once a second: looked at on every wake (100 ms).
        if let Some(health) = &health {
            while let Some(report) = health.receive()? {
                let json = health_json(&report).context("cannot write a health report")?;
                health_out.put(json).wait().map_err(|e| {
                    anyhow::anyhow!("cannot put a health report on Zenoh: {}", zenoh_reason(&e))
                })?;
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
    use std::net::TcpListener;
    use std::path::PathBuf;

    use clap::{CommandFactory, Parser};
    use slope_sensor::publish::StopFlag;

    use super::{endpoint_arg, key_prefix_arg, run, zenoh_config, zenoh_reason, BridgeArgs};

    fn args(flags: &[&str]) -> BridgeArgs {
        let mut line = vec!["slope-bridge", "--service-prefix", "slope-bridge-unit"];
        line.extend_from_slice(flags);
        BridgeArgs::try_parse_from(line).unwrap_or_else(|e| panic!("{flags:?}: {e}"))
    }

    /// `key` of the Zenoh configuration that `flags` make.
    fn setting(flags: &[&str], key: &str) -> String {
        let config = zenoh_config(&args(flags)).unwrap_or_else(|e| panic!("{flags:?}: {e:#}"));
        config.get_json(key).expect("a Zenoh key")
    }

    /// A Zenoh configuration file holding `text`, removed when dropped.
    struct ConfigFile(PathBuf);

    impl ConfigFile {
        fn new(name: &str, text: &str) -> Self {
            let path = std::env::temp_dir()
                .join(format!("slope-bridge-{}-{name}.json5", std::process::id()));
            std::fs::write(&path, text).expect("write the config file");
            ConfigFile(path)
        }

        fn path(&self) -> &str {
            self.0.to_str().expect("UTF-8 temporary path")
        }
    }

    impl Drop for ConfigFile {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    /// slope-bridge speaks with the voice of every slope program
    /// (`slope_tools::flag_rules`).
    #[test]
    fn the_bridge_follows_the_flag_rules() {
        let found = slope_tools::flag_rules::violations(&BridgeArgs::command());
        assert!(found.is_empty(), "{}", found.join("\n"));
    }

    /// The bridge has no --config; its --service-prefix help must not send
    /// the reader to one.
    #[test]
    fn the_service_prefix_help_names_no_config_flag() {
        let command = BridgeArgs::command();
        let help = command
            .get_arguments()
            .find(|a| a.get_id() == "service_prefix")
            .and_then(|a| a.get_help())
            .expect("--service-prefix has a help text")
            .to_string();
        assert!(!help.contains("--config"), "{help}");
        assert!(help.contains("/etc/slope/slope.toml"), "{help}");
    }

    /// Without flags or file: peer mode, no multicast scouting.
    #[test]
    fn without_flags_or_file_the_bridge_is_a_peer_without_multicast() {
        assert_eq!(setting(&[], "mode"), "\"peer\"");
        assert_eq!(setting(&[], "scouting/multicast/enabled"), "false");
        assert_eq!(
            setting(&["--multicast-scouting"], "scouting/multicast/enabled"),
            "true"
        );
    }

    /// A --zenoh-config file's mode and multicast scouting hold unless a
    /// flag says otherwise.
    #[test]
    fn the_config_file_keeps_its_mode_and_scouting_unless_a_flag_is_given() {
        let file = ConfigFile::new(
            "mode",
            r#"{ mode: "router", scouting: { multicast: { enabled: true } } }"#,
        );
        let from_file = ["--zenoh-config", file.path()];
        assert_eq!(setting(&from_file, "mode"), "\"router\"");
        assert_eq!(setting(&from_file, "scouting/multicast/enabled"), "true");
        let overridden = ["--zenoh-config", file.path(), "--mode", "client"];
        assert_eq!(setting(&overridden, "mode"), "\"client\"");

        let off = ConfigFile::new(
            "multicast-off",
            "{ scouting: { multicast: { enabled: false } } }",
        );
        let flagged = ["--zenoh-config", off.path(), "--multicast-scouting"];
        assert_eq!(setting(&flagged, "scouting/multicast/enabled"), "true");
        assert_eq!(setting(&["--zenoh-config", off.path()], "mode"), "\"peer\"");
    }

    /// Nothing is listened on unless --listen or the file says where
    /// (Zenoh's default would be every interface, tcp/[::]:0).
    #[test]
    fn the_bridge_listens_only_where_told() {
        assert_eq!(setting(&[], "listen/endpoints"), "[]");
        assert_eq!(setting(&["--mode", "router"], "listen/endpoints"), "[]");
        assert_eq!(
            setting(&["--listen", "tcp/127.0.0.1:7447"], "listen/endpoints"),
            r#"["tcp/127.0.0.1:7447"]"#
        );
        let file = ConfigFile::new(
            "listen",
            r#"{ listen: { endpoints: ["tcp/127.0.0.1:7448"] } }"#,
        );
        assert_eq!(
            setting(&["--zenoh-config", file.path()], "listen/endpoints"),
            r#"["tcp/127.0.0.1:7448"]"#
        );
        assert_eq!(
            setting(
                &[
                    "--zenoh-config",
                    file.path(),
                    "--listen",
                    "tcp/127.0.0.1:7449"
                ],
                "listen/endpoints"
            ),
            r#"["tcp/127.0.0.1:7449"]"#
        );
    }

    /// In client mode the connection is retried for ever (Zenoh's default,
    /// 0, gives up at once), unless the file sets connect/timeout_ms.
    #[test]
    fn a_client_retries_its_router_unless_the_file_says_otherwise() {
        let timeout = setting(&["--mode", "client"], "connect/timeout_ms");
        assert!(timeout.contains("\"client\":-1"), "{timeout}");
        let file = ConfigFile::new("timeout", "{ connect: { timeout_ms: 2500 } }");
        assert_eq!(
            setting(&["--zenoh-config", file.path()], "connect/timeout_ms"),
            "2500"
        );
    }

    #[test]
    fn zenoh_source_locations_are_cut_from_its_messages() {
        let raw = "Can not create a new TCP listener bound to 127.0.0.1:1: Address in use (os \
                   error 98) at /root/.cargo/registry/src/index.crates.io-x/zenoh-link-tcp-1.10.2/\
                   src/unicast.rs:375. - Caused by invalid at /a/b.rs:1.";
        assert_eq!(
            zenoh_reason(&raw),
            "Can not create a new TCP listener bound to 127.0.0.1:1: Address in use (os error 98) \
             - Caused by invalid"
        );
        assert_eq!(zenoh_reason(&"look at this"), "look at this");
        let pest =
            " --> 1:9\n  |\n1 | { mode: \n  |         ^---\n  |\n  = expected array, or string";
        assert_eq!(
            zenoh_reason(&pest),
            "at line 1, column 9: expected array, or string"
        );
    }

    /// `--listen nonsense`: one line saying what was given and what is
    /// expected.
    #[test]
    fn a_malformed_endpoint_is_refused_with_what_is_expected() {
        for given in [
            "nonsense",
            "udp/127.0.0.1:7447",
            "tcp/127.0.0.1",
            "tcp/host:port",
        ] {
            let err = endpoint_arg(given).expect_err(given);
            assert!(err.contains(&format!("'{given}'")), "{err}");
            assert!(err.contains("tcp/HOST:PORT"), "{err}");
            assert!(!err.contains(".rs:") && !err.contains('\n'), "{err}");
        }
        for given in ["tcp/127.0.0.1:7447", "tcp/[::]:0", "tcp/router.local:7447"] {
            assert_eq!(endpoint_arg(given).as_deref(), Ok(given));
        }
        let err = BridgeArgs::try_parse_from(["slope-bridge", "--listen", "nonsense"])
            .expect_err("--listen nonsense");
        assert!(err.to_string().contains("tcp/HOST:PORT"), "{err}");
    }

    #[test]
    fn a_key_prefix_must_be_a_plain_zenoh_key_expression() {
        for bad in ["", "a//b", "/a", "a/", "a/*", "a/**", "a$b", "a?b", "a#b"] {
            let err = key_prefix_arg(bad).expect_err(bad);
            assert!(
                err.contains(&format!("'{bad}'")) && err.contains("e.g. robot1/slope"),
                "{err}"
            );
        }
        for good in ["slope", "robot1/slope", "slope-test-bridge-1-0"] {
            assert_eq!(key_prefix_arg(good).as_deref(), Ok(good));
        }
    }

    /// The bridge's error for `flags`, as its user reads it.
    fn run_error(flags: &[&str]) -> String {
        let err = run(&args(flags), &StopFlag::new()).expect_err("the bridge fails");
        let text = format!("{err:#}");
        assert!(
            !text.contains(".cargo") && !text.contains(".rs:") && !text.contains('\n'),
            "{text}"
        );
        text
    }

    /// A service prefix that is no key expression is refused before the
    /// session opens (here the port in use would otherwise fail first).
    #[test]
    fn an_unusable_key_prefix_is_refused_before_the_session_opens() {
        let held = TcpListener::bind("127.0.0.1:0").expect("bind a port");
        let endpoint = format!(
            "tcp/127.0.0.1:{}",
            held.local_addr().expect("address").port()
        );
        let mut line = vec!["slope-bridge", "--service-prefix", "robot#1", "--listen"];
        line.push(&endpoint);
        let err = run(
            &BridgeArgs::try_parse_from(line).expect("flags"),
            &StopFlag::new(),
        )
        .expect_err("refused");
        let text = format!("{err:#}");
        assert!(
            text.contains("'robot#1'") && text.contains("--key-prefix"),
            "{text}"
        );
    }

    #[test]
    fn a_port_in_use_is_one_line_naming_the_endpoint() {
        let held = TcpListener::bind("127.0.0.1:0").expect("bind a port");
        let endpoint = format!(
            "tcp/127.0.0.1:{}",
            held.local_addr().expect("address").port()
        );
        let text = run_error(&["--listen", &endpoint]);
        assert!(text.contains(&endpoint), "{text}");
    }

    #[test]
    fn a_missing_zenoh_config_says_which_file() {
        let text = run_error(&["--zenoh-config", "/nonexistent/zenoh.json5"]);
        assert!(
            text.contains("/nonexistent/zenoh.json5") && text.contains("No such file"),
            "{text}"
        );
        let broken = ConfigFile::new("broken", "{ mode: ");
        let text = run_error(&["--zenoh-config", broken.path()]);
        assert!(text.contains(broken.path()), "{text}");
    }
}
