//! The operational-space update allocates nothing after its workspaces are made: a
//! counting allocator wraps the system one; OSC runs on Panda (fixed base) and on the
//! chapter robot m5 (reduced model) with the counter armed.

mod counting_alloc;
use counting_alloc::allocations;

use moma::control::osc::{OscData, ReducedOscData, osc_fixed_base, osc_reduced};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;

#[test]
fn osc_updates_do_not_allocate() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let model =
        model_from_urdf_file(dir.join("pinocchio/urdf/panda.urdf"), RootJoint::Fixed).unwrap();
    let mut data = Data::new(&model);
    let mut od = OscData::new(model.nv, &[0, 1, 2, 3, 4, 5]);
    let fid = model.frame_id("panda_hand_tcp").unwrap();
    let q = DVector::from_fn(model.nq, |i, _| 0.1 * i as f64 - 0.3);
    let v = DVector::from_element(model.nv, 0.3);
    let a = DVector::from_element(6, 0.5);
    let t0 = DVector::from_element(model.nv, -0.2);

    let doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("chapter/m5_mobile_manipulator_3d.json")).unwrap(),
    )
    .unwrap();
    let params = serde_json::from_value(doc["cases"][0]["params"].clone()).unwrap();
    let wm = moma::closed_form::multibody_models::m5_model(&params).unwrap();
    let mut rod = ReducedOscData::new(&wm, &[0, 1, 2]);
    let tip = wm.model.frame_id("tip").unwrap();
    let qm = DVector::from_fn(wm.model.nq, |i, _| 0.2 * i as f64 + 0.1);
    let vr = DVector::from_element(wm.nr(), 0.1);
    let am = DVector::from_element(3, 0.2);
    let tm = DVector::from_element(wm.nr(), 0.4);

    let (count, ()) = allocations(|| {
        for _ in 0..3 {
            osc_fixed_base(&model, &mut data, &mut od, fid, &q, &v, &a, &t0).unwrap();
        }
    });
    assert_eq!(count, 0, "allocations during fixed-base OSC updates");
    let (count, ()) = allocations(|| {
        for _ in 0..3 {
            osc_reduced(&wm, &mut rod, tip, &qm, &vr, &am, &tm).unwrap();
        }
    });
    assert_eq!(count, 0, "allocations during reduced OSC updates");
}
