//! Clouds `slope-estimator` refuses ([`slope_sensor::cloud_checks`]: a
//! header that lies about the size, the intrinsics or the mount, or a
//! cloud over `--max-points`), logged at WARN without flooding the log.
//!
//! The first refusal is logged at once; after it at most one line every
//! [`WARN_EVERY`], which says how many more were refused since the last
//! line. Health counts every one (`errors`, `last_error`): see
//! `estimator.rs`.

use std::time::{Duration, Instant};

use slope_sensor::cloud_checks::CloudCheckError;

/// The shortest time between two WARN lines about refused clouds.
pub const WARN_EVERY: Duration = Duration::from_secs(10);

/// Counts refused clouds and decides which are logged.
#[derive(Debug, Default)]
pub struct RejectedClouds {
    /// Refused since the start.
    pub total: u64,
    /// When the last WARN line went out.
    last_warn: Option<Instant>,
    /// Refused since the last WARN line, not logged.
    unlogged: u64,
}

impl RejectedClouds {
    /// Counts the refusal of cloud `frame` at `now`; the WARN line to log,
    /// when one is due.
    pub fn refused(&mut self, frame: u64, err: &CloudCheckError, now: Instant) -> Option<String> {
        self.total += 1;
        let due = self
            .last_warn
            .is_none_or(|last| now.duration_since(last) >= WARN_EVERY);
        if !due {
            self.unlogged += 1;
            return None;
        }
        let more = match self.unlogged {
            0 => String::new(),
            n => format!(" ({n} more refused since the last warning)"),
        };
        self.last_warn = Some(now);
        self.unlogged = 0;
        Some(format!(
            "refused cloud {frame}: {err}; answered as bad_frame{more}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1,000 refusals in 25 s: three WARN lines (at 0, 10 and 20 s), the
    /// later ones counting those not logged; all 1,000 counted.
    #[test]
    fn refusals_are_logged_once_per_interval_and_all_counted() {
        let start = Instant::now();
        let err = CloudCheckError::Empty {
            width: 0,
            height: 4,
        };
        let mut rejected = RejectedClouds::default();
        let lines: Vec<(u64, String)> = (0..1000u64)
            .filter_map(|k| {
                let at = start + Duration::from_millis(k * 25);
                rejected.refused(k, &err, at).map(|line| (k, line))
            })
            .collect();
        assert_eq!(rejected.total, 1000);
        let frames: Vec<u64> = lines.iter().map(|(k, _)| *k).collect();
        assert_eq!(frames, [0, 400, 800]);
        assert_eq!(
            lines[0].1,
            "refused cloud 0: the header says 0 x 4: an empty image; answered as bad_frame"
        );
        assert!(
            lines[1]
                .1
                .ends_with("(399 more refused since the last warning)"),
            "{}",
            lines[1].1
        );
    }
}
