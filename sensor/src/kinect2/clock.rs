//! The device's 32-bit clock as a 64-bit time that never goes backwards:
//! pure arithmetic on the stamps libfreenect2 reports.

// Without the `kinect2` feature only the tests use the clock.
#![cfg_attr(not(feature = "kinect2"), allow(dead_code))]

use std::time::Duration;

/// Units of the device clock.
const DEVICE_TICK_NS: u64 = 125_000;

/// Turns the device's 32-bit clock (0.125 ms units; wraps after about 6.2
/// days, restarts when the device does) into a 64-bit nanosecond time that
/// never goes backwards.
#[derive(Debug, Default)]
pub(crate) struct DeviceClock {
    /// The last raw stamp and the time it became.
    last: Option<(u32, u64)>,
    /// Set by [`DeviceClock::restart`]: the next stamp continues the time
    /// by this gap, whatever the device's clock says.
    restart_gap_ns: Option<u64>,
}

impl DeviceClock {
    pub(crate) fn stamp(&mut self, raw: u32) -> u64 {
        let ns = match (self.last, self.restart_gap_ns.take()) {
            (None, _) => u64::from(raw) * DEVICE_TICK_NS,
            (Some((_, last_ns)), Some(gap)) => last_ns.saturating_add(gap.max(1)),
            (Some((last_raw, last_ns)), None) => {
                // The forward distance modulo 2^32 ticks, so a wrap just
                // continues; a "forward" jump of more than half the range
                // is the clock going backwards (a reset): one tick on.
                let ahead = raw.wrapping_sub(last_raw);
                if ahead < 1 << 31 {
                    last_ns.saturating_add(u64::from(ahead) * DEVICE_TICK_NS)
                } else {
                    tracing::warn!(raw, last_raw, "the Kinect v2 clock went backwards");
                    last_ns.saturating_add(DEVICE_TICK_NS)
                }
            }
        };
        self.last = Some((raw, ns));
        ns
    }

    /// The device was reopened (its clock restarts): the next stamp is the
    /// last one plus `gap`.
    pub(crate) fn restart(&mut self, gap: Duration) {
        self.restart_gap_ns = Some(u64::try_from(gap.as_nanos()).unwrap_or(u64::MAX));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TICK: u64 = DEVICE_TICK_NS;

    #[test]
    fn the_device_clock_runs_on_through_a_wrap() {
        let mut clock = DeviceClock::default();
        let start = u32::MAX - 266;
        let first = clock.stamp(start);
        assert_eq!(first, u64::from(start) * TICK);
        // 266 ticks later the u32 has wrapped to 0; then 266 more.
        assert_eq!(clock.stamp(u32::MAX), first + 266 * TICK);
        assert_eq!(clock.stamp(266), first + 533 * TICK);
        assert_eq!(clock.stamp(532), first + 799 * TICK);
    }

    #[test]
    fn the_device_clock_never_goes_back() {
        let mut clock = DeviceClock::default();
        assert_eq!(clock.stamp(10_000), 10_000 * TICK);
        // A reset without a reopen: one tick on, then onwards from there.
        assert_eq!(clock.stamp(100), 10_001 * TICK);
        assert_eq!(clock.stamp(366), 10_267 * TICK);
        // A reopen: the gap in wall time, whatever the new clock says.
        clock.restart(Duration::from_millis(1500));
        let after = clock.stamp(5);
        assert_eq!(after, 10_267 * TICK + 1_500_000_000);
        assert_eq!(clock.stamp(271), after + 266 * TICK);
    }
}
