//! Bad input: malformed or cyclic URDFs, bad inertials, unsupported joints, unknown
//! frames, wrong state sizes and non-finite values give clear errors, never a panic.

use moma::Error;
use moma::io::urdf::{model_from_urdf_file, model_from_urdf_str};
use moma::kinematics::check_state;
use moma::multibody::{JointIndex, JointLimits, JointType, ModelBuilder, RootJoint};
use moma::spatial::{Inertia, SE3};
use nalgebra::{Matrix3, Vector3};

fn robot(body: &str) -> String {
    format!("<robot name=\"t\">{body}</robot>")
}

const LINKS_AB: &str = r#"<link name="a"/><link name="b"/>"#;

fn err(text: &str) -> String {
    let e = model_from_urdf_str(text, RootJoint::Fixed, "bad.urdf").unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("bad.urdf"),
        "error does not name the file: {msg}"
    );
    msg
}

#[test]
fn malformed_xml() {
    let m = err("<robot name=\"t\"><link name=\"a\"></robot>");
    assert!(m.contains("malformed"), "{m}");
}

#[test]
fn cyclic_graph() {
    let m = err(&robot(&format!(
        r#"{LINKS_AB}
        <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
        <joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint>"#
    )));
    assert!(m.contains("cyclic"), "{m}");
}

#[test]
fn link_with_two_parents() {
    let m = err(&robot(
        r#"<link name="a"/><link name="b"/><link name="c"/>
        <joint name="j1" type="fixed"><parent link="a"/><child link="c"/></joint>
        <joint name="j2" type="fixed"><parent link="b"/><child link="c"/></joint>"#,
    ));
    assert!(m.contains("'c'") && m.contains("two joints"), "{m}");
}

#[test]
fn unknown_link_and_duplicates() {
    let m = err(&robot(
        r#"<link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="zz"/></joint>"#,
    ));
    assert!(m.contains("'zz'"), "{m}");
    let m = err(&robot(r#"<link name="a"/><link name="a"/>"#));
    assert!(m.contains("duplicate link name 'a'"), "{m}");
    let m = err(&robot(&format!(
        r#"{LINKS_AB}<link name="c"/>
        <joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>
        <joint name="j" type="fixed"><parent link="a"/><child link="c"/></joint>"#
    )));
    assert!(m.contains("duplicate joint name 'j'"), "{m}");
    let m = err(&robot(LINKS_AB));
    assert!(m.contains("several root links"), "{m}");
}

fn with_inertial(inertial: &str) -> String {
    robot(&format!(
        r#"<link name="a"/><link name="b">{inertial}</link>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
    ))
}

#[test]
fn bad_inertials() {
    let m = err(&with_inertial(
        r#"<inertial><mass value="1"/><inertia ixx="-1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ));
    assert!(
        m.contains("link 'b'") && m.contains("positive definite"),
        "{m}"
    );
    let m = err(&with_inertial(
        r#"<inertial><mass value="1"/><inertia ixx="1" ixy="2" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ));
    assert!(m.contains("positive definite"), "{m}");
    // a point mass (zero rotational inertia) loads
    let point = r#"<inertial><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>"#;
    let model = model_from_urdf_str(&with_inertial(point), RootJoint::Fixed, "ok.urdf").unwrap();
    assert!(model.total_mass() > 0.0);
    // A link with a round-off-level negative eigenvalue (−1e-8 kg·m², like TIAGo's 1 µg
    // antenna links) passes the link check; it loads when a fixed joint merges it into a
    // real body (the merged body is positive semidefinite) ...
    let tiny = r#"<inertial><mass value="1e-6"/><inertia ixx="5e-8" ixy="6e-8" ixz="0" iyy="5e-8" iyz="0" izz="5e-8"/></inertial>"#;
    let merged = robot(&format!(
        r#"<link name="a"/><link name="b"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
        <link name="antenna">{tiny}</link>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        <joint name="fix" type="fixed"><parent link="b"/><child link="antenna"/></joint>"#
    ));
    let model = model_from_urdf_str(&merged, RootJoint::Fixed, "ok.urdf").unwrap();
    assert!((model.total_mass() - (1.0 + 1e-6)).abs() < 1e-15);
    // ... but is refused as a body of its own, since the joint-space inertia matrix would
    // not be positive definite.
    let m = err(&with_inertial(tiny));
    assert!(
        m.contains("body inertia of joint 'j'") && m.contains("not positive semidefinite"),
        "{m}"
    );
    let m = err(&with_inertial(
        r#"<inertial><mass value="-2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ));
    assert!(m.contains("mass must be >= 0"), "{m}");
    let m = err(&with_inertial(
        r#"<inertial><mass value="nan"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ));
    assert!(m.contains("not finite"), "{m}");
    // an <inertial> without its <inertia>
    let m = err(&with_inertial(r#"<inertial><mass value="1"/></inertial>"#));
    assert!(m.contains("malformed"), "{m}");
    // no <inertial> at all: a massless link is fine
    let model = model_from_urdf_str(&with_inertial(""), RootJoint::Fixed, "ok.urdf").unwrap();
    assert_eq!(model.total_mass(), 0.0);
}

#[test]
fn unsupported_joints_and_bad_values() {
    for kind in ["floating", "planar", "spherical"] {
        let m = err(&robot(&format!(
            r#"{LINKS_AB}<joint name="base" type="{kind}"><parent link="a"/><child link="b"/></joint>"#
        )));
        assert!(
            m.contains(&format!("unsupported joint type '{kind}'")) && m.contains("'base'"),
            "{m}"
        );
    }
    let m = err(&robot(&format!(
        r#"{LINKS_AB}<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint>"#
    )));
    assert!(m.contains("joint 'j' axis"), "{m}");
    let m = err(&robot(&format!(
        r#"{LINKS_AB}<joint name="j" type="continuous"><parent link="a"/><child link="b"/><origin xyz="inf 0 0"/></joint>"#
    )));
    assert!(m.contains("joint 'j' origin"), "{m}");
    let m = err(&robot(&format!(
        r#"{LINKS_AB}<joint name="j" type="revolute"><parent link="a"/><child link="b"/><limit lower="1" upper="-1" effort="1" velocity="1"/></joint>"#
    )));
    assert!(m.contains("lower limit"), "{m}");
    // A revolute or prismatic joint without <limit> is refused naming it (urdfdom
    // refuses it too); a continuous joint needs none, and all-zero limits are accepted.
    for kind in ["revolute", "prismatic"] {
        let m = err(&robot(&format!(
            r#"{LINKS_AB}<joint name="elbow" type="{kind}"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>"#
        )));
        assert!(
            m.contains("joint 'elbow'") && m.contains("<limit>") && m.contains(kind),
            "{m}"
        );
        // a <limit> of a joint inside another element does not count
        let m = err(&robot(&format!(
            r#"{LINKS_AB}<joint name="elbow" type="{kind}"><parent link="a"/><child link="b"/></joint>
            <transmission name="t"><joint name="elbow"><limit/></joint></transmission>"#
        )));
        assert!(m.contains("joint 'elbow'"), "{m}");
        let zero = robot(&format!(
            r#"{LINKS_AB}<joint name="elbow" type="{kind}"><parent link="a"/><child link="b"/><limit lower="0" upper="0" effort="0" velocity="0"/></joint>"#
        ));
        assert!(model_from_urdf_str(&zero, RootJoint::Fixed, "zero.urdf").is_ok());
    }
    let cont = robot(&format!(
        r#"{LINKS_AB}<joint name="wheel" type="continuous"><parent link="a"/><child link="b"/></joint>"#
    ));
    let m = model_from_urdf_str(&cont, RootJoint::Fixed, "cont.urdf").unwrap();
    assert!(m.lower_position_limit[0].is_infinite() && m.upper_position_limit[0].is_infinite());
    let e = model_from_urdf_str("<robot name=\"t\"/>", RootJoint::Fixed, "empty.urdf").unwrap_err();
    assert!(e.to_string().contains("no <link>"), "{e}");
}

#[test]
fn missing_file_and_frame() {
    let e = model_from_urdf_file("does/not/exist.urdf", RootJoint::Fixed).unwrap_err();
    assert!(matches!(e, Error::Io { .. }));
    assert!(e.to_string().contains("does/not/exist.urdf"));
    let model = model_from_urdf_str(&with_inertial(""), RootJoint::Planar, "ok.urdf").unwrap();
    let e = model.frame_id("nope").unwrap_err();
    assert_eq!(e.to_string(), "unknown frame 'nope'");
    assert!(model.joint_id("nope").is_err());
    assert!("wheeled".parse::<RootJoint>().is_err());
}

#[test]
fn state_checks() {
    let model = model_from_urdf_str(&with_inertial(""), RootJoint::FreeFlyer, "ok.urdf").unwrap();
    assert_eq!((model.nq, model.nv), (8, 7));
    let q = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5];
    let v = [0.0; 7];
    check_state(&model, "s", Some(&q), Some(&v), None, None).unwrap();
    let e = check_state(&model, "states[2]", Some(&q[..7]), None, None, None).unwrap_err();
    assert_eq!(e.to_string(), "states[2] q: expected length 8, got 7");
    let mut bad = v;
    bad[3] = f64::NAN;
    let e = check_state(&model, "states[0]", Some(&q), Some(&bad), None, None).unwrap_err();
    assert_eq!(e.to_string(), "non-finite value in states[0] v[3]");
    let mut qn = q;
    qn[6] = 2.0;
    let e = check_state(&model, "s", Some(&qn), None, None, None).unwrap_err();
    assert!(e.to_string().contains("unit norm"), "{e}");
}

#[test]
fn builder_rejects_bad_input() {
    let mut b = ModelBuilder::new("t");
    assert!(
        b.add_joint(
            JointIndex(3),
            "j",
            JointType::RevoluteZ,
            SE3::identity(),
            JointLimits::unlimited()
        )
        .is_err()
    );
    let j = b
        .add_joint(
            JointIndex(0),
            "j",
            JointType::RevoluteZ,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    assert!(
        b.add_joint(
            JointIndex(0),
            "j",
            JointType::RevoluteZ,
            SE3::identity(),
            JointLimits::unlimited()
        )
        .is_err()
    );
    let mut not_rot = SE3::identity();
    not_rot.rotation[(0, 0)] = 2.0;
    assert!(
        b.add_joint(
            j,
            "k",
            JointType::RevoluteX,
            not_rot,
            JointLimits::unlimited()
        )
        .is_err()
    );
    let limits = JointLimits {
        lower: vec![0.0, 1.0],
        ..JointLimits::default()
    };
    assert!(
        b.add_joint(j, "k", JointType::RevoluteX, SE3::identity(), limits)
            .is_err()
    );
    let bad = Inertia::new(-1.0, Vector3::zeros(), Matrix3::identity());
    assert!(b.append_body_inertia(j, &bad, &SE3::identity()).is_err());
    let nan = Inertia::new(f64::NAN, Vector3::zeros(), Matrix3::identity());
    assert!(b.append_body_inertia(j, &nan, &SE3::identity()).is_err());
    assert!(JointType::revolute(Vector3::zeros()).is_err());
    assert!(JointType::prismatic(Vector3::new(f64::NAN, 0.0, 1.0)).is_err());
    assert_eq!(
        JointType::revolute(Vector3::new(0.0, 0.0, 2.0)).unwrap(),
        JointType::RevoluteZ
    );
}
