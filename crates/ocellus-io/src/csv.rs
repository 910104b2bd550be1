//! Numeric CSV rows, the format of every small table ocellus reads (fixation points, camera
//! angles, correspondences, matches).
//!
//! Each data line holds exactly `columns` numbers: a line with more or fewer fields is an
//! error naming the line (a silently cut row would hide a file of another layout). Separators
//! may be commas, semicolons, tabs or spaces. Blank lines and lines starting with `#` are
//! skipped, and so is a first content line with a field that is not a number (a header); a
//! first line of numbers is data, however many. Any other malformed line, or a non-finite
//! number, is an error naming the line.

use crate::{read_bytes, IoError, Result};
use std::path::Path;

/// Reads the rows of a CSV file; `expected` describes a row for error messages (e.g.
/// `"'x,y' in pixels"`).
pub fn read_rows(path: impl AsRef<Path>, columns: usize, expected: &str) -> Result<Vec<Vec<f64>>> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    parse_rows(&bytes, path, columns, expected)
}

/// Parses CSV text into rows of `columns` numbers; `path` only names the source.
pub fn parse_rows(bytes: &[u8], path: &Path, columns: usize, expected: &str) -> Result<Vec<Vec<f64>>> {
    let invalid = |reason: String| IoError::Invalid { path: path.into(), reason };
    let text = std::str::from_utf8(bytes).map_err(|e| invalid(format!("not UTF-8 text: {e}")))?;
    let mut rows = Vec::new();
    let mut first_content_line = true;
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields = line.split([',', ';', '\t', ' ']).map(str::trim).filter(|f| !f.is_empty());
        let values: Vec<Option<f64>> = fields.map(|f| f.parse().ok()).collect();
        let numeric = values.iter().all(Option::is_some);
        if first_content_line && !numeric {
            first_content_line = false;
            continue; // a header
        }
        first_content_line = false;
        if !numeric {
            return Err(invalid(format!("line {}: expected {expected}, got '{line}'", n + 1)));
        }
        if values.len() != columns {
            return Err(invalid(format!(
                "line {}: expected {expected} ({columns} numbers), got {} in '{line}'",
                n + 1,
                values.len()
            )));
        }
        let row: Vec<f64> = values.into_iter().flatten().collect();
        if row.iter().any(|v| !v.is_finite()) {
            return Err(invalid(format!("line {}: non-finite number in '{line}'", n + 1)));
        }
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_header_comments_and_errors() {
        let p = |s: &str, c| parse_rows(s.as_bytes(), Path::new("t.csv"), c, "three numbers");
        assert_eq!(p("a,b,c\n# x\n1 2 3\n\n4;5;6\n", 3).unwrap(), vec![vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]]);
        // Extra columns are not cut, and a short first line of numbers is not a header.
        let e = p("1,2,3,9\n", 3).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("got 4"), "{e}");
        assert!(p("1,2\n3,4,5\n", 3).unwrap_err().to_string().contains("line 1"));
        assert!(p("x,y\n1,2,3\n", 3).is_ok());
        let e = p("1,2,3\n4,5\n", 3).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("three numbers"), "{e}");
        assert!(p("1,2,inf\n", 3).unwrap_err().to_string().contains("non-finite"));
        assert!(parse_rows(&[0xff], Path::new("t.csv"), 1, "x").is_err());
    }
}
