//! Shortcut smoothing of grid paths with line-of-sight checks against the C-space.

use super::astar::SearchGrid;

/// `true` if the straight segment between the centres of cells `a` and `b` crosses only
/// free C-space cells. Every cell the segment passes through is checked (a supercover
/// traversal, Amanatides & Woo 1987); where it passes exactly through a cell corner, both
/// cells beside the corner must be free (the no-corner-cutting rule of the search).
pub fn line_of_sight(grid: &SearchGrid, a: (usize, usize), b: (usize, usize)) -> bool {
    let (mut x, mut y) = (a.0 as i64, a.1 as i64);
    let (tx, ty) = (b.0 as i64, b.1 as i64);
    let (dx, dy) = (tx - x, ty - y);
    let (sx, sy) = (dx.signum(), dy.signum());
    let (adx, ady) = (dx.abs(), dy.abs());
    if !grid.is_free(x, y) {
        return false;
    }
    // Compare crossings with integers: the next vertical boundary is crossed at parameter
    // (2i + 1) / (2 adx), the next horizontal one at (2j + 1) / (2 ady).
    let (mut i, mut j) = (0i64, 0i64);
    while i < adx || j < ady {
        let lhs = (2 * i + 1) * ady;
        let rhs = (2 * j + 1) * adx;
        if i < adx && (j >= ady || lhs < rhs) {
            x += sx;
            i += 1;
        } else if j < ady && (i >= adx || rhs < lhs) {
            y += sy;
            j += 1;
        } else {
            // Through a corner: both side cells and the diagonal cell must be free.
            if !grid.is_free(x + sx, y) || !grid.is_free(x, y + sy) {
                return false;
            }
            x += sx;
            y += sy;
            i += 1;
            j += 1;
        }
        if !grid.is_free(x, y) {
            return false;
        }
    }
    true
}

/// Shortcut ("string-pulling") smoothing: from each kept waypoint, jump to the farthest
/// following path cell still in line of sight (scanning forward until the first blocked
/// sight line), and drop the cells in between. The result starts and ends with the
/// path's ends, every segment is collision-free in the C-space, and it is never longer
/// than the input.
#[doc(alias = "shortcut")]
pub fn smooth(grid: &SearchGrid, cells: &[(usize, usize)]) -> Vec<(usize, usize)> {
    if cells.len() <= 2 {
        return cells.to_vec();
    }
    let mut out = vec![cells[0]];
    let mut i = 0;
    while i < cells.len() - 1 {
        let mut best = i + 1;
        let mut j = i + 2;
        while j < cells.len() && line_of_sight(grid, cells[i], cells[j]) {
            best = j;
            j += 1;
        }
        out.push(cells[best]);
        i = best;
    }
    out
}

/// Euclidean length of a polyline of cells (in cells).
pub fn polyline_length(cells: &[(usize, usize)]) -> f64 {
    cells
        .windows(2)
        .map(|w| ((w[1].0 as f64 - w[0].0 as f64).powi(2) + (w[1].1 as f64 - w[0].1 as f64).powi(2)).sqrt())
        .sum()
}
