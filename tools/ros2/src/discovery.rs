//! ROS 2's own discovery settings, read as `rcl` reads them, so that
//! `slope-ros2` finds (and is found by) the nodes a ROS 2 user expects:
//!
//! - `ROS_DOMAIN_ID` (0 when unset or empty), overridden by `--domain-id`;
//! - `ROS_AUTOMATIC_DISCOVERY_RANGE`: `SUBNET` (the default) and
//!   `SYSTEM_DEFAULT` use every interface, `LOCALHOST` only the loopback;
//!   `OFF` is refused (RustDDS always announces itself on this host, so
//!   "off" cannot be kept);
//! - `ROS_LOCALHOST_ONLY=1` (before Jazzy) means `LOCALHOST` and wins over
//!   the range, as in `rcl`;
//! - `ROS_STATIC_PEERS` is not supported: [`Discovery::static_peers`] keeps
//!   it so that the node can say it is ignored.

use std::fmt;

/// The environment variable of the DDS domain.
pub const DOMAIN_ID_ENV: &str = "ROS_DOMAIN_ID";
/// The environment variable of the discovery range (Jazzy and later).
pub const DISCOVERY_RANGE_ENV: &str = "ROS_AUTOMATIC_DISCOVERY_RANGE";
/// The older switch to this host only (`1`).
pub const LOCALHOST_ONLY_ENV: &str = "ROS_LOCALHOST_ONLY";
/// Peers to reach beyond discovery (not supported here).
pub const STATIC_PEERS_ENV: &str = "ROS_STATIC_PEERS";

pub use slope_tools::ros2_names::MAX_DOMAIN_ID;

/// Which interfaces discovery and data use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiscoveryRange {
    /// The loopback interface only: this host's nodes.
    Localhost,
    /// Every interface (RustDDS's default), as ROS 2's `SUBNET`.
    Subnet,
}

impl DiscoveryRange {
    pub fn name(self) -> &'static str {
        match self {
            Self::Localhost => "localhost",
            Self::Subnet => "subnet",
        }
    }
}

/// What the environment (and `--domain-id`) say.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Discovery {
    pub domain_id: u16,
    pub range: DiscoveryRange,
    /// The variable that set the range (`None`: the default).
    pub range_from: Option<&'static str>,
    /// `ROS_STATIC_PEERS` when set and not empty (ignored).
    pub static_peers: Option<String>,
}

/// Why the environment's discovery settings were refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DiscoveryError {
    /// `ROS_DOMAIN_ID` or `--domain-id` out of range or not a number.
    DomainId { from: &'static str, value: String },
    /// `ROS_AUTOMATIC_DISCOVERY_RANGE` not one of ROS 2's values.
    Range(String),
    /// `ROS_AUTOMATIC_DISCOVERY_RANGE=OFF`.
    Off,
}

impl fmt::Display for DiscoveryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DomainId { from, value } => write!(
                f,
                "{from} is '{value}': expected a DDS domain id from 0 to {MAX_DOMAIN_ID}"
            ),
            Self::Range(value) => write!(
                f,
                "{DISCOVERY_RANGE_ENV} is '{value}': expected SUBNET, LOCALHOST or SYSTEM_DEFAULT"
            ),
            Self::Off => write!(
                f,
                "{DISCOVERY_RANGE_ENV}=OFF is not supported by slope-ros2 (RustDDS always \
                 announces itself on this host): use LOCALHOST to stay on this host"
            ),
        }
    }
}

impl std::error::Error for DiscoveryError {}

/// `--domain-id`: a number from 0 to [`MAX_DOMAIN_ID`].
pub fn domain_id_arg(text: &str) -> Result<u16, String> {
    parse_domain_id(text, "--domain-id").map_err(|e| e.to_string())
}

fn parse_domain_id(text: &str, from: &'static str) -> Result<u16, DiscoveryError> {
    text.trim()
        .parse::<u16>()
        .ok()
        .filter(|id| *id <= MAX_DOMAIN_ID)
        .ok_or_else(|| DiscoveryError::DomainId {
            from,
            value: text.to_string(),
        })
}

impl Discovery {
    /// The settings of the process's environment, `domain_flag`
    /// (`--domain-id`) over `ROS_DOMAIN_ID`.
    pub fn from_env(domain_flag: Option<u16>) -> Result<Self, DiscoveryError> {
        Self::from_lookup(|name| std::env::var(name).ok(), domain_flag)
    }

    /// The settings `lookup` (an environment) gives.
    pub fn from_lookup(
        lookup: impl Fn(&str) -> Option<String>,
        domain_flag: Option<u16>,
    ) -> Result<Self, DiscoveryError> {
        let set = |name: &str| lookup(name).filter(|value| !value.trim().is_empty());
        let domain_id = match (domain_flag, set(DOMAIN_ID_ENV)) {
            (Some(id), _) => id,
            (None, Some(text)) => parse_domain_id(&text, DOMAIN_ID_ENV)?,
            (None, None) => 0,
        };
        let localhost_only = set(LOCALHOST_ONLY_ENV).is_some_and(|v| v.trim() == "1");
        let (range, range_from) = if localhost_only {
            (DiscoveryRange::Localhost, Some(LOCALHOST_ONLY_ENV))
        } else {
            match set(DISCOVERY_RANGE_ENV) {
                None => (DiscoveryRange::Subnet, None),
                Some(value) => match value.trim().to_ascii_uppercase().as_str() {
                    "LOCALHOST" => (DiscoveryRange::Localhost, Some(DISCOVERY_RANGE_ENV)),
                    "SUBNET" | "SYSTEM_DEFAULT" => {
                        (DiscoveryRange::Subnet, Some(DISCOVERY_RANGE_ENV))
                    }
                    "OFF" => return Err(DiscoveryError::Off),
                    _ => return Err(DiscoveryError::Range(value)),
                },
            }
        };
        Ok(Self {
            domain_id,
            range,
            range_from,
            static_peers: set(STATIC_PEERS_ENV),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(vars: &[(&str, &str)], flag: Option<u16>) -> Result<Discovery, DiscoveryError> {
        let vars: Vec<(String, String)> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Discovery::from_lookup(
            |name| vars.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone()),
            flag,
        )
    }

    #[test]
    fn nothing_set_is_domain_0_on_every_interface() {
        let d = with(&[], None).unwrap();
        assert_eq!(
            (d.domain_id, d.range, d.range_from),
            (0, DiscoveryRange::Subnet, None)
        );
        let empty = with(&[(DOMAIN_ID_ENV, ""), (DISCOVERY_RANGE_ENV, " ")], None).unwrap();
        assert_eq!(empty, d);
    }

    #[test]
    fn the_flag_wins_over_ros_domain_id() {
        assert_eq!(with(&[(DOMAIN_ID_ENV, "42")], None).unwrap().domain_id, 42);
        assert_eq!(
            with(&[(DOMAIN_ID_ENV, "42")], Some(7)).unwrap().domain_id,
            7
        );
        // A bad variable under a flag does not matter.
        assert_eq!(with(&[(DOMAIN_ID_ENV, "x")], Some(7)).unwrap().domain_id, 7);
        for bad in ["233", "-1", "x"] {
            let err = with(&[(DOMAIN_ID_ENV, bad)], None).unwrap_err();
            assert!(err.to_string().contains("from 0 to 232"), "{err}");
        }
        assert_eq!(domain_id_arg("232"), Ok(232));
        assert!(domain_id_arg("300").unwrap_err().contains("--domain-id"));
    }

    #[test]
    fn the_ranges_of_ros_2_and_the_older_localhost_switch() {
        let range = |vars: &[(&str, &str)]| with(vars, None).map(|d| (d.range, d.range_from));
        assert_eq!(
            range(&[(DISCOVERY_RANGE_ENV, "LOCALHOST")]),
            Ok((DiscoveryRange::Localhost, Some(DISCOVERY_RANGE_ENV)))
        );
        assert_eq!(
            range(&[(DISCOVERY_RANGE_ENV, "subnet")]),
            Ok((DiscoveryRange::Subnet, Some(DISCOVERY_RANGE_ENV)))
        );
        assert_eq!(
            range(&[(DISCOVERY_RANGE_ENV, "SYSTEM_DEFAULT")]),
            Ok((DiscoveryRange::Subnet, Some(DISCOVERY_RANGE_ENV)))
        );
        // ROS_LOCALHOST_ONLY=1 wins, as in rcl; 0 leaves the range.
        assert_eq!(
            range(&[(LOCALHOST_ONLY_ENV, "1"), (DISCOVERY_RANGE_ENV, "SUBNET")]),
            Ok((DiscoveryRange::Localhost, Some(LOCALHOST_ONLY_ENV)))
        );
        assert_eq!(
            range(&[(LOCALHOST_ONLY_ENV, "0")]),
            Ok((DiscoveryRange::Subnet, None))
        );
        assert_eq!(
            range(&[(DISCOVERY_RANGE_ENV, "OFF")]),
            Err(DiscoveryError::Off)
        );
        let err = range(&[(DISCOVERY_RANGE_ENV, "LAN")]).unwrap_err();
        assert!(
            err.to_string().contains("expected SUBNET, LOCALHOST"),
            "{err}"
        );
    }

    #[test]
    fn static_peers_are_kept_to_be_reported() {
        let d = with(&[(STATIC_PEERS_ENV, "192.168.1.7")], None).unwrap();
        assert_eq!(d.static_peers.as_deref(), Some("192.168.1.7"));
    }
}
