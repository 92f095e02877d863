//! A contact plant: the robot on a free-flyer root whose drive wheels and casters touch
//! the ground plane z = 0 through a compliant contact law, so it can roll, slide, lift a
//! wheel and tip (the reduced model of [`crate::mobile`] can do none of these).
//!
//! * **Wheels** ([`WheelSpec`]): disks on revolute joints; the contact point is the lowest
//!   point of the wheel circle; frictional.
//! * **Casters** ([`CasterSpec`]): ball casters, frictionless spheres.
//! * **Law** (`docs/contact.md`): normal force `N = max(0, k δ + c δ̇)` for a penetration
//!   δ > 0 (a linear spring-damper, Kelvin–Voigt, that never pulls); friction
//!   `F_t = −μ N v_t / max(|v_t|, v_ε)` on the slip velocity v_t of the body's material
//!   point at the contact (Coulomb, regularised below v_ε).
//! * **Step**: contact forces at the start of the step, accelerations by the
//!   articulated-body algorithm with the contact forces as generalised forces `Jᵀ f`,
//!   semi-implicit Euler at a fixed `dt`. The stable-step bounds are checked before a
//!   run ([`ContactPlant::check_step`]).
//! * **Files** ([`PlantKind`], [`ContactSpec`]): the plant choice and the `[contact]`
//!   table, one schema for the `moma simulate` scenario and the `moma mission` file.
//!
//! [`ContactPlant`] is immutable; a run is a [`ContactState`] (allocated once), advanced
//! by [`ContactPlant::step`], which does not allocate.

mod geometry;
mod law;
mod params;
mod plant;
mod point_force;
mod report;
mod spec;
mod start;
mod step;
mod table;

pub use geometry::{disk_lowest_point, sphere_lowest_point};
pub use law::{friction_force, normal_force};
pub use params::{ContactParams, friction_step_bound, spring_damper_step_bound};
pub use plant::{ContactPlant, ContactState};
pub use report::ContactReport;
pub use spec::{CasterSpec, WheelSpec};
pub use table::{ContactSpec, PlantKind};
