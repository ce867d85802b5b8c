//! Range checks shared by the stages' configuration structs: each stage's
//! `validate` names its own keys, [`crate::config::EstimatorConfig`] puts the
//! section in front (`ransac.` + `confidence`).

use std::borrow::Cow;

/// A configuration value out of its range: the key, the value and the range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}` = {value}: {reason}")]
pub struct InvalidValue {
    pub key: String,
    pub value: String,
    /// The range the value must be in (`must be at least 3`).
    pub reason: Cow<'static, str>,
}

impl InvalidValue {
    pub fn new(key: &str, value: impl ToString, reason: impl Into<Cow<'static, str>>) -> Self {
        Self {
            key: key.to_owned(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// The same error with `section.` in front of the key.
    pub fn in_section(mut self, section: &str) -> Self {
        self.key = format!("{section}.{}", self.key);
        self
    }
}

/// A finite number > 0.
pub fn positive(key: &str, v: f64) -> Result<(), InvalidValue> {
    check(
        v.is_finite() && v > 0.0,
        key,
        v,
        "must be a finite number > 0",
    )
}

/// A finite number >= 0.
pub fn non_negative(key: &str, v: f64) -> Result<(), InvalidValue> {
    check(
        v.is_finite() && v >= 0.0,
        key,
        v,
        "must be a finite number >= 0",
    )
}

/// An angle in 0..=180 degrees.
pub fn angle(key: &str, v: f64) -> Result<(), InvalidValue> {
    check(
        v.is_finite() && (0.0..=180.0).contains(&v),
        key,
        v,
        "must be an angle in 0..=180 degrees",
    )
}

/// A fraction in 0..=1.
pub fn fraction(key: &str, v: f64) -> Result<(), InvalidValue> {
    check(
        v.is_finite() && (0.0..=1.0).contains(&v),
        key,
        v,
        "must be in 0..=1",
    )
}

/// A count of at least `min`.
pub fn at_least(key: &str, v: usize, min: usize) -> Result<(), InvalidValue> {
    check(v >= min, key, v, format!("must be at least {min}"))
}

/// A count in `min..=max`: the upper bounds keep a mistyped count (an extra
/// zero or three) from stalling every frame past the service watchdog.
pub fn count_in(key: &str, v: usize, min: usize, max: usize) -> Result<(), InvalidValue> {
    check(
        (min..=max).contains(&v),
        key,
        v,
        format!("must be in {min}..={max}"),
    )
}

/// `Ok` when `ok`, else the error for `key` = `v`.
pub fn check(
    ok: bool,
    key: &str,
    v: impl ToString,
    reason: impl Into<Cow<'static, str>>,
) -> Result<(), InvalidValue> {
    if ok {
        Ok(())
    } else {
        Err(InvalidValue::new(key, v, reason))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_key_in_its_section() {
        let e = at_least("draws", 0, 1)
            .unwrap_err()
            .in_section("cumulative");
        assert_eq!(e.to_string(), "`cumulative.draws` = 0: must be at least 1");
        assert!(positive("x", f64::NAN).is_err());
        assert!(non_negative("x", 0.0).is_ok());
        assert!(angle("x", 180.5).is_err());
        assert!(fraction("x", 1.0).is_ok());
        assert_eq!(
            at_least("neighbours", 2, 3).unwrap_err().to_string(),
            "`neighbours` = 2: must be at least 3"
        );
        assert!(count_in("k", 3, 3, 10).is_ok() && count_in("k", 10, 3, 10).is_ok());
        assert_eq!(
            count_in("k", 11, 3, 10).unwrap_err().to_string(),
            "`k` = 11: must be in 3..=10"
        );
        assert!(count_in("k", 2, 3, 10).is_err());
    }
}
