//! Every count derived from user input is bounded before anything is allocated: each
//! guard answers at once with an error that names the count, instead of exhausting the
//! machine (each test runs in milliseconds).

use moma::Error;
use moma::ik::placement::{MAX_SAMPLES, PlacementGrid};
use moma::planning::MAX_TRAJECTORY_SAMPLES;
use moma::planning::costmap::{
    Footprint, FootprintCSpace, MAX_FOOTPRINT_CSPACE_CELLS, astar_footprint, footprint_cspace,
};
use moma::planning::trajectory::{DiffDriveLimits, time_parameterize};
use moma::planning::{MapKind, OccupancyGrid, SearchGrid};

const LIMITS: DiffDriveLimits = DiffDriveLimits {
    v_max: 0.5,
    omega_max: 1.0,
    a_max: 0.5,
    alpha_max: 1.0,
};

fn invalid(e: Error, field: &str, words: &str) {
    match &e {
        Error::InvalidInput { field: f, message } => {
            assert_eq!(f, field, "{e}");
            assert!(message.contains(words), "{e}");
        }
        other => panic!("expected InvalidInput for {field}, got {other}"),
    }
}

#[test]
fn trajectory_samples_are_bounded() {
    let path = [[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]];
    // A normal request works and respects the count it promises.
    let ok = time_parameterize(&path, None, &LIMITS, 0.01).unwrap();
    assert!(ok.len() > 100 && ok.len() < MAX_TRAJECTORY_SAMPLES);
    // `plan --dt 1e-12`: ~4e13 samples.
    let e = time_parameterize(&path, None, &LIMITS, 1e-12).unwrap_err();
    invalid(e, "trajectory samples", "larger dt");
    // Tiny velocity or acceleration limits: an absurdly long trajectory at a sane dt.
    for limits in [
        DiffDriveLimits {
            v_max: 1e-9,
            ..LIMITS
        },
        DiffDriveLimits {
            a_max: 1e-15,
            ..LIMITS
        },
        DiffDriveLimits {
            omega_max: 1e-9,
            ..LIMITS
        },
        DiffDriveLimits {
            alpha_max: 1e-15,
            ..LIMITS
        },
    ] {
        let e = time_parameterize(&path, None, &limits, 0.01).unwrap_err();
        invalid(e, "trajectory samples", "limit of 10000000");
    }
}

#[test]
fn footprint_cspace_and_search_states_are_bounded() {
    let fp = Footprint::new(vec![[-0.3, -0.2], [0.3, -0.2], [0.3, 0.2], [-0.3, 0.2]]).unwrap();
    // 20000 x 20000 cells x 8 headings x 2 = 6.4e9 one-byte cells: refused before the
    // obstacle mask is even looked at.
    let e = footprint_cspace(&[], 20_000, 20_000, 0.05, &fp, 8).unwrap_err();
    invalid(e, "footprint C-space", "coarser map");
    // Overflowing products are refused too.
    let e = footprint_cspace(&[], usize::MAX / 2, 3, 0.05, &fp, 8).unwrap_err();
    invalid(
        e,
        "footprint C-space",
        &MAX_FOOTPRINT_CSPACE_CELLS.to_string(),
    );
    // The search refuses a C-space whose state count is too large (its fields are public)
    // before it indexes or allocates anything.
    let cs = FootprintCSpace {
        headings: 8,
        width: 6000,
        height: 6000,
        slices: Vec::new(),
        sweeps: Vec::new(),
    };
    let e = astar_footprint(&cs, (0, 0, 0), (5, 5), 1.0).unwrap_err();
    invalid(e, "footprint search", "search states");
    // A small one still plans.
    let free = vec![false; 40 * 30];
    let cs = footprint_cspace(&free, 40, 30, 0.05, &fp, 8).unwrap();
    let p = astar_footprint(&cs, (5, 5, 0), (30, 20), 1.0)
        .unwrap()
        .unwrap();
    assert_eq!(p.states.first(), Some(&(5, 5, 0)));
    assert_eq!(
        (p.states.last().unwrap().0, p.states.last().unwrap().1),
        (30, 20)
    );
}

#[test]
fn placement_grids_are_bounded() {
    // 1e5 x 1e5 cells x 8 headings = 8e10 base poses at a 1 mm step over 100 m.
    let e = PlacementGrid::new([0.0, 0.0, 100.0, 100.0], 1e-3, 8).unwrap_err();
    invalid(e, "step", &MAX_SAMPLES.to_string());
    // a huge heading count alone
    let e = PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.5, usize::MAX).unwrap_err();
    invalid(e, "step", "exceed the limit");
    assert_eq!(
        PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.5, 8)
            .unwrap()
            .len(),
        72
    );
}

#[test]
fn search_grid_from_an_inconsistent_occupancy_grid_is_an_error() {
    let mut g = OccupancyGrid::new_free(10, 10, MapKind::MovingAi).unwrap();
    assert!(SearchGrid::from_grid(&g, true).is_ok());
    g.cells.pop();
    let e = SearchGrid::from_grid(&g, true).unwrap_err();
    assert!(
        matches!(
            e,
            Error::WrongLength {
                expected: 100,
                got: 99,
                ..
            }
        ),
        "{e}"
    );
    g.width = 0;
    assert!(SearchGrid::from_grid(&g, true).is_err());
}
