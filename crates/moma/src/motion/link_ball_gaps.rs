//! The first bound of the arm's state check, for every cluster at once: each link's ball
//! against the other link's ball or the scene object's box
//! ([`super::clearance`]'s clusters). The bounds live as plain arrays, coordinate by
//! coordinate, so one pass computes all of them in straight loops the compiler runs
//! several lanes at a time (two on the default x86-64 target: packed maxima and square
//! roots), the centres gathered first, then the arithmetic over contiguous arrays, in
//! place of one branchy call per cluster.

use nalgebra::Vector3;

/// Link ball gaps: the link–link clusters first, then the link–scene ones.
#[derive(Clone, Debug, Default)]
pub(super) struct LinkBallGaps {
    /// Per link: its ball's radius, and its world centre at the placed state.
    radius: Vec<f64>,
    centre: [Vec<f64>; 3],
    /// Link–link clusters: the two links and their radii.
    pair_a: Vec<usize>,
    pair_b: Vec<usize>,
    pair_ra: Vec<f64>,
    pair_rb: Vec<f64>,
    /// Link–scene clusters: the link, its radius, and the object's box.
    scene_link: Vec<usize>,
    scene_r: Vec<f64>,
    lo: [Vec<f64>; 3],
    hi: [Vec<f64>; 3],
    /// Scratch: the gathered centres (or their differences).
    d: [Vec<f64>; 3],
    /// Each cluster's gap after [`Self::fill_all`].
    pub gap: Vec<f64>,
}

impl LinkBallGaps {
    /// The gaps of link balls of `radius` (one per link) in clusters `pairs` (two links)
    /// followed by clusters `boxes` (a link, and a scene object's box `(lo, hi)`).
    pub fn new(
        radius: Vec<f64>,
        pairs: &[(usize, usize)],
        boxes: &[(usize, Vector3<f64>, Vector3<f64>)],
    ) -> Self {
        let links = radius.len();
        let n = pairs.len().max(boxes.len());
        LinkBallGaps {
            centre: std::array::from_fn(|_| vec![0.0; links]),
            pair_a: pairs.iter().map(|p| p.0).collect(),
            pair_b: pairs.iter().map(|p| p.1).collect(),
            pair_ra: pairs.iter().map(|p| radius[p.0]).collect(),
            pair_rb: pairs.iter().map(|p| radius[p.1]).collect(),
            scene_link: boxes.iter().map(|b| b.0).collect(),
            scene_r: boxes.iter().map(|b| radius[b.0]).collect(),
            lo: std::array::from_fn(|k| boxes.iter().map(|b| b.1[k]).collect()),
            hi: std::array::from_fn(|k| boxes.iter().map(|b| b.2[k]).collect()),
            d: std::array::from_fn(|_| vec![0.0; n]),
            gap: vec![0.0; pairs.len() + boxes.len()],
            radius,
        }
    }

    /// Sets link `l`'s world centre.
    pub fn set_centre(&mut self, l: usize, c: &Vector3<f64>) {
        for k in 0..3 {
            self.centre[k][l] = c[k];
        }
    }

    /// Every cluster's gap into [`Self::gap`], at the centres set.
    pub fn fill_all(&mut self) {
        let n = self.pair_a.len();
        let [dx, dy, dz] = &mut self.d;
        let [cx, cy, cz] = &self.centre;
        for (i, (&a, &b)) in self.pair_a.iter().zip(&self.pair_b).enumerate() {
            dx[i] = cx[a] - cx[b];
            dy[i] = cy[a] - cy[b];
            dz[i] = cz[a] - cz[b];
        }
        let (pairs, boxes) = self.gap.split_at_mut(n);
        for (i, g) in pairs.iter_mut().enumerate() {
            *g = ball_gap(dx[i], dy[i], dz[i], self.pair_ra[i], self.pair_rb[i]);
        }
        for (j, &l) in self.scene_link.iter().enumerate() {
            dx[j] = cx[l];
            dy[j] = cy[l];
            dz[j] = cz[l];
        }
        let ([lx, ly, lz], [hx, hy, hz]) = (&self.lo, &self.hi);
        for (j, g) in boxes.iter_mut().enumerate() {
            *g = box_gap(
                [dx[j], dy[j], dz[j]],
                [lx[j], ly[j], lz[j]],
                [hx[j], hy[j], hz[j]],
                self.scene_r[j],
            );
        }
    }

    /// Cluster `c`'s gap alone, at the centres set (into [`Self::gap`] too).
    pub fn fill_one(&mut self, c: usize) -> f64 {
        let n = self.pair_a.len();
        let [cx, cy, cz] = &self.centre;
        let g = if c < n {
            let (a, b) = (self.pair_a[c], self.pair_b[c]);
            ball_gap(
                cx[a] - cx[b],
                cy[a] - cy[b],
                cz[a] - cz[b],
                self.pair_ra[c],
                self.pair_rb[c],
            )
        } else {
            let j = c - n;
            let l = self.scene_link[j];
            let ([lx, ly, lz], [hx, hy, hz]) = (&self.lo, &self.hi);
            box_gap(
                [cx[l], cy[l], cz[l]],
                [lx[j], ly[j], lz[j]],
                [hx[j], hy[j], hz[j]],
                self.radius[l],
            )
        };
        self.gap[c] = g;
        g
    }
}

/// The gap between balls of radii `ra`, `rb` whose centres differ by `(dx, dy, dz)`.
#[inline]
fn ball_gap(dx: f64, dy: f64, dz: f64, ra: f64, rb: f64) -> f64 {
    (dx * dx + dy * dy + dz * dz).sqrt() - ra - rb
}

/// The gap between a ball (centre `c`, radius `r`) and the box `[lo, hi]`.
#[inline]
fn box_gap(c: [f64; 3], lo: [f64; 3], hi: [f64; 3], r: f64) -> f64 {
    let e = |k: usize| (lo[k] - c[k]).max(c[k] - hi[k]).max(0.0);
    let (ex, ey, ez) = (e(0), e(1), e(2));
    (ex * ex + ey * ey + ez * ez).sqrt() - r
}
