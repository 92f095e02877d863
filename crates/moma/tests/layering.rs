//! One direction of dependency between the library's top-level modules.
//!
//! Every `.rs` file under `crates/moma/src/` is read, its comments and string literals
//! are blanked, and every path that starts with `crate::` (including the items of
//! `use crate::{a::…, b::…}` groups) is taken as a use of the top-level module it names.
//! A module may use only modules of a strictly lower layer of [`LAYERS`]; a use of a
//! module of the same or a higher layer fails the test, naming the file, the line and the
//! import. A module that has no layer yet also fails (place it in [`LAYERS`] first).
//!
//! The table "The library, module by module" of `ARCHITECTURE.md` must state the true
//! direct dependencies: for every module that exists, its "depends on" column lists
//! exactly the modules it uses (besides `error`, which every module may use).
//!
//! Not seen: `super::super::…` paths that climb out of a top-level module (the code uses
//! `crate::` for those) and uses written inside macros' string arguments.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first. Modules that do not exist yet (`space`, `stability`,
/// `control`, `mission`) already have their place, so adding them needs no change here.
/// `planning` stands apart: it sits right above `error` and so may use nothing else.
const LAYERS: &[&[&str]] = &[
    &["error"],
    &["spatial", "ode", "linalg", "planning"],
    &["multibody"],
    &["io", "kinematics"],
    &["dynamics", "collision"],
    &["mobile", "space", "contact"],
    &["stability", "manipulability"],
    &["ik"],
    &["control", "motion"],
    &["closed_form"],
    &["sim"],
    &["mission"],
    &["sim_config"],
    &["sweep"],
];

/// Items re-exported at the crate root, with the module that defines them.
const ROOT_ITEMS: &[(&str, &str)] = &[("Error", "error"), ("Result", "error")];

/// One use of a top-level module by a file of another.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Use {
    /// 1-based line of the `crate` keyword.
    line: usize,
    /// The top-level module used.
    module: String,
    /// The import as written (comments removed, whitespace collapsed).
    import: String,
}

/// Replaces comments, string and character literals by spaces (newlines kept, so line
/// numbers stay right).
fn blank_non_code(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0usize;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (i == 0 || !is_ident(c[i - 1]))
            && matches!(c.get(i + 1), Some('"') | Some('#'))
        {
            // Raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            for &ch in &c[i..j.min(c.len())] {
                blank(&mut out, ch);
            }
            i = j;
        } else if c[i] == '"' {
            blank(&mut out, c[i]);
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' && i + 1 < c.len() {
                    blank(&mut out, c[i]);
                    i += 1;
                }
                blank(&mut out, c[i]);
                i += 1;
            }
            if i < c.len() {
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '\'' {
            // Character literal ('x', '\n', '\'', '\u{..}') or a lifetime ('a).
            let end = if c.get(i + 1) == Some(&'\\') {
                (i + 2..c.len()).find(|&j| c[j] == '\'' && j > i + 2)
            } else if c.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for &ch in &c[i..=e] {
                        blank(&mut out, ch);
                    }
                    i = e + 1;
                }
                None => {
                    out.push(c[i]);
                    i += 1;
                }
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// Every `crate::…` reference in `src` (already a whole file), with its top-level module
/// (root items such as `crate::Error` are mapped through [`ROOT_ITEMS`]).
fn crate_uses(src: &str) -> Vec<Use> {
    let code = blank_non_code(src);
    let c: Vec<char> = code.chars().collect();
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let skip_ws = |mut j: usize| {
        while j < c.len() && c[j].is_whitespace() {
            j += 1;
        }
        j
    };
    let ident_at = |j: usize| {
        let mut k = j;
        while k < c.len() && is_ident(c[k]) {
            k += 1;
        }
        (c[j..k].iter().collect::<String>(), k)
    };
    let line_of = |j: usize| 1 + c[..j].iter().filter(|&&ch| ch == '\n').count();
    let squeeze = |s: &[char]| {
        s.iter()
            .collect::<String>()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut uses = Vec::new();
    let mut i = 0;
    while i + 5 <= c.len() {
        let starts_word = i == 0 || !(is_ident(c[i - 1]) || c[i - 1] == '$');
        if !(starts_word && c[i..i + 5].iter().collect::<String>() == "crate")
            || c.get(i + 5).is_some_and(|&ch| is_ident(ch))
        {
            i += 1;
            continue;
        }
        let mut j = skip_ws(i + 5);
        if !(c.get(j) == Some(&':') && c.get(j + 1) == Some(&':')) {
            i += 5;
            continue;
        }
        j = skip_ws(j + 2);
        let line = line_of(i);
        if c.get(j) == Some(&'{') {
            // A group: split its items at depth-0 commas.
            let mut depth = 0usize;
            let mut item_start = j + 1;
            let mut k = j;
            while k < c.len() {
                match c[k] {
                    '{' => depth += 1,
                    '}' | ',' if depth == 1 => {
                        let s = skip_ws(item_start);
                        if s < k && is_ident(c[s]) {
                            let (name, _) = ident_at(s);
                            uses.push(Use {
                                line,
                                module: name,
                                import: format!("crate::{}", squeeze(&c[s..k])),
                            });
                        }
                        item_start = k + 1;
                        if c[k] == '}' {
                            break;
                        }
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
                k += 1;
            }
            i = k.max(i + 5);
        } else if c.get(j).is_some_and(|&ch| is_ident(ch)) {
            let (name, mut k) = ident_at(j);
            // The rest of the path, for the message.
            loop {
                let a = skip_ws(k);
                if c.get(a) == Some(&':') && c.get(a + 1) == Some(&':') {
                    let b = skip_ws(a + 2);
                    if c.get(b).is_some_and(|&ch| is_ident(ch)) {
                        k = ident_at(b).1;
                        continue;
                    }
                    if c.get(b) == Some(&'{') {
                        k = (b..c.len())
                            .find(|&e| c[e] == '}')
                            .map_or(c.len(), |e| e + 1);
                    }
                }
                break;
            }
            uses.push(Use {
                line,
                module: name,
                import: squeeze(&c[i..k]),
            });
            i = k;
        } else {
            i = j;
        }
    }
    for u in &mut uses {
        if let Some((_, m)) = ROOT_ITEMS.iter().find(|(item, _)| *item == u.module) {
            u.module = (*m).to_string();
        }
    }
    uses
}

/// The layer of `module`, if it has one.
fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// The top-level module a file belongs to, from its path relative to `src/`
/// (`None` for `lib.rs`, the crate root that declares the modules).
fn module_of(rel: &Path) -> Option<String> {
    let mut parts = rel.components();
    let first = parts.next()?.as_os_str().to_str()?.to_string();
    if parts.next().is_some() {
        Some(first)
    } else if first == "lib.rs" {
        None
    } else {
        first.strip_suffix(".rs").map(str::to_string)
    }
}

/// Checks files `(path relative to src/, contents)` against [`LAYERS`]; returns one
/// message per violation, and the direct dependencies of each module (besides itself).
fn check(files: &[(PathBuf, String)]) -> (Vec<String>, BTreeMap<String, BTreeSet<String>>) {
    let mut errors = Vec::new();
    let mut deps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, text) in files {
        let Some(me) = module_of(rel) else { continue };
        deps.entry(me.clone()).or_default();
        let Some(my_layer) = layer(&me) else {
            errors.push(format!(
                "{}: module `{me}` has no layer; place it in LAYERS (tests/layering.rs) and \
                 in ARCHITECTURE.md's module table",
                rel.display()
            ));
            continue;
        };
        for u in crate_uses(text) {
            if u.module == me {
                continue;
            }
            deps.get_mut(&me)
                .expect("entry made above")
                .insert(u.module.clone());
            match layer(&u.module) {
                None => errors.push(format!(
                    "{}:{}: `{}` names `{}`, which is not a known top-level module",
                    rel.display(),
                    u.line,
                    u.import,
                    u.module
                )),
                Some(l) if l >= my_layer => errors.push(format!(
                    "{}:{}: `{me}` (layer {my_layer}) imports `{}` from `{}` (layer {l}); a \
                     module may use only modules of a lower layer",
                    rel.display(),
                    u.line,
                    u.import,
                    u.module
                )),
                Some(_) => {}
            }
        }
    }
    (errors, deps)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn source_files() -> Vec<(PathBuf, String)> {
    files_under(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

/// Every `.rs` file under `src`, with its path relative to `src`.
fn files_under(src: &Path) -> Vec<(PathBuf, String)> {
    let mut paths = Vec::new();
    rust_files(src, &mut paths);
    assert!(
        paths.len() > 20,
        "expected the library's sources under {}",
        src.display()
    );
    paths
        .into_iter()
        .map(|p| {
            let text =
                std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p.strip_prefix(src).expect("under src").to_path_buf(), text)
        })
        .collect()
}

/// The identifiers that start the paths of a `use` tree at `j` (a name, or a `{…}` group
/// whose items are read recursively, e.g. `{a::X, b}` gives `a` and `b`).
fn first_segments(c: &[char], j: usize) -> Vec<String> {
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut j = j;
    while j < c.len() && c[j].is_whitespace() {
        j += 1;
    }
    if c.get(j) == Some(&'{') {
        let mut out = Vec::new();
        let (mut depth, mut item_start) = (0usize, j + 1);
        for k in j..c.len() {
            match c[k] {
                '{' => depth += 1,
                '}' | ',' if depth == 1 => {
                    out.extend(first_segments(c, item_start).into_iter().take(1));
                    item_start = k + 1;
                    if c[k] == '}' {
                        break;
                    }
                }
                '}' => depth -= 1,
                _ => {}
            }
        }
        return out;
    }
    let mut k = j;
    while k < c.len() && is_ident(c[k]) {
        k += 1;
    }
    if k > j {
        vec![c[j..k].iter().collect()]
    } else {
        Vec::new()
    }
}

/// The files of its own module that a file uses: `super::NAME` and `crate::MODULE::NAME`
/// (also inside `{…}` groups), where `NAME.rs` is a file of the module's folder. A
/// module's `mod.rs` is left out on both ends: it declares the files and re-exports their
/// items, the module's face rather than a concept of its own, so what the files share
/// lives there.
fn sibling_uses(rel: &Path, text: &str, siblings: &BTreeSet<String>) -> BTreeSet<String> {
    let Some(me) = module_of(rel) else {
        return BTreeSet::new();
    };
    let own = rel.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
    let code = blank_non_code(text);
    let c: Vec<char> = code.chars().collect();
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut used = BTreeSet::new();
    // `(prefix, starts of the names after it)` for every `super::` and `crate::me::`
    let mut i = 0;
    while i < c.len() {
        if i > 0 && (is_ident(c[i - 1]) || c[i - 1] == ':') || !is_ident(c[i]) {
            i += 1;
            continue;
        }
        let word_end = (i..c.len()).find(|&k| !is_ident(c[k])).unwrap_or(c.len());
        let word: String = c[i..word_end].iter().collect();
        let after =
            |k: usize| (c.get(k) == Some(&':') && c.get(k + 1) == Some(&':')).then_some(k + 2);
        let names = match (word.as_str(), after(word_end)) {
            ("super", Some(j)) => first_segments(&c, j),
            ("crate", Some(j)) => first_segments(&c, j)
                .into_iter()
                .filter(|m| *m == me)
                .flat_map(|_| {
                    let m_end = j + me.len();
                    after(m_end).map_or_else(Vec::new, |k| first_segments(&c, k))
                })
                .collect(),
            _ => Vec::new(),
        };
        used.extend(
            names
                .into_iter()
                .filter(|n| n != own && siblings.contains(n)),
        );
        i = word_end;
    }
    used
}

/// Every set of files of one module that import each other in a cycle (the strongly
/// connected components of the files' use graph with more than one file), each as the
/// sorted list of its files, `mod.rs` files left out (see [`sibling_uses`]).
fn file_cycles(files: &[(PathBuf, String)]) -> Vec<Vec<String>> {
    let concept = |p: &Path| {
        module_of(p).is_some()
            && p.file_name().is_some_and(|f| f != "mod.rs")
            && p.components().count() == 2
    };
    let mut by_dir: BTreeMap<PathBuf, BTreeSet<String>> = BTreeMap::new();
    for (rel, _) in files.iter().filter(|(p, _)| concept(p)) {
        let stem = rel.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        by_dir
            .entry(rel.parent().unwrap_or(Path::new("")).to_path_buf())
            .or_default()
            .insert(stem.to_string());
    }
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, text) in files.iter().filter(|(p, _)| concept(p)) {
        let dir = rel.parent().unwrap_or(Path::new("")).to_path_buf();
        let name = |stem: &str| dir.join(format!("{stem}.rs")).display().to_string();
        graph.insert(
            rel.display().to_string(),
            sibling_uses(rel, text, &by_dir[&dir])
                .iter()
                .map(|s| name(s))
                .collect(),
        );
    }
    // files that reach each other lie on one cycle
    let reach = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(f) = stack.pop() {
            for g in graph.get(&f).into_iter().flatten() {
                if seen.insert(g.clone()) {
                    stack.push(g.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&String, BTreeSet<String>> =
        graph.keys().map(|f| (f, reach(f))).collect();
    let mut cycles: Vec<Vec<String>> = Vec::new();
    for (f, r) in &reaches {
        if !r.contains(*f) || cycles.iter().any(|c| c.contains(f)) {
            continue;
        }
        let mut cycle: Vec<String> = r
            .iter()
            .filter(|g| reaches.get(g).is_some_and(|rg| rg.contains(*f)))
            .cloned()
            .collect();
        cycle.sort();
        cycles.push(cycle);
    }
    cycles
}

/// The rows of ARCHITECTURE.md's module table: module → listed dependencies.
fn architecture_table(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let start = text
        .find("## The library, module by module")
        .expect("ARCHITECTURE.md has the section \"The library, module by module\"");
    let mut rows = BTreeMap::new();
    let mut in_table = false;
    for line in text[start..].lines().skip(1) {
        let line = line.trim();
        if !line.starts_with('|') {
            if in_table {
                break;
            }
            continue;
        }
        in_table = true;
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        let Some(name) = cells[0].strip_prefix('`').and_then(|s| s.strip_suffix('`')) else {
            continue; // header and separator rows
        };
        let listed = cells.last().expect("a row has cells");
        let deps: BTreeSet<String> = listed
            .split(',')
            .map(|d| d.trim().trim_matches('`').to_string())
            .filter(|d| !d.is_empty() && d != "—" && d != "-")
            .collect();
        rows.insert(name.to_string(), deps);
    }
    rows
}

#[test]
fn modules_use_only_lower_layers() {
    let (errors, _) = check(&source_files());
    assert!(
        errors.is_empty(),
        "layering violations:\n{}",
        errors.join("\n")
    );
}

/// The library's files and the CLI's (`crates/moma-cli/src`), each crate on its own.
#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let cli = Path::new(env!("CARGO_MANIFEST_DIR")).join("../moma-cli/src");
    let cycles: Vec<Vec<String>> = file_cycles(&source_files())
        .into_iter()
        .chain(file_cycles(&files_under(&cli)))
        .collect();
    assert!(
        cycles.is_empty(),
        "files that import each other in a cycle (move what they share into one of them \
         or into a lower file):\n{}",
        cycles
            .iter()
            .map(|c| c.join(" <-> "))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn file_cycle_checker_finds_cycles_through_super_crate_paths_and_groups() {
    let files: Vec<(PathBuf, String)> = [
        ("planning/a.rs", "use super::b::X;\n// super::c::Y\n"),
        (
            "planning/b.rs",
            "fn f() { crate::planning::{c::Z, grid}::g(); }",
        ),
        ("planning/c.rs", "use super::{a, mod_item};"),
        (
            "planning/d.rs",
            "use super::a::X; use crate::planning::mod_item;",
        ),
        ("planning/mod.rs", "pub mod a; pub use a::X;"),
        ("sim/e.rs", "use crate::sim::f;"),
        ("sim/f.rs", "use crate::planning::d;"),
    ]
    .iter()
    .map(|(p, t)| (PathBuf::from(p), t.to_string()))
    .collect();
    assert_eq!(
        file_cycles(&files),
        vec![vec![
            "planning/a.rs".to_string(),
            "planning/b.rs".to_string(),
            "planning/c.rs".to_string()
        ]]
    );
}

#[test]
fn architecture_table_states_the_true_dependencies() {
    let (_, deps) = check(&source_files());
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../ARCHITECTURE.md");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let table = architecture_table(&text);
    let mut errors = Vec::new();
    for (module, used) in &deps {
        let used: BTreeSet<String> = used.iter().filter(|m| *m != "error").cloned().collect();
        match table.get(module) {
            None => errors.push(format!("module `{module}` has no row in ARCHITECTURE.md")),
            Some(listed) if *listed != used => errors.push(format!(
                "ARCHITECTURE.md: `{module}` depends on {used:?} (besides error), the table says {listed:?}"
            )),
            Some(_) => {}
        }
    }
    for (module, listed) in &table {
        let Some(l) = layer(module) else {
            errors.push(format!(
                "ARCHITECTURE.md row `{module}` has no layer in LAYERS"
            ));
            continue;
        };
        for d in listed {
            if layer(d).is_none_or(|ld| ld >= l) {
                errors.push(format!(
                    "ARCHITECTURE.md row `{module}` lists `{d}`, which is not in a lower layer"
                ));
            }
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

fn synthetic(files: &[(&str, &str)]) -> Vec<String> {
    let files: Vec<(PathBuf, String)> = files
        .iter()
        .map(|(p, t)| (PathBuf::from(p), t.to_string()))
        .collect();
    check(&files).0
}

#[test]
fn checker_reports_an_upward_import_with_file_line_and_path() {
    let errors = synthetic(&[(
        "multibody/data.rs",
        "use crate::spatial::SE3;\n\nfn f() {\n    let q = crate::kinematics::neutral(m);\n}\n",
    )]);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].starts_with("multibody/data.rs:4:"),
        "{}",
        errors[0]
    );
    assert!(
        errors[0].contains("`crate::kinematics::neutral`"),
        "{}",
        errors[0]
    );
}

#[test]
fn checker_reads_use_groups_and_root_items() {
    let errors = synthetic(&[(
        "ode/mod.rs",
        "use crate::{\n    Error, Result,\n    sim::{Rk4, StepStats},\n    error::ensure_len,\n};\n",
    )]);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("`crate::sim::{Rk4, StepStats}`"),
        "{}",
        errors[0]
    );
    assert!(errors[0].starts_with("ode/mod.rs:1:"), "{}", errors[0]);
}

#[test]
fn checker_rejects_same_layer_and_unknown_modules_and_unplaced_files() {
    let errors = synthetic(&[
        ("io/urdf.rs", "use crate::kinematics::neutral;"),
        ("kinematics/mod.rs", "use crate::nowhere::Thing;"),
        ("teleport.rs", "use crate::error::Result;"),
    ]);
    assert_eq!(errors.len(), 3, "{errors:?}");
    assert!(errors[0].contains("`io` (layer 3) imports `crate::kinematics::neutral`"));
    assert!(errors[1].contains("not a known top-level module"));
    assert!(errors[2].contains("module `teleport` has no layer"));
}

#[test]
fn checker_ignores_comments_strings_and_own_module() {
    let errors = synthetic(&[(
        "spatial/se3.rs",
        "//! See [`crate::sim::Rk4`].\n/* crate::ik /* nested crate::ik */ */\n\
         const S: &str = \"crate::dynamics::rnea\";\nconst R: &str = r#\"crate::mobile\"#;\n\
         const C: char = '\"'; use crate::spatial::Motion; fn f<'a>(x: &'a u8) {}\n\
         pub(crate) fn g() {}\n",
    )]);
    assert!(errors.is_empty(), "{errors:?}");
}

#[test]
fn planning_may_use_error_alone() {
    let errors = synthetic(&[
        (
            "planning/astar.rs",
            "use crate::{Error, Result};\nuse crate::error::ensure_finite;",
        ),
        ("planning/grid.rs", "use crate::spatial::SE3;"),
    ]);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].starts_with("planning/grid.rs:1:"),
        "{}",
        errors[0]
    );
}

#[test]
fn architecture_table_parser_reads_modules_and_dependencies() {
    let text = "# x\n\n## The library, module by module\n\n| module | what | depends on |\n\
                | --- | --- | --- |\n| `error` | errors | — |\n| `ik` | IK, `a, b` | kinematics, `mobile` |\n\nafter\n| `no` | x | y |\n";
    let t = architecture_table(text);
    assert_eq!(t.len(), 2);
    assert!(t["error"].is_empty());
    assert_eq!(
        t["ik"],
        ["kinematics", "mobile"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    );
}
