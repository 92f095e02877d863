//! Collision geometry: the robot's shapes from the URDF (primitives and meshes, a mesh
//! used as its convex hull), the link pairs to check (minus adjacent, fixed-together and
//! SRDF-disabled pairs), signed distances with world witness points, in-collision with
//! early exit, the distance's derivative, the robot's footprint, and exact triangle-mesh
//! distances as an option ([`exact`]).
//!
//! Pinocchio's idiom: an immutable [`GeometryModel`] attached to the joints of a
//! rigid-body [`Model`](crate::multibody::Model), a [`GeometryData`] workspace, and free
//! functions that read the joint placements of the rigid-body `Data` after forward
//! kinematics. Meshes are read with `stl_io` / `tobj`, hulled with `parry3d-f64`, and the
//! distances are this module's own GJK/EPA on the shapes' support functions, converged
//! to a 1e-12 m duality gap (see [`gjk`]).

pub mod convex;
pub mod exact;
pub mod footprint;
pub mod geometry_data;
pub mod geometry_model;
pub mod gjk;
pub mod gradient;
pub mod mesh;
pub mod point_cloud;
pub mod scene;
pub mod srdf;
pub mod urdf_geometry;

pub use convex::Convex;
pub use exact::{ExactGeometry, compute_exact_distances};
pub use footprint::{base_ground_pose, footprint, footprint_in, outline_points};
pub use geometry_data::{
    GeometryData, PairSelection, compute_collision, compute_distances, distance_derivative,
    pair_derivative, update_geometry_placements,
};
pub use geometry_model::{GeometryModel, GeometryObject, GeometryOptions, LinkGeometry};
pub use gjk::PairDistance;
pub use gradient::{ClosestPair, closest_pair, min_distance_gradient, scene_distance_derivative};
pub use point_cloud::read_points;
pub use scene::{
    Scene, SceneData, SceneObject, SceneOptions, compute_scene_distances, point_cloud_object,
    read_scene, scene_collision, voxel_object,
};
