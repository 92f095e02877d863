//! Review regressions: degenerate or gigantic footprints are rejected with an error
//! naming the footprint instead of being silently ignored or taking for ever.

use moma::planning::costmap::{Footprint, footprint_cspace};

#[test]
fn zero_area_footprint_is_rejected() {
    assert!(Footprint::new(vec![[0.0, 0.0]; 3]).is_err());
    assert!(Footprint::new(vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).is_err());
    assert!(Footprint::new(vec![[-1.0, -1.0], [1.0, -1.0], [0.0, 1.0]]).is_ok());
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
    let f = Footprint::new(vec![[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]).unwrap();
    assert!(footprint_cspace(&obstacles, 20, 10, 0.05, &f, 8).is_ok());
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
