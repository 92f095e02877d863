//! Structured inputs for the JSON and TOML readers: a valid template document, changed by
//! a list of edits that `arbitrary` derives from the fuzzer's bytes. Each edit walks down
//! the value tree (every step picks a child by index modulo the child count) and replaces,
//! removes, inserts, repeats or truncates what it reaches, with extreme but well-formed
//! values (huge, tiny, negative zero, subnormal, NaN and ±inf where the format has them,
//! wrong types, long arrays). The document stays valid except where an edit lands, so the
//! fuzzer reaches the validation code past the first field.

use arbitrary::Arbitrary;

/// Largest repetition an edit may ask for (keeps documents small enough to be fast).
const MAX_REPEAT: usize = 300;

/// A replacement value.
#[derive(Arbitrary, Debug, Clone)]
pub enum Leaf {
    /// An integer.
    Int(i64),
    /// Any float (NaN and ±inf become the format's spelling, or null in JSON).
    Float(f64),
    /// One of the classic edge numbers.
    Extreme(u8),
    /// A string.
    Str(String),
    /// A boolean.
    Bool(bool),
    /// JSON null / an empty TOML table.
    Null,
    /// An empty array.
    EmptyArray,
    /// An empty object / table.
    EmptyObject,
    /// An array of `n` copies of an edge number.
    Numbers(u16, u8),
}

/// One edit of the document.
#[derive(Arbitrary, Debug, Clone)]
pub enum Edit {
    /// Replace the value reached.
    Replace(Vec<u16>, Leaf),
    /// Remove the value reached from its parent.
    Remove(Vec<u16>),
    /// Insert a key (into an object) or an element (into an array) at the value reached.
    Insert(Vec<u16>, String, Leaf),
    /// Make the array reached `n` times longer by repeating its elements.
    Repeat(Vec<u16>, u8),
    /// Cut the array reached to `n` elements.
    Truncate(Vec<u16>, u8),
}

/// The edge numbers of [`Leaf::Extreme`].
pub fn extreme(k: u8) -> f64 {
    const X: [f64; 16] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        1e308,
        -1e308,
        f64::MAX,
        f64::MIN_POSITIVE,
        5e-324,
        1e-300,
        1e300,
        1e9,
        -1e9,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    X[k as usize % X.len()]
}

fn json_number(x: f64) -> serde_json::Value {
    serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

fn json_leaf(l: &Leaf) -> serde_json::Value {
    use serde_json::Value;
    match l {
        Leaf::Int(i) => Value::from(*i),
        Leaf::Float(x) => json_number(*x),
        Leaf::Extreme(k) => json_number(extreme(*k)),
        Leaf::Str(s) => Value::String(s.clone()),
        Leaf::Bool(b) => Value::Bool(*b),
        Leaf::Null => Value::Null,
        Leaf::EmptyArray => Value::Array(Vec::new()),
        Leaf::EmptyObject => Value::Object(serde_json::Map::new()),
        Leaf::Numbers(n, k) => Value::Array(
            std::iter::repeat_n(json_number(extreme(*k)), (*n as usize).min(MAX_REPEAT)).collect(),
        ),
    }
}

/// The container that `path` reaches and the index the last step names: every step but
/// the last picks a child (index modulo the child count) while that child is itself a
/// container; `None` for an empty path.
fn json_walk<'a>(
    v: &'a mut serde_json::Value,
    path: &[u16],
) -> Option<(&'a mut serde_json::Value, usize)> {
    use serde_json::Value;
    let (&last, _) = path.split_last()?;
    let (&first, rest) = path.split_first()?;
    if rest.is_empty() {
        return Some((v, last as usize));
    }
    let child = |x: &Value| x.is_array() || x.is_object();
    let descend = match &*v {
        Value::Array(a) => !a.is_empty() && child(&a[first as usize % a.len()]),
        Value::Object(o) => {
            !o.is_empty() && child(o.values().nth(first as usize % o.len()).expect("in range"))
        }
        _ => false,
    };
    if !descend {
        return Some((v, last as usize));
    }
    match v {
        Value::Array(a) => {
            let n = a.len();
            json_walk(&mut a[first as usize % n], rest)
        }
        Value::Object(o) => {
            let n = o.len();
            json_walk(
                o.iter_mut().nth(first as usize % n).expect("in range").1,
                rest,
            )
        }
        _ => None,
    }
}

/// Applies `edits` to a JSON document.
pub fn edit_json(doc: &mut serde_json::Value, edits: &[Edit]) {
    use serde_json::Value;
    for e in edits.iter().take(16) {
        let path = match e {
            Edit::Replace(p, _)
            | Edit::Remove(p)
            | Edit::Insert(p, _, _)
            | Edit::Repeat(p, _)
            | Edit::Truncate(p, _) => p,
        };
        let Some((parent, k)) = json_walk(doc, path) else {
            if let Edit::Replace(_, l) = e {
                *doc = json_leaf(l);
            }
            continue;
        };
        match (parent, e) {
            (Value::Array(a), Edit::Replace(_, l)) if !a.is_empty() => {
                let n = a.len();
                a[k % n] = json_leaf(l);
            }
            (Value::Object(o), Edit::Replace(_, l)) if !o.is_empty() => {
                let n = o.len();
                *o.values_mut().nth(k % n).expect("in range") = json_leaf(l);
            }
            (Value::Array(a), Edit::Remove(_)) if !a.is_empty() => {
                let n = a.len();
                a.remove(k % n);
            }
            (Value::Object(o), Edit::Remove(_)) if !o.is_empty() => {
                let n = o.len();
                let key = o.keys().nth(k % n).expect("in range").clone();
                o.remove(&key);
            }
            (Value::Array(a), Edit::Insert(_, _, l)) => {
                let n = a.len();
                a.insert(k % (n + 1), json_leaf(l));
            }
            (Value::Object(o), Edit::Insert(_, key, l)) => {
                o.insert(key.clone(), json_leaf(l));
            }
            (Value::Array(a), Edit::Repeat(_, n)) if !a.is_empty() => {
                let copies = (*n as usize).min(MAX_REPEAT / a.len().max(1));
                let orig = a.clone();
                for _ in 0..copies {
                    a.extend(orig.iter().cloned());
                }
            }
            (Value::Array(a), Edit::Truncate(_, n)) => a.truncate(*n as usize),
            _ => {}
        }
    }
}

fn toml_leaf(l: &Leaf) -> toml::Value {
    use toml::Value;
    match l {
        Leaf::Int(i) => Value::Integer(*i),
        Leaf::Float(x) => Value::Float(*x),
        Leaf::Extreme(k) => Value::Float(extreme(*k)),
        Leaf::Str(s) => Value::String(s.clone()),
        Leaf::Bool(b) => Value::Boolean(*b),
        Leaf::Null | Leaf::EmptyObject => Value::Table(toml::Table::new()),
        Leaf::EmptyArray => Value::Array(Vec::new()),
        Leaf::Numbers(n, k) => Value::Array(
            std::iter::repeat_n(Value::Float(extreme(*k)), (*n as usize).min(MAX_REPEAT)).collect(),
        ),
    }
}

fn toml_walk<'a>(v: &'a mut toml::Value, path: &[u16]) -> Option<(&'a mut toml::Value, usize)> {
    use toml::Value;
    let (&last, _) = path.split_last()?;
    let (&first, rest) = path.split_first()?;
    if rest.is_empty() {
        return Some((v, last as usize));
    }
    let child = |x: &Value| x.is_array() || x.is_table();
    let descend = match &*v {
        Value::Array(a) => !a.is_empty() && child(&a[first as usize % a.len()]),
        Value::Table(o) => {
            !o.is_empty() && child(o.values().nth(first as usize % o.len()).expect("in range"))
        }
        _ => false,
    };
    if !descend {
        return Some((v, last as usize));
    }
    match v {
        Value::Array(a) => {
            let n = a.len();
            toml_walk(&mut a[first as usize % n], rest)
        }
        Value::Table(o) => {
            let n = o.len();
            toml_walk(
                o.iter_mut().nth(first as usize % n).expect("in range").1,
                rest,
            )
        }
        _ => None,
    }
}

/// Applies `edits` to a TOML document (its root table).
pub fn edit_toml(doc: &mut toml::Value, edits: &[Edit]) {
    use toml::Value;
    for e in edits.iter().take(16) {
        let path = match e {
            Edit::Replace(p, _)
            | Edit::Remove(p)
            | Edit::Insert(p, _, _)
            | Edit::Repeat(p, _)
            | Edit::Truncate(p, _) => p,
        };
        let Some((parent, k)) = toml_walk(doc, path) else {
            continue;
        };
        match (parent, e) {
            (Value::Array(a), Edit::Replace(_, l)) if !a.is_empty() => {
                let n = a.len();
                a[k % n] = toml_leaf(l);
            }
            (Value::Table(o), Edit::Replace(_, l)) if !o.is_empty() => {
                let n = o.len();
                *o.iter_mut().nth(k % n).expect("in range").1 = toml_leaf(l);
            }
            (Value::Array(a), Edit::Remove(_)) if !a.is_empty() => {
                let n = a.len();
                a.remove(k % n);
            }
            (Value::Table(o), Edit::Remove(_)) if !o.is_empty() => {
                let n = o.len();
                let key = o.keys().nth(k % n).expect("in range").clone();
                o.remove(&key);
            }
            (Value::Array(a), Edit::Insert(_, _, l)) => {
                let n = a.len();
                a.insert(k % (n + 1), toml_leaf(l));
            }
            (Value::Table(o), Edit::Insert(_, key, l)) => {
                o.insert(key.clone(), toml_leaf(l));
            }
            (Value::Array(a), Edit::Repeat(_, n)) if !a.is_empty() => {
                let copies = (*n as usize).min(MAX_REPEAT / a.len().max(1));
                let orig = a.clone();
                for _ in 0..copies {
                    a.extend(orig.iter().cloned());
                }
            }
            (Value::Array(a), Edit::Truncate(_, n)) => a.truncate(*n as usize),
            _ => {}
        }
    }
}
