//! A bounding-volume tree of axis-aligned boxes over a list of items, built by median
//! splits along the longest axis: the scene objects' shapes ([`super::scene`], in the
//! world) and a mesh's triangles ([`super::exact`], in the mesh's frame).

use nalgebra::Vector3;

/// A node: its box; a leaf holds a range of the items, an inner node two children.
#[derive(Clone, Debug)]
pub(super) struct BvhNode {
    pub lo: Vector3<f64>,
    pub hi: Vector3<f64>,
    /// Leaf: `Some((first, count))` into the items; inner: children `child`, `child + 1`.
    pub leaf: Option<(usize, usize)>,
    pub child: usize,
}

/// The tree over `items` (reordered into leaf order, at most `leaf_size` per leaf; root
/// at node 0), `aabb` giving each item's box (min, max).
pub(super) fn build_bvh<T>(
    items: &mut [T],
    leaf_size: usize,
    aabb: impl Fn(&T) -> (Vector3<f64>, Vector3<f64>) + Copy,
) -> Vec<BvhNode> {
    let mut nodes = Vec::with_capacity(2 * items.len() / leaf_size.max(1) + 2);
    nodes.push(BvhNode {
        lo: Vector3::zeros(),
        hi: Vector3::zeros(),
        leaf: None,
        child: 0,
    });
    build(items, 0, 0, leaf_size.max(1), aabb, &mut nodes);
    nodes
}

/// Builds node `k` over `items` (which start at `first` in the whole list).
fn build<T>(
    items: &mut [T],
    first: usize,
    k: usize,
    leaf_size: usize,
    aabb: impl Fn(&T) -> (Vector3<f64>, Vector3<f64>) + Copy,
    nodes: &mut Vec<BvhNode>,
) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for s in items.iter() {
        let (l, h) = aabb(s);
        lo = lo.inf(&l);
        hi = hi.sup(&h);
    }
    nodes[k].lo = lo;
    nodes[k].hi = hi;
    if items.len() <= leaf_size {
        nodes[k].leaf = Some((first, items.len()));
        return;
    }
    let axis = (hi - lo).imax();
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        let (la, ha) = aabb(a);
        let (lb, hb) = aabb(b);
        (la[axis] + ha[axis]).total_cmp(&(lb[axis] + hb[axis]))
    });
    let child = nodes.len();
    nodes[k].child = child;
    for _ in 0..2 {
        nodes.push(BvhNode {
            lo,
            hi,
            leaf: None,
            child: 0,
        });
    }
    let (left, right) = items.split_at_mut(mid);
    build(left, first, child, leaf_size, aabb, nodes);
    build(right, first + mid, child + 1, leaf_size, aabb, nodes);
}

/// The gap between two boxes (0 when they overlap): a lower bound on the distance of
/// anything in one to anything in the other.
pub(super) fn box_gap(
    lo_a: &Vector3<f64>,
    hi_a: &Vector3<f64>,
    lo_b: &Vector3<f64>,
    hi_b: &Vector3<f64>,
) -> f64 {
    (lo_a - hi_b)
        .sup(&(lo_b - hi_a))
        .sup(&Vector3::zeros())
        .norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item lies in its leaf's box and in every ancestor's, each item in one leaf.
    #[test]
    fn leaves_cover_the_items_once() {
        let mut items: Vec<Vector3<f64>> = (0..37)
            .map(|i| {
                Vector3::new(
                    f64::from(i).sin(),
                    f64::from(i * 7 % 11),
                    f64::from(i) * 0.1,
                )
            })
            .collect();
        let nodes = build_bvh(&mut items, 4, |p| (*p, *p));
        let mut seen = vec![0; items.len()];
        let mut stack = vec![0];
        while let Some(n) = stack.pop() {
            let node = &nodes[n];
            match node.leaf {
                Some((first, count)) => {
                    assert!(count <= 4);
                    for (i, p) in items.iter().enumerate().skip(first).take(count) {
                        seen[i] += 1;
                        assert!(p.iter().zip(node.lo.iter()).all(|(x, l)| x >= l));
                        assert!(p.iter().zip(node.hi.iter()).all(|(x, h)| x <= h));
                    }
                }
                None => {
                    for c in [node.child, node.child + 1] {
                        assert!(nodes[c].lo.iter().zip(node.lo.iter()).all(|(x, l)| x >= l));
                        assert!(nodes[c].hi.iter().zip(node.hi.iter()).all(|(x, h)| x <= h));
                        stack.push(c);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&k| k == 1));
    }

    #[test]
    fn box_gap_is_the_distance_between_boxes() {
        let o = Vector3::zeros();
        let one = Vector3::repeat(1.0);
        assert_eq!(
            box_gap(
                &o,
                &one,
                &Vector3::new(0.5, 0.5, 0.5),
                &Vector3::repeat(2.0)
            ),
            0.0
        );
        let lo = Vector3::new(4.0, 5.0, 0.5);
        assert!((box_gap(&o, &one, &lo, &(lo + one)) - 5.0).abs() < 1e-15);
    }
}
