//! Writing outputs all or nothing. A single file is written to a temporary sibling and
//! renamed into place; a set of files given by path is staged the same way and renamed
//! only once every one of them is written; an output *directory* (`simulate`) is built
//! as a temporary directory beside the target and renamed into place in one step, so a
//! run that fails leaves no file and no new directory behind, and a rerun replaces the
//! previous output directory as a whole.

use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_sibling(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("{}: cannot write output file", path.display()))
}

/// Serialises `value` as pretty JSON and writes it atomically to `path`.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value).context("serialising JSON output")?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Prints `value` as pretty JSON on standard output.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).context("serialising JSON output")?;
    // `println!` panics when the reader went away (`moma ... --json | head`); a closed
    // pipe is the reader's choice, not an error, and any other failure is reported.
    let mut stdout = std::io::stdout().lock();
    match writeln!(stdout, "{text}").and_then(|()| stdout.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("cannot write to standard output"),
    }
}

/// Writes several outputs only once all of them were produced: the caller builds every
/// `(path, bytes)` pair first, then calls this. Every file is first written to its
/// temporary sibling; only when all of them succeeded are they renamed into place, so an
/// unwritable path (e.g. a missing directory) leaves none of the outputs behind.
pub fn write_all_atomic(files: &[(PathBuf, Vec<u8>)]) -> Result<()> {
    let mut written: Vec<(PathBuf, &Path)> = Vec::with_capacity(files.len());
    let cleanup = |written: &[(PathBuf, &Path)]| {
        for (tmp, _) in written {
            let _ = std::fs::remove_file(tmp);
        }
    };
    for (path, bytes) in files {
        let tmp = temp_sibling(path);
        let result = (|| -> std::io::Result<()> {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            cleanup(&written);
            return Err(anyhow::Error::new(e)
                .context(format!("{}: cannot write output file", path.display())));
        }
        written.push((tmp, path.as_path()));
    }
    for (i, (tmp, path)) in written.iter().enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&written[i..]);
            return Err(anyhow::Error::new(e)
                .context(format!("{}: cannot write output file", path.display())));
        }
    }
    Ok(())
}

/// The file name a directory must hold to count as a previous output of [`write_dir`]
/// that a rerun may replace.
pub const DIR_MARKER: &str = "summary.json";

/// Writes the files `files` (names relative to `dir`, no subdirectories) as the directory
/// `dir`, all or nothing: missing parent directories are created, the files are written
/// into a temporary directory beside `dir`, and that directory is renamed to `dir` in one
/// step. An existing `dir` is replaced only if it is empty or is a previous output (it
/// holds [`DIR_MARKER`] and no subdirectory); anything else is refused, so a mistyped
/// `--output` never deletes a user's folder. On any failure the temporary directory and
/// every parent directory this call created are removed again.
pub fn write_dir(dir: &Path, files: &[(String, Vec<u8>)]) -> Result<()> {
    check_replaceable(dir)?;
    let mut created = Vec::new();
    let result = stage_and_swap(dir, files, &mut created);
    if result.is_err() {
        // innermost first; a directory that is no longer empty is someone else's
        for d in created.iter().rev() {
            let _ = std::fs::remove_dir(d);
        }
    }
    result
}

fn check_replaceable(dir: &Path) -> Result<()> {
    if !dir.exists() {
        return Ok(());
    }
    if !dir.is_dir() {
        anyhow::bail!(
            "{}: output directory exists and is not a directory",
            dir.display()
        );
    }
    let mut marker = false;
    for entry in std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read output directory", dir.display()))?
    {
        let entry = entry.with_context(|| format!("{}: cannot read", dir.display()))?;
        if entry.file_type().map(|t| t.is_dir()).unwrap_or(true) {
            anyhow::bail!(
                "{}: output directory exists and holds a subdirectory ({}); not a previous moma output, refusing to replace it",
                dir.display(),
                entry.file_name().to_string_lossy()
            );
        }
        marker |= entry.file_name() == DIR_MARKER;
    }
    let empty = std::fs::read_dir(dir)
        .map(|mut d| d.next().is_none())
        .unwrap_or(false);
    if !marker && !empty {
        anyhow::bail!(
            "{}: output directory exists, is not empty and holds no {DIR_MARKER}; not a previous moma output, refusing to replace it",
            dir.display()
        );
    }
    Ok(())
}

/// Creates the missing ancestors of `dir` (recorded in `created`), writes the files into
/// a temporary sibling directory and swaps it into place.
fn stage_and_swap(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    created: &mut Vec<PathBuf>,
) -> Result<()> {
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut missing = Vec::new();
    let mut p = parent.as_path();
    while !p.as_os_str().is_empty() && !p.exists() {
        missing.push(p.to_path_buf());
        match p.parent() {
            Some(q) => p = q,
            None => break,
        }
    }
    for d in missing.iter().rev() {
        std::fs::create_dir(d)
            .with_context(|| format!("{}: cannot create output directory", d.display()))?;
        created.push(d.clone());
    }
    let tmp = temp_sibling(dir);
    let _ = std::fs::remove_dir_all(&tmp);
    let staged = (|| -> Result<()> {
        std::fs::create_dir(&tmp)
            .with_context(|| format!("{}: cannot create output directory", dir.display()))?;
        for (name, bytes) in files {
            let path = tmp.join(name);
            let mut f = std::fs::File::create(&path).with_context(|| {
                format!("{}: cannot write output file", dir.join(name).display())
            })?;
            f.write_all(bytes)
                .and_then(|()| f.sync_all())
                .with_context(|| {
                    format!("{}: cannot write output file", dir.join(name).display())
                })?;
        }
        swap_into_place(&tmp, dir)
    })();
    if staged.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    staged
}

/// Renames `tmp` to `dir`; an existing `dir` is moved aside first and removed after.
fn swap_into_place(tmp: &Path, dir: &Path) -> Result<()> {
    let cannot = || {
        format!(
            "{}: cannot move the output directory into place",
            dir.display()
        )
    };
    if !dir.exists() {
        return std::fs::rename(tmp, dir).with_context(cannot);
    }
    let old = dir.with_file_name(format!(
        ".{}.old-{}",
        dir.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&old);
    std::fs::rename(dir, &old).with_context(cannot)?;
    if let Err(e) = std::fs::rename(tmp, dir) {
        let _ = std::fs::rename(&old, dir);
        return Err(anyhow::Error::new(e).context(cannot()));
    }
    let _ = std::fs::remove_dir_all(&old);
    Ok(())
}

fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("moma-output-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_directory_write_leaves_nothing_behind() {
        let root = scratch("fail");
        let target = root.join("new").join("deeper").join("out");
        // the second file cannot be created (its subdirectory does not exist)
        let files = vec![
            ("a.txt".to_string(), b"a".to_vec()),
            ("missing/b.txt".to_string(), b"b".to_vec()),
        ];
        assert!(write_dir(&target, &files).is_err());
        assert!(names(&root).is_empty(), "left behind: {:?}", names(&root));
    }

    #[test]
    fn a_rerun_replaces_the_previous_directory_as_a_whole() {
        let root = scratch("rerun");
        let target = root.join("out");
        let first = vec![
            ("x.svg".to_string(), b"1".to_vec()),
            (DIR_MARKER.to_string(), b"{}".to_vec()),
        ];
        write_dir(&target, &first).unwrap();
        let second = vec![(DIR_MARKER.to_string(), b"{\"run\": 2}".to_vec())];
        write_dir(&target, &second).unwrap();
        assert_eq!(names(&target), [DIR_MARKER]);
        assert_eq!(
            std::fs::read(target.join(DIR_MARKER)).unwrap(),
            b"{\"run\": 2}"
        );
        assert_eq!(names(&root), ["out"], "no temporary directory left");
    }

    #[test]
    fn a_foreign_directory_is_never_replaced() {
        let root = scratch("foreign");
        let target = root.join("mine");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("thesis.tex"), "precious").unwrap();
        let files = vec![(DIR_MARKER.to_string(), b"{}".to_vec())];
        let e = write_dir(&target, &files).unwrap_err().to_string();
        assert!(e.contains("refusing to replace"), "{e}");
        assert_eq!(names(&target), ["thesis.tex"]);
    }

    #[test]
    fn a_failed_file_set_leaves_no_file() {
        let root = scratch("set");
        let files = vec![
            (root.join("a.json"), b"a".to_vec()),
            (root.join("nope").join("b.svg"), b"b".to_vec()),
        ];
        assert!(write_all_atomic(&files).is_err());
        assert!(names(&root).is_empty(), "left behind: {:?}", names(&root));
    }
}
