//! The URDF loader on arbitrary text, with each root joint.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::multibody::RootJoint;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let root = [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer][usize::from(sel % 3)];
    let _ = moma::io::urdf::model_from_urdf_str(text, root, "fuzz.urdf");
});
