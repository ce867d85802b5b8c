//! Unit tests: the flags, the Zenoh configuration they make, and the
//! bridge's errors as its user reads them.

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
        let path =
            std::env::temp_dir().join(format!("slope-bridge-{}-{name}.json5", std::process::id()));
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
    let pest = " --> 1:9\n  |\n1 | { mode: \n  |         ^---\n  |\n  = expected array, or string";
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
