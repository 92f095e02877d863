//! An object attached to the robot (MoveIt's attached collision object): a carried
//! object's shapes become one more link of the [`GeometryModel`], fixed to a joint's body,
//! so every query on the model (self distances, scene distances, the arm planner's check)
//! sees it.
//!
//! Its pairs with the robot's links are enabled except with the links it is carried by or
//! held between (MoveIt's touch links: the caller names them, e.g. the gripper and its
//! fingers) and with the links fixed to the same body (they never move relative to it,
//! as the fixed-together rule of [`GeometryModel::from_urdf`] has it).

use super::convex::Convex;
use super::geometry_model::{GeometryModel, GeometryObject, LinkGeometry, bounding_radius_about};
use crate::multibody::JointIndex;
use crate::spatial::SE3;
use crate::{Error, Result};

impl GeometryModel {
    /// This model with one more link, `name`, carried by `joint`: its shapes are given by
    /// their placement in the joint's frame. Its pairs with the links of `touch` (indices
    /// into [`GeometryModel::links`]) and with the links on `joint` are disabled, the others
    /// enabled; the existing pairs keep their flags. The new link is the last of `links`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the object when it has no shape or its name is
    /// already a link's, or a touch link out of range.
    pub fn with_attached(
        &self,
        name: &str,
        joint: JointIndex,
        shapes: &[(SE3, Convex)],
        touch: &[usize],
    ) -> Result<Self> {
        let field = || format!("attached object '{name}'");
        if shapes.is_empty() {
            return Err(Error::invalid(field(), "has no shape"));
        }
        if self.link_index(name).is_some() {
            return Err(Error::invalid(
                field(),
                "its name is already a link of the robot",
            ));
        }
        if let Some(t) = touch.iter().find(|&&t| t >= self.links.len()) {
            return Err(Error::invalid(
                field(),
                format!("touch link {t} is not a link of the model"),
            ));
        }
        let mut out = self.clone();
        let link = out.links.len();
        let first = out.objects.len();
        for (placement, shape) in shapes {
            let (centre, _) = shape.local_aabb();
            out.objects.push(GeometryObject {
                link,
                joint,
                placement: *placement,
                shape: shape.clone(),
                hull_faces: Vec::new(),
                bounding_radius: bounding_radius_about(shape, &centre),
                bounding_centre: centre,
                mesh: None,
            });
        }
        out.links.push(LinkGeometry {
            name: name.to_string(),
            joint,
            first,
            count: shapes.len(),
        });
        for (l, other) in self.links.iter().enumerate() {
            out.pairs.push([l, link]);
            out.enabled
                .push(other.joint != joint && !touch.contains(&l));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{
        GeometryData, PairSelection, compute_distances, update_geometry_placements,
    };
    use crate::kinematics::forward_kinematics;
    use crate::multibody::{Data, Model, RootJoint};
    use nalgebra::{DVector, Vector3};

    const TWO_LINKS: &str = r#"<robot name="r">
      <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
      <link name="arm"><collision><origin xyz="0.5 0 0"/><geometry><box size="1 0.1 0.1"/></geometry></collision></link>
      <link name="hand"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
        <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="arm"/><child link="hand"/>
        <origin xyz="1 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    </robot>"#;

    fn robot() -> (Model, GeometryModel) {
        let dir = std::env::temp_dir().join(format!("moma-attached-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let urdf = dir.join("r.urdf");
        std::fs::write(&urdf, TWO_LINKS).unwrap();
        let model = crate::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
        let gm = GeometryModel::from_urdf(&model, &urdf, &Default::default()).unwrap();
        (model, gm)
    }

    #[test]
    fn an_attached_box_moves_with_its_joint_and_meets_the_base() {
        let (model, gm) = robot();
        let hand = gm.link_index("hand").unwrap();
        let joint = gm.links[hand].joint;
        // a 0.2 m cube 0.3 m along the hand's x axis
        let cube = (
            SE3::from_translation(Vector3::new(0.3, 0.0, 0.0)),
            Convex::Box {
                half: Vector3::repeat(0.1),
            },
        );
        let carried = gm
            .with_attached("cube", joint, std::slice::from_ref(&cube), &[hand])
            .unwrap();
        let c = carried.link_index("cube").unwrap();
        assert_eq!(c, gm.links.len());
        let flag = |a: usize| {
            let p = carried.pairs.iter().position(|&p| p == [a, c]).unwrap();
            carried.enabled[p]
        };
        // the hand holds it; the arm and the base are checked against it
        assert!(!flag(hand));
        assert!(flag(gm.link_index("arm").unwrap()));
        assert!(flag(gm.link_index("base").unwrap()));
        // arm down (j1 = π/2 turns +x to −z): the hand at z = 0.5 − 1 = −0.5, the cube
        // 0.3 m further down, from −0.9 to −0.7; the base box spans −0.1..0.1
        let mut data = Data::new(&model);
        let q = DVector::from_vec(vec![std::f64::consts::FRAC_PI_2, 0.0]);
        forward_kinematics(&model, &mut data, &q);
        let mut gd = GeometryData::new(&carried);
        update_geometry_placements(&carried, &data, &mut gd);
        compute_distances(&carried, &mut gd, PairSelection::Enabled);
        let p = carried
            .pairs
            .iter()
            .position(|&p| p == [gm.link_index("base").unwrap(), c])
            .unwrap();
        assert!(
            (gd.results[p].distance - 0.6).abs() < 1e-9,
            "{}",
            gd.results[p].distance
        );
        assert!(
            gm.with_attached("hand", joint, std::slice::from_ref(&cube), &[])
                .is_err()
        );
        assert!(gm.with_attached("x", joint, &[], &[]).is_err());
    }
}
