//! The one place where numeric command-line options are checked.
//!
//! Every numeric option takes one of these parsers, so a value outside its finite range (NaN,
//! infinity, zero where zero is meaningless, a size that would allocate gigabytes) is refused
//! by the parser with the range in the message, before any work starts. Each option's `--help`
//! states the same range (a test checks that every numeric option's help says "range").
//! Negative numbers parse as values (`--blur -1` gives the range error, not clap's
//! "unexpected argument"): `main` enables that for every subcommand.

use std::fmt::Display;
use std::str::FromStr;

/// A parser of numbers accepted by `keep`; `range` says which in the error.
fn number<T>(
    keep: impl Fn(T) -> bool + Clone + Send + Sync + 'static,
    range: String,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + Display + Copy + Send + Sync + 'static,
    T::Err: Display,
{
    move |s: &str| {
        let v: T = s.trim().parse().map_err(|e| format!("`{s}` is not a number ({e})"))?;
        // NaN fails every comparison, so it is refused by any range.
        if keep(v) {
            Ok(v)
        } else {
            Err(format!("{s} is outside the range {range}"))
        }
    }
}

/// A parser of a number in `[lo, hi]` (both ends included).
pub fn within<T>(lo: T, hi: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
    T::Err: Display,
{
    number(move |v| v >= lo && v <= hi, format!("{lo}..={hi}"))
}

/// A parser of a number in `(lo, hi]`: above `lo`, at most `hi`.
pub fn above<T>(lo: T, hi: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
    T::Err: Display,
{
    number(move |v| v > lo && v <= hi, format!("({lo}, {hi}] (above {lo}, at most {hi})"))
}

/// A parser of a point `X,Y` of two finite numbers (pixels).
pub fn point(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<&str> = s.split(',').collect();
    if v.len() != 2 {
        return Err(format!("expected X,Y, got '{s}'"));
    }
    let p = |t: &str| t.trim().parse::<f64>().map_err(|e| format!("'{t}': {e}"));
    let (x, y) = (p(v[0])?, p(v[1])?);
    if !(x.is_finite() && y.is_finite()) {
        return Err(format!("'{s}' is not a finite point"));
    }
    Ok([x, y])
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn ends_nan_and_infinity() {
        let p = within(0.0f64, 1.0);
        assert_eq!(p("0"), Ok(0.0));
        assert_eq!(p("1"), Ok(1.0));
        for bad in ["-0.001", "1.0001", "NaN", "nan", "inf", "-inf", "1e30", "", "x", "0x1"] {
            assert!(p(bad).is_err(), "{bad}");
        }
        let q = above(0.0f64, 1e6);
        assert!(q("0").is_err() && q("-0").is_err() && q("1e-300").is_ok() && q("1e6").is_ok() && q("1e7").is_err());
        let n = within(1usize, 10);
        assert!(n("0").is_err() && n("-1").is_err() && n("1").is_ok() && n("11").is_err() && n("2.5").is_err());
    }

    proptest! {
        /// Whatever the text, the parser either refuses it or returns a value in the range
        /// that equals the text's own parse.
        #[test]
        fn accepted_values_lie_in_the_range(s in "\\PC{0,12}", lo in -1e3f64..1e3, span in 0.0f64..1e3) {
            let hi = lo + span;
            if let Ok(v) = within(lo, hi)(&s) {
                prop_assert!(v >= lo && v <= hi && v.is_finite());
                prop_assert_eq!(Some(v), s.trim().parse::<f64>().ok());
            }
            if let Ok(v) = above(lo, hi)(&s) {
                prop_assert!(v > lo && v <= hi);
            }
        }

        #[test]
        fn numbers_in_range_are_accepted(v in -1e3f64..1e3) {
            let text = format!("{v}");
            prop_assert_eq!(within(-1e3, 1e3)(&text), Ok(v));
            prop_assert_eq!(within(-1e3f64, 1e3)(&format!("{v:e}")), Ok(v));
        }
    }
}
