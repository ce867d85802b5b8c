//! Service names. Every process builds them from one prefix so that tests
//! (and users running several robots' stacks on one machine) never share a
//! service by accident.

/// The prefix used when neither `--service-prefix` nor
/// [`SERVICE_PREFIX_ENV`] says otherwise.
pub const DEFAULT_SERVICE_PREFIX: &str = "slope";

/// Environment variable that overrides the service prefix.
pub const SERVICE_PREFIX_ENV: &str = "SLOPE_SERVICE_PREFIX";

/// Upper bound on points per cloud unless configured otherwise: 1024 x 1024,
/// enough for Kinect v2 (512 x 424), VGA (640 x 480) and 730 x 530 frames.
pub const DEFAULT_MAX_CLOUD_POINTS: usize = 1024 * 1024;

/// Suffix of the cloud service (publish-subscribe and event).
pub const CLOUD_SUFFIX: &str = "cloud";

/// Suffix of the estimate service (publish-subscribe and event).
pub const ESTIMATE_SUFFIX: &str = "estimate";

/// Suffix of the surfaces service (publish-subscribe and event).
pub const SURFACES_SUFFIX: &str = "surfaces";

/// Suffix of the health service (publish-subscribe and event).
pub const HEALTH_SUFFIX: &str = "health";

/// The service names for one prefix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    prefix: String,
}

impl ServiceNames {
    pub fn new(prefix: impl Into<String>) -> Self {
        Self {
            prefix: prefix.into(),
        }
    }

    /// The prefix from [`SERVICE_PREFIX_ENV`], else the default.
    pub fn from_env() -> Self {
        Self::new(
            std::env::var(SERVICE_PREFIX_ENV)
                .ok()
                .filter(|p| !p.is_empty())
                .unwrap_or_else(|| DEFAULT_SERVICE_PREFIX.to_string()),
        )
    }

    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// `<prefix>/cloud`: organised point clouds (and their "new cloud" event).
    pub fn cloud(&self) -> String {
        format!("{}/{}", self.prefix, CLOUD_SUFFIX)
    }

    /// `<prefix>/estimate`: slope estimates (and their "new estimate" event).
    pub fn estimate(&self) -> String {
        format!("{}/{}", self.prefix, ESTIMATE_SUFFIX)
    }

    /// `<prefix>/surfaces`: every surface of a frame with its role (and
    /// their "new surfaces" event).
    pub fn surfaces(&self) -> String {
        format!("{}/{}", self.prefix, SURFACES_SUFFIX)
    }

    /// `<prefix>/health`: the daemons' health reports (and their event).
    pub fn health(&self) -> String {
        format!("{}/{}", self.prefix, HEALTH_SUFFIX)
    }
}

impl Default for ServiceNames {
    fn default() -> Self {
        Self::new(DEFAULT_SERVICE_PREFIX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_carry_the_prefix() {
        let names = ServiceNames::new("test-42");
        assert_eq!(names.cloud(), "test-42/cloud");
        assert_eq!(names.estimate(), "test-42/estimate");
        assert_eq!(names.health(), "test-42/health");
        assert_eq!(names.surfaces(), "test-42/surfaces");
        assert_eq!(ServiceNames::default().cloud(), "slope/cloud");
    }
}
