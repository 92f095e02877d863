//! The chapter's closed-form constrained models (m1, m2, m5 of
//! [`crate::closed_form`]) as [`ReducedSystem`]s for the simulator.

use nalgebra::SVector;

use crate::closed_form::lagrange::{self, PfaffianSystem};
use crate::closed_form::m1_unicycle::{Unicycle, UnicycleParams};
use crate::closed_form::m2_platform_arm::{PlatformArm, PlatformArmParams};
use crate::closed_form::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams};
use crate::closed_form::{ChapterModel, PlatformVelocity};
use crate::error::{Error, Result};
use crate::sim::reduced_system::ReducedSystem;

/// A closed-form Pfaffian system with `N` coordinates, `NV` reduced velocities and `NU`
/// inputs, with the names of its channels.
pub struct ClosedFormSystem<S, const N: usize, const NV: usize, const NU: usize> {
    /// The closed-form model.
    pub model: S,
    q_names: [&'static str; N],
    v_names: [&'static str; NV],
    u_names: [&'static str; NU],
}

fn platform_v_names(velocity: PlatformVelocity) -> [&'static str; 2] {
    match velocity {
        PlatformVelocity::LateralVelocity => ["v_F", "v_T"],
        PlatformVelocity::YawRate => ["v_F", "phi_dot"],
    }
}

/// The SI unit of a channel of the chapter models: positions in m, speeds `v_F`, `v_T`
/// in m/s, angles in rad, angle rates (`…_dot`) in rad/s, torques (`tau_…`) in N m.
///
/// # Panics
/// On a name that none of m1, m2, m5 uses (a test covers all of them).
fn chapter_unit(name: &str) -> &'static str {
    match name {
        "x" | "y" => "m",
        "v_F" | "v_T" => "m/s",
        "phi" | "phit" | "theta1" | "theta2" | "theta12" => "rad",
        n if n.ends_with("_dot") => "rad/s",
        n if n.starts_with("tau_") => "N m",
        other => panic!("no unit for chapter channel '{other}'"),
    }
}

/// The chapter's model m1 (unicycle platform), `q = [x, y, φ]`, `u = [τ_L, τ_R]`.
pub fn m1(params: UnicycleParams) -> Result<ClosedFormSystem<Unicycle, 3, 2, 2>> {
    let model = Unicycle::new(params)?;
    let v_names = platform_v_names(model.velocity);
    Ok(ClosedFormSystem {
        model,
        q_names: ["x", "y", "phi"],
        v_names,
        u_names: ["tau_L", "tau_R"],
    })
}

/// The chapter's model m2 (platform + horizontal two-link arm), `q = [x, y, φ, θ1, θ2]`.
pub fn m2(params: PlatformArmParams) -> Result<ClosedFormSystem<PlatformArm, 5, 4, 4>> {
    let model = PlatformArm::new(params)?;
    let [a, b] = platform_v_names(model.velocity);
    Ok(ClosedFormSystem {
        model,
        q_names: ["x", "y", "phi", "theta1", "theta2"],
        v_names: [a, b, "theta1_dot", "theta2_dot"],
        u_names: ["tau_L", "tau_R", "tau_1", "tau_2"],
    })
}

/// The chapter's model m5 (platform + capstan + two-link arm), `q = [x, y, φ, φt, θ1, θ12]`.
pub fn m5(params: MobileManipulatorParams) -> Result<ClosedFormSystem<MobileManipulator, 6, 5, 5>> {
    let model = MobileManipulator::new(params)?;
    let [a, b] = platform_v_names(model.velocity);
    Ok(ClosedFormSystem {
        model,
        q_names: ["x", "y", "phi", "phit", "theta1", "theta12"],
        v_names: [a, b, "phit_dot", "theta1_dot", "theta12_dot"],
        u_names: ["tau_L", "tau_R", "tau_c", "tau_s", "tau_e"],
    })
}

/// Builds the chapter model `name` from a table of parameters (the field names of the
/// reference vectors, e.g. `m`, `I`, `d`, `r_w`, `b` for m1). Names are those of the one
/// registry, [`ChapterModel::from_name`] (canonical names such as `m1_unicycle` and
/// aliases such as `m1`), the same that `moma eval` accepts; the dynamic constrained
/// models m1, m2 and m5 can be simulated. Unknown names, the other models and missing or
/// malformed parameters are errors naming the field.
pub fn chapter_system(name: &str, params: &serde_json::Value) -> Result<Box<dyn ReducedSystem>> {
    fn parse<T: crate::closed_form::ChapterParams>(
        name: &str,
        params: &serde_json::Value,
    ) -> Result<T> {
        if let Some(obj) = params.as_object() {
            for (k, v) in obj {
                if !v.is_number() {
                    return Err(Error::invalid(
                        format!("params.{k}"),
                        format!("must be a number for model {name}, got {v}"),
                    ));
                }
            }
        }
        crate::closed_form::parse_params(&format!("params of model {name}"), params)
    }
    match ChapterModel::from_name(name)? {
        ChapterModel::M1Unicycle => Ok(Box::new(m1(parse(name, params)?)?)),
        ChapterModel::M2PlatformArm => Ok(Box::new(m2(parse(name, params)?)?)),
        ChapterModel::M5MobileManipulator => Ok(Box::new(m5(parse(name, params)?)?)),
        other @ (ChapterModel::M3DiffDrive
        | ChapterModel::M4CartTwoLink
        | ChapterModel::M6SpaceManipulator) => {
            let simulable: Vec<String> = SIMULABLE
                .iter()
                .map(|m| format!("{} ({})", m.canonical_name(), m.short_name()))
                .collect();
            Err(Error::invalid(
                "model",
                format!(
                    "chapter model '{name}' ({}) is not a constrained dynamic model that the \
                     simulator runs; simulable models: {}",
                    other.canonical_name(),
                    simulable.join(", ")
                ),
            ))
        }
    }
}

/// The chapter models [`chapter_system`] builds.
pub const SIMULABLE: [ChapterModel; 3] = [
    ChapterModel::M1Unicycle,
    ChapterModel::M2PlatformArm,
    ChapterModel::M5MobileManipulator,
];

impl<S, const N: usize, const NV: usize, const NU: usize> ClosedFormSystem<S, N, NV, NU>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn qdot(&self, q: &[f64], v: &[f64]) -> SVector<f64, N> {
        let qa: [f64; N] = q.try_into().expect("length checked by the caller");
        let nb = self.model.velocity_basis_generic::<f64>(&qa);
        SVector::from_fn(|i, _| (0..NV).map(|j| nb[i][j] * v[j]).sum())
    }
}

impl<S, const N: usize, const NV: usize, const NU: usize> ReducedSystem
    for ClosedFormSystem<S, N, NV, NU>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn nq(&self) -> usize {
        N
    }
    fn nv(&self) -> usize {
        NV
    }
    fn nu(&self) -> usize {
        NU
    }
    fn q_names(&self) -> Vec<String> {
        self.q_names.iter().map(|s| s.to_string()).collect()
    }
    fn v_names(&self) -> Vec<String> {
        self.v_names.iter().map(|s| s.to_string()).collect()
    }
    fn u_names(&self) -> Vec<String> {
        self.u_names.iter().map(|s| s.to_string()).collect()
    }
    fn q_units(&self) -> Vec<&'static str> {
        self.q_names.iter().map(|n| chapter_unit(n)).collect()
    }
    fn v_units(&self) -> Vec<&'static str> {
        self.v_names.iter().map(|n| chapter_unit(n)).collect()
    }
    fn u_units(&self) -> Vec<&'static str> {
        self.u_names.iter().map(|n| chapter_unit(n)).collect()
    }
    fn dynamics(
        &mut self,
        q: &[f64],
        v: &[f64],
        u: &[f64],
        qdot: &mut [f64],
        vdot: &mut [f64],
    ) -> Result<()> {
        let (qd, vd) = lagrange::state_derivative(
            &self.model,
            &SVector::<f64, N>::from_column_slice(q),
            &SVector::<f64, NV>::from_column_slice(v),
            &SVector::<f64, NU>::from_column_slice(u),
        )?;
        qdot.copy_from_slice(qd.as_slice());
        vdot.copy_from_slice(vd.as_slice());
        Ok(())
    }
    fn energy(&mut self, q: &[f64], v: &[f64]) -> Result<(f64, f64)> {
        let qv = SVector::<f64, N>::from_column_slice(q);
        let qd = self.qdot(q, v);
        let h = lagrange::mass_matrix(&self.model, &qv);
        let qa: [f64; N] = q.try_into().expect("length checked by the caller");
        Ok((
            0.5 * qd.dot(&(h * qd)),
            self.model.potential_generic::<f64>(&qa),
        ))
    }
    fn input_power(&mut self, q: &[f64], v: &[f64], u: &[f64]) -> Result<f64> {
        let qv = SVector::<f64, N>::from_column_slice(q);
        let force = self.model.input_matrix(&qv) * SVector::<f64, NU>::from_column_slice(u);
        Ok(force.dot(&self.qdot(q, v)))
    }
    fn constraint_residual(&mut self, q: &[f64], v: &[f64]) -> Result<f64> {
        let qa: [f64; N] = q.try_into().expect("length checked by the caller");
        let c = self.model.constraint_row_generic::<f64>(&qa);
        let qd = self.qdot(q, v);
        Ok((0..N).map(|i| c[i] * qd[i]).sum::<f64>().abs())
    }
    fn nk(&self) -> usize {
        1
    }
    fn multipliers(&mut self, q: &[f64], v: &[f64], u: &[f64], out: &mut [f64]) -> Result<()> {
        let ev = lagrange::evaluate_constrained(
            &self.model,
            &SVector::<f64, N>::from_column_slice(q),
            &SVector::<f64, NV>::from_column_slice(v),
            &SVector::<f64, NU>::from_column_slice(u),
        )?;
        out[0] = ev.lambda;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_build_the_same_system_and_kinematic_models_are_refused() {
        let p = serde_json::json!({"m": 20.0, "I": 0.5, "d": 0.1, "r_w": 0.05, "b": 0.2});
        for name in ["m1", "m1_unicycle"] {
            let sys = chapter_system(name, &p).unwrap();
            assert_eq!((sys.nq(), sys.nv(), sys.nu()), (3, 2, 2), "{name}");
        }
        for name in ["m3", "m4_cart_two_link"] {
            let err = chapter_system(name, &p).err().unwrap().to_string();
            assert!(err.contains("simulable models"), "{name}: {err}");
        }
        let err = chapter_system("m7", &p).err().unwrap().to_string();
        assert!(err.contains("unknown model 'm7'"), "{err}");
    }
}
