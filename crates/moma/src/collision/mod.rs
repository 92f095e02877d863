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
//!
//! # How it is built
//!
//! * [`GeometryModel`] holds, per link with `<collision>` elements, its shapes with their
//!   `joint_from_object` placements (a link merged into its parent body by a fixed joint
//!   keeps its fixed offset from its `body` frame), and every link pair with an `enabled`
//!   flag. [`GeometryData`] holds the world placements, the per-pair results and one GJK
//!   warm start (last direction, support-climb vertices) per shape pair, so queries
//!   allocate nothing once EPA's buffers have grown.
//! * The URDF's geometry is read in its own `quick-xml` pass (the rigid-body loader strips
//!   it); meshes with `stl_io` (binary and ASCII STL) and `tobj` (OBJ); hulls with
//!   `parry3d-f64`'s quickhull (its glam types converted in [`mesh`], nalgebra everywhere
//!   else), completed with any input vertex left outside so the support function is the
//!   mesh's.
//! * The distances are not parry's: the reference is graded at 1e-6 m, which a
//!   default-tolerance GJK/EPA misses, so [`gjk`] is a GJK to a 1e-12 m duality gap whose
//!   closest points are explicit convex combinations of support points (never below the
//!   true distance) and an EPA to the same gap, on the shapes' support functions (hulls
//!   climb along their edge graph from the last vertex); spheres and capsules are a point
//!   or segment core plus a margin ([`convex`]). Against coal 3.0.3 on Fetch the worst
//!   distance error is 1.1e-11 m (`docs/collision.md`).
//! * Enabled pairs: not joined by one URDF joint, not on the same moma joint (fixed to
//!   each other), not disabled by the SRDF; on Fetch this leaves exactly the 76 pairs that
//!   the SRDF alone leaves (MoveIt's SRDF already disables the adjacent and fixed pairs).
//! * Exact triangle-mesh distances ([`exact`], the `--mesh exact` option), for link pairs
//!   and for (link, scene object) pairs (through the scene's own nearest search, whose
//!   hull bounds hold for the meshes inside the hulls): each mesh keeps a tree of its
//!   triangles (`bvh.rs`, the scene objects' tree builder), a query descends the trees
//!   nearest first and measures the triangles left with [`gjk`] (a [`convex::Triangle`]
//!   is a flat convex shape). They match coal's BVH distances to 5.0e-13 m (Fetch and
//!   Panda self pairs) and 6.6e-11 m (Fetch scenes) and allocate nothing; the hull path
//!   stays the default (hulls are cheaper and bound the meshes from below).
//! * Scene objects ([`scene`]) keep a bounding-volume tree each; a link's nearest search
//!   prunes subtrees by its bounding ball and by a separating-axis bound along the best
//!   pair's normal (the previous query's to start), which skips a whole layer of voxels
//!   at once.
//! * An object the robot carries ([`attached`], MoveIt's attached collision object) is
//!   one more link of the model, fixed to the carrying joint, its pairs with the touch
//!   links disabled; a scene object may allow links to touch it
//!   ([`SceneObject::touch_links`], MoveIt's allowed-collision entries).
//! * [`ball_cover`] covers a hull with a few balls (one per slab along its longest axis),
//!   a cheap lower bound on its distances that the arm planner's check tries before GJK;
//!   [`ball_gap`] bounds a ball's gap to a primitive exactly and to a hull by its 26
//!   bounding planes, in closed form.

pub mod attached;
pub mod ball_cover;
pub mod ball_gap;
mod bvh;
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
pub mod separating_plane;
pub mod srdf;
pub mod urdf_geometry;

pub use convex::Convex;
pub use exact::{
    ExactGeometry, ExactScene, compute_exact_distances, compute_exact_scene_distances,
};
pub use footprint::{base_ground_pose, footprint, footprint_in, outline_points};
pub use geometry_data::{
    GeometryData, PairSelection, compute_collision, compute_distances, distance_derivative,
    pair_derivative, update_geometry_placements,
};
pub use geometry_model::{GeometryModel, GeometryObject, GeometryOptions, LinkGeometry};
pub use gjk::PairDistance;
pub use gradient::{
    ClosestPair, closest_pair, min_distance_gradient, pair_distance_derivative,
    scene_distance_derivative,
};
pub use point_cloud::read_points;
pub use scene::{
    Scene, SceneData, SceneObject, SceneOptions, compute_scene_distances,
    compute_scene_distances_below, point_cloud_object, read_scene, scene_collision, voxel_object,
};
