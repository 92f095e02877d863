//! Degenerate or gigantic footprints are rejected with an error
//! naming the footprint instead of being silently ignored or taking for ever.

use moma::planning::costmap::{Footprint, footprint_cspace};

#[test]
fn zero_area_footprint_is_rejected() {
    assert!(Footprint::new(vec![[0.0, 0.0]; 3]).is_err());
    assert!(Footprint::new(vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).is_err());
    let t = Footprint::new(vec![[-1.0, -1.0], [1.0, -1.0], [0.0, 1.0]]).unwrap();
    // circumscribed: the farthest vertex; inscribed: the nearest edge, 2x + y = 1
    assert!((t.circumscribed_radius() - 2f64.sqrt()).abs() < 1e-12);
    assert!((t.inscribed_radius() - 1.0 / 5f64.sqrt()).abs() < 1e-12);
    assert!(t.contains(0.0, 0.0) && t.contains(0.0, 0.9) && !t.contains(0.9, 0.9));
}

#[test]
fn footprint_wider_than_the_map_is_an_error() {
    let obstacles = vec![false; 20 * 10];
    let f = Footprint::new(vec![[0.0, 0.0], [1e10, 0.0], [0.0, 1e10]]).unwrap();
    let err = footprint_cspace(&obstacles, 20, 10, 0.05, &f, 8).unwrap_err();
    assert!(err.to_string().contains("footprint"), "{err}");
    // So large that its area overflows: refused when built.
    let err = Footprint::new(vec![[0.0, 0.0], [1e300, 0.0], [0.0, 1e300]]).unwrap_err();
    assert!(err.to_string().contains("footprint"), "{err}");
    // A normal footprint: every heading's mask equals a brute-force check of which
    // poses put the rotated square footprint onto the obstacle cell's square (side
    // 0.05 m): the two squares meet when no axis of either separates them.
    let h = 0.11;
    let f = Footprint::new(vec![[-h, -h], [h, -h], [h, h], [-h, h]]).unwrap();
    let empty = footprint_cspace(&obstacles, 20, 10, 0.05, &f, 8).unwrap();
    assert!(
        empty
            .slices
            .iter()
            .chain(&empty.sweeps)
            .flatten()
            .all(|b| !b)
    );
    let mut one = obstacles.clone();
    let (ox, oy) = (10usize, 5usize);
    one[oy * 20 + ox] = true;
    let cs = footprint_cspace(&one, 20, 10, 0.05, &f, 8).unwrap();
    let e = 0.025;
    let mut counts = Vec::new();
    for k in 0..8 {
        let th = k as f64 * std::f64::consts::FRAC_PI_4;
        let (c, s) = (th.cos(), th.sin());
        let spread = c.abs() + s.abs();
        let mut blocked = 0;
        for y in 0..10 {
            for x in 0..20 {
                let (wx, wy) = ((ox as f64 - x as f64) * 0.05, (oy as f64 - y as f64) * 0.05);
                // the grid's axes, then the footprint's
                let want = wx.abs() <= e + h * spread
                    && wy.abs() <= e + h * spread
                    && (c * wx + s * wy).abs() <= h + e * spread
                    && (-s * wx + c * wy).abs() <= h + e * spread;
                assert_eq!(
                    cs.slices[k][y * 20 + x],
                    want,
                    "heading {k}, cell ({x}, {y})"
                );
                blocked += want as usize;
                // the turn from θ_k sweeps at least both end poses
                if want || cs.slices[(k + 1) % 8][y * 20 + x] {
                    assert!(cs.sweeps[k][y * 20 + x], "sweep {k}, cell ({x}, {y})");
                }
            }
        }
        counts.push(blocked);
    }
    // axis-aligned: the square reaches 0.11 + 0.025 m = 2.7 cells, 5 x 5 poses as with
    // the centres; at 45° the footprint's corners reach into the obstacle's square from
    // 12 poses beyond the 25 whose footprint holds the obstacle's centre
    assert_eq!(counts, [25, 37, 25, 37, 25, 37, 25, 37]);
}

#[test]
fn ros_map_with_a_missing_image_names_the_yaml_and_the_field() {
    let dir = std::env::temp_dir().join(format!("moma-review-rosmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let yaml = dir.join("broken.yaml");
    std::fs::write(
        &yaml,
        "image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let err = moma::planning::rosmap::load_ros_map(&yaml).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("broken.yaml") && msg.contains("'image'") && msg.contains("missing.pgm"),
        "{msg}"
    );
}
