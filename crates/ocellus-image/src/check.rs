//! Range checks of named parameters, the one wording every crate's configuration errors use:
//! the parameter's name, its value and the range it must lie in ("update_factor = 1.5 is
//! outside (0, 1)"). Each returns the message, which the caller wraps in its own error type;
//! [`same_size`] returns the typed size error.
//! NaN fails every check.

use crate::ImageError;
use std::fmt::Display;

/// `got` (width, height) equals `want`, else [`ImageError::SizeMismatch`] naming `what`: the
/// one "wrong size" error of the workspace (other crates wrap it with `#[from]`, so a caller
/// matches `Image(ImageError::SizeMismatch { .. })` whichever crate reported it).
pub fn same_size(what: &'static str, got: (usize, usize), want: (usize, usize)) -> Result<(), ImageError> {
    if got == want {
        return Ok(());
    }
    Err(ImageError::SizeMismatch { what, got_w: got.0, got_h: got.1, want_w: want.0, want_h: want.1 })
}

/// `v` in `[lo, hi]`.
pub fn within<T: PartialOrd + Display + Copy>(name: &str, v: T, lo: T, hi: T) -> Result<(), String> {
    if v >= lo && v <= hi {
        Ok(())
    } else {
        Err(format!("{name} = {v} is outside [{lo}, {hi}]"))
    }
}

/// `v` in `(lo, hi)`.
pub fn between<T: PartialOrd + Display + Copy>(name: &str, v: T, lo: T, hi: T) -> Result<(), String> {
    if v > lo && v < hi {
        Ok(())
    } else {
        Err(format!("{name} = {v} is outside ({lo}, {hi})"))
    }
}

/// `v` finite and above 0.
pub fn positive<T: Into<f64> + Copy + Display>(name: &str, v: T) -> Result<(), String> {
    let x: f64 = v.into();
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} = {v} must be finite and above 0"))
    }
}

/// `v` finite and at least 0.
pub fn non_negative<T: Into<f64> + Copy + Display>(name: &str, v: T) -> Result<(), String> {
    let x: f64 = v.into();
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(format!("{name} = {v} must be finite and at least 0"))
    }
}

/// `v` finite.
pub fn finite<T: Into<f64> + Copy + Display>(name: &str, v: T) -> Result<(), String> {
    if v.into().is_finite() {
        Ok(())
    } else {
        Err(format!("{name} = {v} must be finite"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Each check accepts exactly the values of its range, whatever the bits of the number.
        #[test]
        fn checks_accept_exactly_their_range(bits in any::<u64>(), lo in -1e6f64..1e6, span in 0.0f64..1e6) {
            let v = f64::from_bits(bits);
            let hi = lo + span;
            prop_assert_eq!(within("v", v, lo, hi).is_ok(), v >= lo && v <= hi);
            prop_assert_eq!(between("v", v, lo, hi).is_ok(), v > lo && v < hi);
            prop_assert_eq!(positive("v", v).is_ok(), v.is_finite() && v > 0.0);
            prop_assert_eq!(non_negative("v", v).is_ok(), v.is_finite() && v >= 0.0);
            prop_assert_eq!(finite("v", v).is_ok(), v.is_finite());
            if let Err(m) = within("the_name", v, lo, hi) {
                prop_assert!(m.starts_with("the_name = "));
            }
        }
    }

    #[test]
    fn messages_name_the_parameter_and_nan_fails() {
        assert!(within("a", 0.5, 0.0, 1.0).is_ok() && within("a", 1.0, 0.0, 1.0).is_ok());
        assert_eq!(within("alpha", 2.0, 0.0, 1.0).unwrap_err(), "alpha = 2 is outside [0, 1]");
        assert!(between("a", 1.0, 0.0, 1.0).is_err() && between("a", f64::NAN, 0.0, 1.0).is_err());
        assert!(positive("s", 0.0f32).unwrap_err().starts_with("s = 0"));
        assert!(positive("s", f64::INFINITY).is_err() && positive("s", 1e-300).is_ok());
        assert!(non_negative("n", 0.0).is_ok() && non_negative("n", -1e-9).is_err());
        assert!(finite("x", f32::NAN).is_err() && finite("x", -3.0).is_ok());
        assert!(within("k", 3usize, 1, 16).is_ok() && within("k", 17usize, 1, 16).is_err());
    }
}
