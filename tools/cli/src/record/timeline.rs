//! The recording's timestamps from a source's stamps ([`Timeline`]).

/// Recording timestamps from a source's stamps: starting at 0 and
/// following the source, but never going backwards. When the source's
/// clock jumps back (a restarted device, a looped replay), the timeline is
/// rebased: that frame comes one previous frame interval after the last,
/// and later frames follow the source from there. So stamps neither freeze
/// nor repeat, and a replay keeps the original pace.
pub(super) struct Timeline {
    /// The last source stamp and the timestamp it became.
    last: Option<(u64, u64)>,
    /// The last forward step, used across a jump back.
    step_ns: u64,
}

impl Timeline {
    pub(super) fn new() -> Self {
        Self {
            last: None,
            step_ns: 1,
        }
    }

    pub(super) fn stamp(&mut self, source_stamp_ns: u64) -> u64 {
        let out = match self.last {
            None => 0,
            Some((last_source, last_out)) if source_stamp_ns >= last_source => {
                let step = source_stamp_ns - last_source;
                if step > 0 {
                    self.step_ns = step;
                }
                last_out.saturating_add(step)
            }
            Some((last_source, last_out)) => {
                tracing::warn!(
                    source_ns = source_stamp_ns,
                    previous_ns = last_source,
                    "source clock went backwards; continuing the recording's time"
                );
                last_out.saturating_add(self.step_ns)
            }
        };
        self.last = Some((source_stamp_ns, out));
        out
    }
}
