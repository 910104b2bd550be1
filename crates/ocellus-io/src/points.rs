//! Fixation points (or any 2D image points) as CSV text.
//!
//! One point per line, `x,y` in pixels of the stimulus: x to the right, y down, origin at the
//! top-left corner, pixel centres at integer coordinates (so `3,5` is the pixel in column 3,
//! row 5, and `3.4,5.6` rounds to it). Separators may be commas, semicolons, tabs or spaces.
//! A line must hold exactly the two numbers: further columns (a subject id, a duration) are an
//! error, not silently dropped, so a file of another layout is never misread. Blank lines and
//! lines starting with `#` are skipped, and so is a first line with a field that is not a
//! number (a header); see [`crate::csv`].

use crate::{read_bytes, Result};
use std::path::Path;

/// Reads a CSV file of points; see the module documentation for the format.
pub fn read_points(path: impl AsRef<Path>) -> Result<Vec<[f64; 2]>> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    parse(&bytes, path)
}

/// Parses CSV text of points; `path` only names the source in errors.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Vec<[f64; 2]>> {
    let rows = crate::csv::parse_rows(bytes, path, 2, "'x,y' in pixels")?;
    Ok(rows.into_iter().map(|r| [r[0], r[1]]).collect())
}

/// The pixels (column, row) holding `points`, for an image of `width` x `height`: each point
/// rounds to its nearest pixel centre; points outside the image are dropped.
pub fn to_pixels(points: &[[f64; 2]], width: usize, height: usize) -> Vec<(usize, usize)> {
    points
        .iter()
        .filter_map(|&[x, y]| {
            let (cx, cy) = (x.round(), y.round());
            let inside = cx >= 0.0 && cy >= 0.0 && cx < width as f64 && cy < height as f64;
            inside.then_some((cx as usize, cy as usize))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(s: &str) -> Result<Vec<[f64; 2]>> {
        parse(s.as_bytes(), Path::new("t.csv"))
    }

    #[test]
    fn header_comments_separators_and_extra_columns() {
        let v = p("x,y\n# a comment\n1,2\n\n3.5;4\n5\t6\n 7 8 \n").unwrap();
        assert_eq!(v, vec![[1.0, 2.0], [3.5, 4.0], [5.0, 6.0], [7.0, 8.0]]);
        let e = p("x,y,subject\n1,2,7\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("got 3"), "{e}");
    }

    #[test]
    fn bad_lines_are_errors_with_line_numbers() {
        let e = p("1,2\n3,abc\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        assert!(p("1,2\nNaN,3\n").unwrap_err().to_string().contains("non-finite"));
        assert!(p("1\n").is_err(), "a short first line of numbers is data, not a header");
        assert!(p("x\n").unwrap().is_empty(), "a lone word is a header");
        assert!(p("1,2\n7\n").is_err());
        assert!(parse(&[0xff, 0xfe], Path::new("t.csv")).is_err());
    }

    #[test]
    fn pixels_round_to_centres_and_drop_outside() {
        let px = to_pixels(&[[0.4, 0.6], [-0.4, 0.0], [-0.6, 0.0], [9.49, 4.0], [9.5, 4.0], [2.0, 5.0]], 10, 5);
        assert_eq!(px, vec![(0, 1), (0, 0), (9, 4)]);
    }
}
