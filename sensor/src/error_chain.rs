//! [`ErrorChain`]: an error and its causes on one line, for logs.
//!
//! Our error types name their cause through `source()` only, never in their
//! own message as well (a report printing the chain would repeat it); a log
//! line that wants the whole story formats the chain.

use std::fmt;

/// Displays `error: cause: cause ...`.
pub struct ErrorChain<'a>(pub &'a (dyn std::error::Error + 'static));

impl fmt::Display for ErrorChain<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)?;
        let mut cause = self.0.source();
        while let Some(c) = cause {
            write!(f, ": {c}")?;
            cause = c.source();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("cannot read frames.csv")]
    struct Outer(#[source] std::io::Error);

    #[test]
    fn every_cause_once() {
        let e = Outer(std::io::Error::other("disk on fire"));
        assert_eq!(
            ErrorChain(&e).to_string(),
            "cannot read frames.csv: disk on fire"
        );
    }
}
