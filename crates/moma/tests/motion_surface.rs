//! Concave links swapped for their mesh surfaces at a goal state
//! (`motion::surface_links_for_states`): a goal whose shoulder sits in the hollow of
//! Fetch's torso, clear of it by 11 mm as coal measures the meshes, is clear for the
//! planner's checker too, and no closer than coal's distance (a patch's hull holds its
//! triangles, so the surface distance is a lower bound on the meshes' distance).

mod fetch_common;

use fetch_common::{FetchQueries, fetch_dir, fetch_geometry, fetch_urdf};
use moma::collision::Scene;
use moma::motion::{
    ClearanceChecker, MeshSource, PATCH_TRIANGLES, Patching, surface_links_for_states,
    with_mesh_surface,
};
use moma::multibody::RootJoint;

/// MotionBenchMaker's default Fetch state (the tucked arm), full model order.
const START: [f64; 15] = [
    0.0, 0.0, 0.1, 0.05, 0.0, 0.0, 1.32, 1.4, -0.2, 1.72, 0.0, 1.66, 0.0, 0.05, 0.05,
];

/// The goal state of a bookshelf_thin variation drawn as MotionBenchMaker draws them
/// (`bench/mbm_unseen_queries.py --draw mbm --seeds 21`, query Front-Can5): the shoulder
/// pan at its limit, the shoulder lift link in the torso's hollow.
const GOAL: [f64; 15] = [
    0.0,
    0.0,
    0.1865244328004094,
    0.05,
    0.0,
    0.0,
    1.6056,
    0.8202180199610574,
    -0.5305565208648615,
    -2.038976719382798,
    -0.8814892155291407,
    1.5943266576647757,
    0.5447963311237461,
    0.05,
    0.05,
];

/// The distance between `torso_lift_link` and `shoulder_lift_link` at `GOAL`, by
/// Pinocchio 4.1.0 + coal 3.0.3 on the exact meshes (`coal.distance` on the two links'
/// BVH models placed by `pin.updateGeometryPlacements`).
const COAL_TORSO_SHOULDER: f64 = 0.011_051_225_112_449_013;

#[test]
fn a_goal_in_the_torsos_hollow_is_clear_once_the_goal_state_swaps_too() {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    // arm_with_torso: the torso lift and the seven arm joints.
    let group = FetchQueries::load().group(&model);
    let scene = Scene::default();
    let source = MeshSource {
        urdf: fetch_urdf(),
        package_dirs: vec![fetch_dir()],
    };
    let margin = 2e-3;
    let weights = vec![1.0; group.dim()];
    let mut x = vec![0.0; group.dim()];
    group.extract(&GOAL, &mut x);
    let closest_at_goal = |geometry| {
        ClearanceChecker::new(&model, geometry, &scene, &group, &START, margin, &weights)
            .unwrap()
            .distance_report(&x)
            .unwrap()
    };

    // Swapped at the start only: the goal is in contact (the first patches still fill
    // the hollow).
    let (start_only, _) =
        surface_links_for_states(&model, &gm, &scene, &group, &[&START], margin, &source).unwrap();
    let before = closest_at_goal(&start_only);
    assert!(before.distance <= margin, "{before:?}");

    let (both, swapped) = surface_links_for_states(
        &model,
        &gm,
        &scene,
        &group,
        &[&START, &GOAL],
        margin,
        &source,
    )
    .unwrap();
    // Splitting the torso's patches where they meet the shoulder clears the goal: the
    // shoulder keeps its hull.
    assert_eq!(swapped, ["torso_lift_link"]);
    // Only the patches in contact are split: far fewer objects than the torso's surface
    // cut into single triangles everywhere (the cost of every checked state grows with
    // them).
    let objects = |geometry: &moma::collision::GeometryModel| {
        geometry.links[geometry.link_index("torso_lift_link").unwrap()].count
    };
    let uniform = |triangles| {
        let g = with_mesh_surface(
            &model,
            &gm,
            &source,
            "torso_lift_link",
            &Patching::uniform(triangles),
        )
        .unwrap();
        objects(&g)
    };
    let (coarse, single) = (uniform(PATCH_TRIANGLES), uniform(1));
    println!(
        "torso objects: {} split where in contact, {coarse} in patches of {PATCH_TRIANGLES}, {single} single triangles",
        objects(&both)
    );
    assert!(objects(&both) > coarse, "no patch was split");
    assert!(
        objects(&both) < coarse + (single - coarse) / 4,
        "{} objects",
        objects(&both)
    );
    let after = closest_at_goal(&both);
    assert!(after.distance > margin, "{after:?}");
    // Every pair's surface distance is a lower bound on coal's mesh distance, so the
    // closest one is too.
    assert!(
        after.distance <= COAL_TORSO_SHOULDER + 1e-9,
        "{} > coal's {COAL_TORSO_SHOULDER}",
        after.distance
    );
}
