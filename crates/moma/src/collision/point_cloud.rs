//! Point clouds from text files, for binning into voxels
//! ([`point_cloud_object`](super::scene::point_cloud_object)): one point per line as
//! `x y z` or `x,y,z` (metres, world frame), blank lines and lines starting with `#`
//! skipped — the plain `.xyz` export of point-cloud tools.

use crate::{Error, Result};
use nalgebra::Vector3;
use std::path::Path;

/// Reads a point-cloud text file.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read; [`Error::Parse`] naming the file and the line
/// of a line without exactly three numbers or with a non-finite one, or a file without
/// points.
pub fn read_points(path: &Path) -> Result<Vec<Vector3<f64>>> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_points(&text, path)
}

/// Parses the text of a point-cloud file; `path` only names the file in errors.
///
/// # Errors
/// As [`read_points`].
pub fn parse_points(text: &str, path: &Path) -> Result<Vec<Vector3<f64>>> {
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        let bad = || {
            Error::parse(
                path,
                format!("line {}: expected 'x y z', got '{line}'", n + 1),
            )
        };
        if fields.len() != 3 {
            return Err(bad());
        }
        let mut p = Vector3::zeros();
        for (k, f) in fields.iter().enumerate() {
            p[k] = f.parse::<f64>().map_err(|_| bad())?;
            if !p[k].is_finite() {
                return Err(Error::parse(
                    path,
                    format!("line {}: coordinate '{f}' is not finite", n + 1),
                ));
            }
        }
        points.push(p);
    }
    if points.is_empty() {
        return Err(Error::parse(path, "no point"));
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_spaces_commas_and_comments_and_names_the_bad_line() {
        let p = Path::new("cloud.xyz");
        let pts = parse_points("# cloud\n1 2 3\n\n4.5,-1,0\n", p).unwrap();
        assert_eq!(
            pts,
            vec![Vector3::new(1.0, 2.0, 3.0), Vector3::new(4.5, -1.0, 0.0)]
        );
        let e = parse_points("1 2 3\n1 2\n", p).unwrap_err().to_string();
        assert!(e.contains("cloud.xyz") && e.contains("line 2"), "{e}");
        let e = parse_points("1 nan 3\n", p).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("not finite"), "{e}");
        assert!(
            parse_points("# none\n", p)
                .unwrap_err()
                .to_string()
                .contains("no point")
        );
    }
}
