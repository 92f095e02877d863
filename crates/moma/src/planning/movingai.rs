//! Moving AI Lab benchmark formats (Sturtevant 2012; Brewer & Sturtevant 2018):
//! 2-D `.map` / `.scen` and 3-D `.3dmap` / `.3dscen`.
//!
//! Readers accept LF and CRLF line endings, blank lines, and both scenario versions
//! (`version 1` with map width/height columns, `version 0` / no header without them).

use super::grid::{FREE, MapKind, OCCUPIED, OccupancyGrid, check_size};
use super::grid3::Grid3;
use crate::{Error, Result};
use std::path::Path;

fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    String::from_utf8(bytes).map_err(|_| Error::parse(path, "not a text file (invalid UTF-8)"))
}

/// Reads a Moving AI `.map`: `.` `G` `S` are passable, everything else (`@` `O` `T` `W`
/// ...) is an obstacle. x = column, y = row from the top.
pub fn load_movingai_map(path: &Path) -> Result<OccupancyGrid> {
    parse_movingai_map(&read_text(path)?, path)
}

/// Parses the text of a `.map` file; `path` only names the file in errors.
pub fn parse_movingai_map(text: &str, path: &Path) -> Result<OccupancyGrid> {
    let mut lines = text.lines().map(|l| l.trim_end_matches('\r')).enumerate();
    let mut width = None;
    let mut height = None;
    loop {
        let Some((n, line)) = lines.next() else {
            return Err(Error::parse(path, "missing 'map' line before the grid"));
        };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let mut it = line.split_whitespace();
        let key = it.next().unwrap_or("");
        let num = |name: &str, v: Option<&str>| -> Result<usize> {
            v.and_then(|s| s.parse().ok())
                .ok_or_else(|| Error::parse(path, format!("line {}: '{name}' needs a positive integer", n + 1)))
        };
        match key {
            "type" => {}
            "height" => height = Some(num("height", it.next())?),
            "width" => width = Some(num("width", it.next())?),
            "map" => break,
            other => return Err(Error::parse(path, format!("line {}: unexpected header '{other}'", n + 1))),
        }
    }
    let width = width.ok_or_else(|| Error::parse(path, "missing 'width' header"))?;
    let height = height.ok_or_else(|| Error::parse(path, "missing 'height' header"))?;
    check_size(width, height).map_err(|e| Error::parse(path, e.to_string()))?;
    let mut cells = Vec::with_capacity(width * height);
    let mut rows = 0;
    for (n, line) in lines {
        if line.is_empty() {
            continue;
        }
        if rows == height {
            return Err(Error::parse(path, format!("line {}: more than height = {height} rows", n + 1)));
        }
        if line.len() != width {
            return Err(Error::parse(
                path,
                format!("line {}: row {rows} has {} characters, expected width = {width}", n + 1, line.len()),
            ));
        }
        cells.extend(line.bytes().map(|b| if matches!(b, b'.' | b'G' | b'S') { FREE } else { OCCUPIED }));
        rows += 1;
    }
    if rows != height {
        return Err(Error::parse(path, format!("{rows} map rows, expected height = {height}")));
    }
    Ok(OccupancyGrid { width, height, resolution: 1.0, origin: [0.0; 3], cells, kind: MapKind::MovingAi })
}

/// One problem of a 2-D `.scen` file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ScenProblem {
    /// 0-based position among the file's problems (header and blank lines not counted).
    pub index: usize,
    /// Bucket column.
    pub bucket: u32,
    /// Map file named by the problem.
    pub map: String,
    /// Map width, if the file has the column (version 1).
    pub map_width: Option<usize>,
    /// Map height, if the file has the column (version 1).
    pub map_height: Option<usize>,
    /// Start cell (x, y).
    pub start: (usize, usize),
    /// Goal cell (x, y).
    pub goal: (usize, usize),
    /// Optimal path length given by the file.
    pub optimal: f64,
}

/// A parsed 2-D `.scen` file.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingAiScenario {
    /// Version number of the header (0 when the file has none).
    pub version: u32,
    /// Problems in file order.
    pub problems: Vec<ScenProblem>,
}

impl MovingAiScenario {
    /// Reads a `.scen` file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::parse(&read_text(path)?, path)
    }

    /// Parses the text of a `.scen` file; `path` only names the file in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let mut version = 0;
        let mut problems = Vec::new();
        let mut seen_header = false;
        let mut seen_version = false;
        for (n, line) in text.lines().enumerate() {
            let line = line.trim_end_matches('\r');
            if line.trim().is_empty() {
                continue;
            }
            if !seen_header && problems.is_empty() {
                seen_header = true;
                let t = line.trim();
                if let Some(v) = t.strip_prefix("version") {
                    let v = v.trim();
                    version = v
                        .parse::<f64>()
                        .map_err(|_| Error::parse(path, format!("line {}: bad version '{v}'", n + 1)))?
                        as u32;
                    seen_version = true;
                    continue;
                }
            }
            let f: Vec<&str> = if line.contains('\t') { line.split('\t').collect() } else { line.split_whitespace().collect() };
            let err = |what: &str| Error::parse(path, format!("line {}: {what}", n + 1));
            let (bucket, map, wh, rest) = match (f.len(), version) {
                (9, v) if v >= 1 || !seen_version => (f[0], f[1], Some((f[2], f[3])), &f[4..]),
                (7, 0) => (f[0], f[1], None, &f[2..]),
                (k, v) => {
                    let want = if v >= 1 { "9 (version 1)" } else { "7 (version 0) or 9" };
                    return Err(err(&format!("expected {want} tab-separated fields, got {k}")));
                }
            };
            let int = |s: &str, name: &str| -> Result<usize> {
                s.trim().parse::<usize>().map_err(|_| err(&format!("{name} '{s}' is not a non-negative integer")))
            };
            let optimal: f64 = rest[4].trim().parse().map_err(|_| err(&format!("optimal length '{}' is not a number", rest[4])))?;
            if !optimal.is_finite() || optimal < 0.0 {
                return Err(err("optimal length must be finite and non-negative"));
            }
            let (map_width, map_height) = match wh {
                Some((w, h)) => (Some(int(w, "width")?), Some(int(h, "height")?)),
                None => (None, None),
            };
            problems.push(ScenProblem {
                index: problems.len(),
                bucket: int(bucket, "bucket")? as u32,
                map: map.to_string(),
                map_width,
                map_height,
                start: (int(rest[0], "start x")?, int(rest[1], "start y")?),
                goal: (int(rest[2], "goal x")?, int(rest[3], "goal y")?),
                optimal,
            });
        }
        Ok(Self { version, problems })
    }
}

/// Reads a `.3dmap` (`voxel X Y Z`, then one blocked voxel `x y z` per line).
pub fn load_3dmap(path: &Path) -> Result<Grid3> {
    parse_3dmap(&read_text(path)?, path)
}

/// Parses the text of a `.3dmap`; `path` only names the file in errors.
pub fn parse_3dmap(text: &str, path: &Path) -> Result<Grid3> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| Error::parse(path, "empty file"))?;
    let h: Vec<&str> = header.split_whitespace().collect();
    if h.len() != 4 || h[0] != "voxel" {
        return Err(Error::parse(path, "line 1: expected 'voxel X Y Z'"));
    }
    let dim = |s: &str| s.parse::<usize>().ok().filter(|&v| v > 0).ok_or_else(|| Error::parse(path, format!("line 1: bad size '{s}'")));
    let mut grid = Grid3::new(dim(h[1])?, dim(h[2])?, dim(h[3])?).map_err(|e| Error::parse(path, e.to_string()))?;
    for (n, line) in lines {
        let mut it = line.split_whitespace().map(|s| s.parse::<usize>());
        match (it.next(), it.next(), it.next(), it.next()) {
            (Some(Ok(x)), Some(Ok(y)), Some(Ok(z)), None) => {
                if x >= grid.nx || y >= grid.ny || z >= grid.nz {
                    return Err(Error::parse(path, format!("line {}: voxel ({x}, {y}, {z}) outside the map", n + 1)));
                }
                grid.set_blocked(x, y, z, true);
            }
            _ => return Err(Error::parse(path, format!("line {}: expected 'x y z'", n + 1))),
        }
    }
    Ok(grid)
}

/// One problem of a `.3dscen` file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Scen3Problem {
    /// 0-based position among the file's problems.
    pub index: usize,
    /// Start voxel.
    pub start: (usize, usize, usize),
    /// Goal voxel.
    pub goal: (usize, usize, usize),
    /// Optimal length given by the file.
    pub optimal: f64,
    /// Ratio optimal / heuristic given by the file.
    pub ratio: f64,
}

/// Reads a `.3dscen` (`version 1`, map name, then `sx sy sz gx gy gz length ratio`).
pub fn load_3dscen(path: &Path) -> Result<Vec<Scen3Problem>> {
    parse_3dscen(&read_text(path)?, path)
}

/// Parses the text of a `.3dscen`; `path` only names the file in errors.
pub fn parse_3dscen(text: &str, path: &Path) -> Result<Vec<Scen3Problem>> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() || f[0] == "version" || f.len() == 1 {
            continue;
        }
        let err = |what: &str| Error::parse(path, format!("line {}: {what}", n + 1));
        if f.len() != 8 {
            return Err(err(&format!("expected 8 fields 'sx sy sz gx gy gz length ratio', got {}", f.len())));
        }
        let int = |s: &str| s.parse::<usize>().map_err(|_| err(&format!("'{s}' is not a non-negative integer")));
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| err(&format!("'{s}' is not a number")));
        out.push(Scen3Problem {
            index: out.len(),
            start: (int(f[0])?, int(f[1])?, int(f[2])?),
            goal: (int(f[3])?, int(f[4])?, int(f[5])?),
            optimal: num(f[6])?,
            ratio: num(f[7])?,
        });
    }
    Ok(out)
}
