//! How the page's numbers are made small: a series thinned to a bounded number of
//! samples (keeping the ones that must survive) and values rounded to the precision a
//! picture needs. Used by the run's JSON (`embed`) and the 3-D view's (`view3d`).

use serde_json::Value;

/// Indices `0..n` thinned to about `max` evenly spaced ones (first and last always kept),
/// merged with `keep` (indices that must survive, e.g. where a monitor is at its
/// extreme), sorted and without repeats. Out-of-range entries of `keep` are ignored.
pub(crate) fn decimate_indices(n: usize, max: usize, keep: &[usize]) -> Vec<usize> {
    let mut idx: Vec<usize> = if n <= max.max(2) {
        (0..n).collect()
    } else {
        let m = max.max(2);
        (0..m)
            .map(|k| ((k as f64) * (n - 1) as f64 / (m - 1) as f64).round() as usize)
            .collect()
    };
    idx.extend(keep.iter().copied().filter(|&i| i < n));
    idx.sort_unstable();
    idx.dedup();
    idx
}

/// `x` rounded to `dec` decimals as a JSON number; non-finite values become `null`.
pub(crate) fn num(x: f64, dec: i32) -> Value {
    if !x.is_finite() {
        return Value::Null;
    }
    let s = 10f64.powi(dec);
    let r = (x * s).round() / s;
    // -0.0 prints as "-0.0"; keep the text short
    let r = if r == 0.0 { 0.0 } else { r };
    serde_json::Number::from_f64(r).map_or(Value::Null, Value::Number)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_is_bounded_keeps_ends_and_extremes() {
        assert_eq!(decimate_indices(5, 100, &[]), vec![0, 1, 2, 3, 4]);
        assert_eq!(decimate_indices(0, 100, &[3]), Vec::<usize>::new());
        let idx = decimate_indices(100_001, 1000, &[12_345, 7, 99_999_999]);
        assert!(idx.len() <= 1002, "{}", idx.len());
        assert_eq!(idx[0], 0);
        assert_eq!(*idx.last().unwrap(), 100_000);
        assert!(idx.contains(&12_345) && idx.contains(&7));
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        // even spacing: the uniform part steps by 100 or 101
        let uniform = decimate_indices(100_001, 1000, &[]);
        assert_eq!(uniform.len(), 1000);
        assert!(
            uniform
                .windows(2)
                .all(|w| (100..=101).contains(&(w[1] - w[0])))
        );
    }
}
