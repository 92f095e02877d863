//! The results table: typed cells, CSV out and in, and the merge of shard tables.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};

/// One cell of a results table.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// An integer (the index, counts, edge numbers).
    Int(i64),
    /// A number.
    Float(f64),
    /// A flag.
    Bool(bool),
    /// A name, or the text of a cell read back from a CSV file.
    Text(String),
    /// No value (an undefined measure); an empty CSV cell.
    Missing,
}

impl Value {
    /// `Some(x)` as a float, `None` as [`Value::Missing`].
    #[must_use]
    pub fn opt(x: Option<f64>) -> Self {
        x.map_or(Value::Missing, Value::Float)
    }

    /// The cell's CSV text: floats in Rust's shortest round-trip form (`1.0`, `0.25`,
    /// `1e-7`), flags as `true` / `false`, missing as the empty string.
    #[must_use]
    pub fn to_text(&self) -> String {
        match self {
            Value::Int(i) => i.to_string(),
            Value::Float(f) => format!("{f:?}"),
            Value::Bool(b) => b.to_string(),
            Value::Text(s) => s.clone(),
            Value::Missing => String::new(),
        }
    }
}

/// A results table: the column names and the rows (each as long as `columns`, its first
/// cell the point index), sorted by index.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Table {
    /// Column names: `index`, parameters, results, timing (`*_time_s`) last.
    pub columns: Vec<String>,
    /// Rows sorted by index.
    pub rows: Vec<Vec<Value>>,
}

fn push_field(out: &mut String, s: &str) {
    if s.contains([',', '"', '\n', '\r']) {
        out.push('"');
        out.push_str(&s.replace('"', "\"\""));
        out.push('"');
    } else {
        out.push_str(s);
    }
}

impl Table {
    /// The index of every row.
    #[must_use]
    pub fn indices(&self) -> Vec<u64> {
        self.rows
            .iter()
            .map(|r| match r.first() {
                Some(Value::Int(i)) => *i as u64,
                _ => u64::MAX,
            })
            .collect()
    }

    /// Position of column `name`.
    #[must_use]
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The table as CSV text (RFC 4180: one header line, `\n` line ends, fields with a
    /// comma, quote or line break quoted).
    #[must_use]
    pub fn to_csv(&self) -> String {
        let mut out = String::with_capacity(64 * (self.rows.len() + 1));
        for (k, c) in self.columns.iter().enumerate() {
            if k > 0 {
                out.push(',');
            }
            push_field(&mut out, c);
        }
        out.push('\n');
        for r in &self.rows {
            for (k, v) in r.iter().enumerate() {
                if k > 0 {
                    out.push(',');
                }
                match v {
                    Value::Float(f) => {
                        let _ = write!(out, "{f:?}");
                    }
                    Value::Int(i) => {
                        let _ = write!(out, "{i}");
                    }
                    other => push_field(&mut out, &other.to_text()),
                }
            }
            out.push('\n');
        }
        out
    }

    /// The table without its timing columns (those named `*_time_s`): the part that is
    /// identical whatever the threads and shards.
    #[must_use]
    pub fn without_timing(&self) -> Table {
        let keep: Vec<usize> = (0..self.columns.len())
            .filter(|&k| !self.columns[k].ends_with("_time_s"))
            .collect();
        Table {
            columns: keep.iter().map(|&k| self.columns[k].clone()).collect(),
            rows: self
                .rows
                .iter()
                .map(|r| keep.iter().map(|&k| r[k].clone()).collect())
                .collect(),
        }
    }

    /// Writes the CSV to `path` atomically (a temporary sibling renamed into place).
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be written.
    pub fn write_csv(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let name = path
            .file_name()
            .map_or_else(|| "table.csv".into(), |n| n.to_string_lossy().into_owned());
        let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        std::fs::write(&tmp, self.to_csv()).map_err(io)?;
        std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            io(e)
        })
    }

    /// Reads a table written by [`Table::write_csv`]. The index column is read as
    /// integers; every other cell keeps its text ([`Value::Text`], empty as
    /// [`Value::Missing`]), so a merged table writes each cell exactly as it was read.
    ///
    /// # Errors
    /// [`Error::Io`]; [`Error::Parse`] naming the file and line for a malformed table
    /// (no `index` first column, a row of the wrong width, a bad index, a bad quote).
    pub fn read_csv(path: impl AsRef<Path>) -> Result<Table> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse_csv(&text, path)
    }

    /// Parses CSV `text` (see [`Table::read_csv`]); `path` names it in errors.
    ///
    /// # Errors
    /// As [`Table::read_csv`].
    pub fn parse_csv(text: &str, path: &Path) -> Result<Table> {
        let records = parse_records(text, path)?;
        let mut it = records.into_iter();
        let (_, columns) = it
            .next()
            .ok_or_else(|| Error::parse(path, "empty table (no header line)"))?;
        if columns.first().map(String::as_str) != Some("index") {
            return Err(Error::parse(
                path,
                "line 1: the first column must be 'index'",
            ));
        }
        let mut rows = Vec::new();
        for (line, rec) in it {
            if rec.len() != columns.len() {
                return Err(Error::parse(
                    path,
                    format!(
                        "line {line}: {} fields, the header has {}",
                        rec.len(),
                        columns.len()
                    ),
                ));
            }
            let mut row = Vec::with_capacity(rec.len());
            for (k, cell) in rec.into_iter().enumerate() {
                if k == 0 {
                    let i: i64 = cell.parse().ok().filter(|&i: &i64| i >= 0).ok_or_else(|| {
                        Error::parse(
                            path,
                            format!("line {line}: index '{cell}' is not a non-negative integer"),
                        )
                    })?;
                    row.push(Value::Int(i));
                } else if cell.is_empty() {
                    row.push(Value::Missing);
                } else {
                    row.push(Value::Text(cell));
                }
            }
            rows.push(row);
        }
        Ok(Table { columns, rows })
    }
}

/// CSV records with their (1-based) starting line numbers.
fn parse_records(text: &str, path: &Path) -> Result<Vec<(usize, Vec<String>)>> {
    let mut out = Vec::new();
    let mut line = 1;
    let mut chars = text.chars().peekable();
    while chars.peek().is_some() {
        let start = line;
        let mut rec = Vec::new();
        let mut field = String::new();
        loop {
            match chars.next() {
                None => {
                    rec.push(std::mem::take(&mut field));
                    break;
                }
                Some('"') if field.is_empty() => loop {
                    match chars.next() {
                        None => {
                            return Err(Error::parse(
                                path,
                                format!("line {start}: unterminated quote"),
                            ));
                        }
                        Some('"') if chars.peek() == Some(&'"') => {
                            chars.next();
                            field.push('"');
                        }
                        Some('"') => break,
                        Some(c) => {
                            if c == '\n' {
                                line += 1;
                            }
                            field.push(c);
                        }
                    }
                },
                Some(',') => rec.push(std::mem::take(&mut field)),
                Some('\r') if chars.peek() == Some(&'\n') => {}
                Some('\n') => {
                    line += 1;
                    rec.push(std::mem::take(&mut field));
                    break;
                }
                Some(c) => field.push(c),
            }
        }
        if !(rec.len() == 1 && rec[0].is_empty()) {
            out.push((start, rec));
        }
    }
    Ok(out)
}

/// Joins shard tables: equal headers, disjoint indices that together are exactly
/// `0 .. n` (n the total number of rows), rows sorted by index. `names` names the
/// tables in errors (e.g. their files).
///
/// # Errors
/// [`Error::InvalidInput`] for no table, a header that differs from the first table's,
/// an index found in two tables, or a missing index (naming the first one).
pub fn merge(tables: Vec<Table>, names: &[String]) -> Result<Table> {
    let name = |k: usize| {
        names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("table {k}"))
    };
    let Some(first) = tables.first() else {
        return Err(Error::invalid("merge", "no table to merge"));
    };
    let columns = first.columns.clone();
    for (k, t) in tables.iter().enumerate().skip(1) {
        if t.columns != columns {
            return Err(Error::invalid(
                format!("merge: {}", name(k)),
                format!("header differs from {}'s", name(0)),
            ));
        }
    }
    let total: usize = tables.iter().map(|t| t.rows.len()).sum();
    let mut owner: Vec<Option<usize>> = vec![None; total];
    let mut rows: Vec<Option<Vec<Value>>> = vec![None; total];
    for (k, t) in tables.into_iter().enumerate() {
        for r in t.rows {
            let i = match r.first() {
                Some(Value::Int(i)) if *i >= 0 => *i as u64,
                _ => {
                    return Err(Error::invalid(
                        format!("merge: {}", name(k)),
                        "a row without an index",
                    ));
                }
            };
            if i >= total as u64 {
                return Err(Error::invalid(
                    format!("merge: {}", name(k)),
                    format!(
                        "index {i} is outside 0..{total} (the merged rows): some shard is missing"
                    ),
                ));
            }
            let i = i as usize;
            if let Some(o) = owner[i] {
                return Err(Error::invalid(
                    format!("merge: {}", name(k)),
                    format!("index {i} is also in {}", name(o)),
                ));
            }
            owner[i] = Some(k);
            rows[i] = Some(r);
        }
    }
    // Every slot is filled: total rows, all distinct and below total.
    Ok(Table {
        columns,
        rows: rows.into_iter().map(|r| r.expect("filled")).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(idx: &[i64]) -> Table {
        Table {
            columns: vec!["index".into(), "a,b".into(), "x".into()],
            rows: idx
                .iter()
                .map(|&i| {
                    vec![
                        Value::Int(i),
                        Value::Text(format!("n\"{i}\"")),
                        Value::Float(i as f64 * 0.1),
                    ]
                })
                .collect(),
        }
    }

    #[test]
    fn csv_round_trip_keeps_the_text() {
        let mut a = t(&[0, 2]);
        a.rows[1][2] = Value::Missing;
        let csv = a.to_csv();
        assert!(
            csv.starts_with("index,\"a,b\",x\n0,\"n\"\"0\"\"\",0.0\n"),
            "{csv}"
        );
        let b = Table::parse_csv(&csv, Path::new("t.csv")).unwrap();
        assert_eq!(b.to_csv(), csv);
        assert_eq!(b.rows[1][2], Value::Missing);
    }

    #[test]
    fn merge_checks_headers_overlap_and_holes() {
        let names: Vec<String> = vec!["s1.csv".into(), "s2.csv".into()];
        let m = merge(vec![t(&[1, 3]), t(&[2, 0])], &names).unwrap();
        assert_eq!(m.indices(), [0, 1, 2, 3]);
        let e = merge(vec![t(&[1, 3]), t(&[3, 0])], &names)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s2.csv") && e.contains("index 3 is also in s1.csv"),
            "{e}"
        );
        let e = merge(vec![t(&[0, 3]), t(&[1])], &names)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing"), "{e}");
        let mut other = t(&[1]);
        other.columns[2] = "y".into();
        let e = merge(vec![t(&[0]), other], &names).unwrap_err().to_string();
        assert!(e.contains("s2.csv") && e.contains("header"), "{e}");
    }

    #[test]
    fn malformed_csv_names_the_line() {
        let e = Table::parse_csv("index,x\n0,1\n1\n", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.csv") && e.contains("line 3"), "{e}");
        let e = Table::parse_csv("x\n", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'index'"), "{e}");
        let e = Table::parse_csv("index,x\n-1,2\n", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2"), "{e}");
    }
}
