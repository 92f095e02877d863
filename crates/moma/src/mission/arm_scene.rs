//! The map's boxes in a pick's arm scene: the `[[map.boxes]]` (`map.boxes[k]`) that the
//! robot can reach from any base pose it may grasp from ([`boxes_near_pick`]), added to
//! the task's scene where the placement search, the arm planner and the arm phases'
//! distance monitor measure it ([`scene_with`]).
//!
//! The frame: the task's scene is placed on the map at load (`task.pose`,
//! [`crate::collision::Scene::placed`]) and the arm is planned and monitored on the full
//! configuration, whose planar root is the base's pose on the map; a box's pose is
//! already the map's ([`super::heights::BoxSpec::object`]). So the boxes join the scene
//! as they are, not through `task.pose`.
//!
//! Near: every point of the robot (holding the object) lies within [`robot_reach`] of
//! its base frame's origin, and a base the grasp frame reaches the grasp from stands
//! within that distance of the grasp; so a box whose outline on the ground lies farther
//! than twice the reach from the grasp can touch the robot at no placement and is left
//! out.

use nalgebra::Vector2;

use crate::collision::footprint::hull_2d;
use crate::collision::{GeometryModel, Scene, SceneObject, outline_points};
use crate::multibody::{FrameIndex, JointType, Model};

/// A bound (m) on the distance from the platform's frame (the body of the planar root
/// joint) to every point of `gm`'s objects and to the frame `frame`, at every
/// configuration: per object, the lengths of the joint offsets on its chain below the
/// planar root, every prismatic joint's largest travel, its offset on its body and its
/// bounding ball's radius (a revolute joint turns about its own origin, so it moves no
/// point farther from it). `+∞` when a prismatic joint on the way has no travel limit
/// or a joint other than the root lets its body float.
#[must_use]
pub fn robot_reach(model: &Model, gm: &GeometryModel, frame: FrameIndex) -> f64 {
    let chain = |mut j: usize| {
        let mut length = 0.0;
        while j != 0 && model.joint_types[j] != JointType::Planar {
            let jt = model.joint_types[j];
            if matches!(jt, JointType::FreeFlyer) {
                return f64::INFINITY;
            }
            if jt.is_prismatic() {
                let iq = model.idx_q[j];
                length += model.lower_position_limit[iq]
                    .abs()
                    .max(model.upper_position_limit[iq].abs());
            }
            length += model.joint_placements[j].translation.norm();
            j = model.parents[j].0;
        }
        length
    };
    let fr = &model.frames[frame.0];
    let to_frame = chain(fr.parent_joint.0) + fr.placement.translation.norm();
    gm.objects
        .iter()
        .map(|o| {
            chain(o.joint.0) + o.placement.act_point(&o.bounding_centre).norm() + o.bounding_radius
        })
        .fold(to_frame, f64::max)
}

/// The boxes of `boxes` (world frame) whose outline on the ground comes within `radius`
/// (m) of `at` (world `[x, y]`), in their order.
#[must_use]
pub fn boxes_near(boxes: &[SceneObject], at: [f64; 2], radius: f64) -> Vec<SceneObject> {
    let p = Vector2::new(at[0], at[1]);
    let mut points = Vec::new();
    boxes
        .iter()
        .filter(|o| {
            o.shapes.iter().any(|s| {
                points.clear();
                outline_points(&s.shape, &s.pose, &mut points);
                polygon_distance(&hull_2d(points.iter().map(|q| q.xy())), &p) <= radius
            })
        })
        .cloned()
        .collect()
}

/// The map's boxes a pick's arm can reach (module docs): those of `boxes` whose outline
/// lies within twice `reach` ([`robot_reach`] of the robot holding the object) of the
/// grasp position `grasp` (world `[x, y]`).
#[must_use]
pub fn boxes_near_pick(boxes: &[SceneObject], grasp: [f64; 2], reach: f64) -> Vec<SceneObject> {
    boxes_near(boxes, grasp, 2.0 * reach)
}

/// `scene` with `extra` objects after its own.
#[must_use]
pub fn scene_with(scene: &Scene, extra: &[SceneObject]) -> Scene {
    Scene {
        objects: scene.objects.iter().chain(extra).cloned().collect(),
    }
}

/// Distance from `p` to the convex polygon `poly` (counter-clockwise), 0 inside.
pub(super) fn polygon_distance(poly: &[Vector2<f64>], p: &Vector2<f64>) -> f64 {
    match poly.len() {
        0 => f64::INFINITY,
        1 => (p - poly[0]).norm(),
        n => {
            let mut inside = n >= 3;
            let mut best = f64::INFINITY;
            for k in 0..n {
                let (a, b) = (poly[k], poly[(k + 1) % n]);
                let e = b - a;
                let w = p - a;
                if e.x * w.y - e.y * w.x < 0.0 {
                    inside = false;
                }
                let s = (w.dot(&e) / e.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
                best = best.min((w - e * s).norm());
            }
            if inside { 0.0 } else { best }
        }
    }
}
