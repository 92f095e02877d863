//! The feedback laws of [`crate::control`] as [`FeedbackLaw`]s of the closed-loop
//! simulator, with the references they track.
//!
//! * [`PlatformController`]: a unicycle law (Kanayama, Samson, Astolfi, Aicardi) or
//!   regulated pure pursuit drives a wheeled URDF robot **dynamically**. The law's
//!   `(v, ω)` command (for the axle midpoint) is limited in wheel speed through the wheel
//!   map of the drive, then tracked by an inner computed-torque loop on the reduced
//!   dynamics: `Qr = Mr a + (cr + Gr)` with `a = [k_v (v_c − v), k_v (ω_c − ω),
//!   k_p (q*_arm − q_arm) − k_d q̇_arm]` (the arm holds its initial posture), the actuator
//!   inputs from `N_Cᵀ S u = Qr`, wheel torques clipped to their limit. V and V̇ are the
//!   law's own (kinematic) Lyapunov function and rate at the actual pose, so the
//!   monitor shows what the inner loop's lag and the limits do to them.
//! * [`OscController`]: operational-space control of an end-effector point on a wheeled
//!   robot through the reduced model ([`crate::control::osc::osc_reduced`]), with
//!   `a_des = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)` and a null-space posture torque;
//!   `V = ½|ė|² + ½ k_p |e|²`, `V̇ = −k_v |ė|²` (exact for continuous, unsaturated
//!   feedback on the exact model).
//! * [`M5TaskController`]: the chapter's task-space laws on model m5 ([`crate::control::task`]):
//!   PD+ (5.122 corrected), task-space computed torque, and the decoupled control
//!   (5.129–5.133) naive, with desired-acceleration feed-forward, or compensated.
//!
//! One law a file: [`platform`], [`osc`], [`m5_task`]; the references they track in
//! [`references`].

pub mod m5_task;
pub mod osc;
pub mod platform;
pub mod references;

pub use m5_task::{M5TaskController, TaskLaw};
pub use osc::{FixedOscController, OscController, OscGains};
pub(crate) use platform::InnerLoop;
pub use platform::{PlatformController, PlatformLaw, VelocityServo};
pub use references::{PointReference, SampledTrajectory, TrackingReference};
