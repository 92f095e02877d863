//! The reduced-dynamics layer against the chapter's reference vectors (m1, m2, m5):
//! fed the joint-space terms H, h, G, Q and the basis N_C, Ṅ_C of each case, it must
//! reproduce Mr, Cr, cr, Gr, Qr, v̇, q̈, λ and the constraint force; λ also agrees with
//! the full-coordinate DAE formula.

use moma::mobile::{JointSpaceTerms, ReducedDynamics, lagrange_multipliers_dae};
use nalgebra::{DMatrix, DVector};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/data/mobile/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn vector(v: &Value) -> DVector<f64> {
    match v {
        Value::Array(a) => DVector::from_iterator(a.len(), a.iter().map(|x| x.as_f64().unwrap())),
        Value::Number(n) => DVector::from_element(1, n.as_f64().unwrap()),
        _ => panic!("not a vector: {v}"),
    }
}

fn matrix(v: &Value) -> DMatrix<f64> {
    let rows = v.as_array().unwrap();
    let r = rows.len();
    if rows[0].is_number() {
        // A row vector stored flat.
        return DMatrix::from_row_slice(1, r, vector(v).as_slice());
    }
    let c = rows[0].as_array().unwrap().len();
    DMatrix::from_fn(r, c, |i, j| rows[i][j].as_f64().unwrap())
}

fn close(what: &str, got: &DMatrix<f64>, want: &DMatrix<f64>, rel: f64) {
    assert_eq!(got.shape(), want.shape(), "{what} shape");
    let err = (got - want).norm();
    let scale = want.norm().max(1.0);
    assert!(
        err <= rel * scale,
        "{what}: error {err:e} (scale {scale})\n got {got}\nwant {want}"
    );
}

fn closev(what: &str, got: &DVector<f64>, want: &DVector<f64>, rel: f64) {
    close(
        what,
        &DMatrix::from_column_slice(got.len(), 1, got.as_slice()),
        &DMatrix::from_column_slice(want.len(), 1, want.as_slice()),
        rel,
    );
}

fn check_model(file: &str, mass_key: &str) -> usize {
    let data = load(file);
    let mut count = 0;
    for case in data["cases"].as_array().unwrap() {
        let out = &case["outputs"];
        let q = vector(&case["state"]["q"]);
        let v = vector(&case["state"]["v"]);
        let n = q.len();
        let h_mat = matrix(&out[mass_key]);
        let zero = DVector::zeros(n);
        let h_vec = out.get("h").map(vector).unwrap_or_else(|| zero.clone());
        let g = out.get("G").map(vector).unwrap_or_else(|| zero.clone());
        let q_force = vector(&out["Q"]);
        let n_c = matrix(&out["N_C"]);
        let n_c_dot = matrix(&out["Ndot_C"]);
        let c = matrix(&out["C"]);
        let r = n_c.ncols();
        let terms = JointSpaceTerms {
            mass_matrix: &h_mat,
            velocity_terms: &h_vec,
            gravity: &g,
            force: &q_force,
        };
        let mut rd = ReducedDynamics::new(n, r, 1);
        rd.compute(&terms, &n_c, &n_c_dot, &v).unwrap();
        let c_cor = out
            .get("C_coriolis")
            .map(matrix)
            .unwrap_or_else(|| DMatrix::zeros(n, n));
        rd.compute_coriolis(&h_mat, &c_cor, &n_c, &n_c_dot);
        let tol = 1e-9;
        close("Mr", &rd.mass_matrix, &matrix(&out["Mr"]), tol);
        close("Cr", &rd.coriolis, &matrix(&out["Cr"]), tol);
        closev("cr", &rd.velocity_terms, &vector(&out["cr"]), tol);
        closev("Cr v", &(&rd.coriolis * &v), &vector(&out["cr"]), tol);
        if let Some(gr) = out.get("Gr") {
            closev("Gr", &rd.gravity, &vector(gr), tol);
        }
        closev("Qr", &rd.force, &vector(&out["Qr"]), tol);
        closev("vdot", &rd.vdot, &vector(&out["vdot"]), tol);
        closev("qddot", &rd.qddot, &vector(&out["qddot"]), tol);
        rd.compute_multipliers(&terms, &c).unwrap();
        closev("lambda", &rd.lambda, &vector(&out["lambda"]), tol);
        if let Some(cf) = out.get("constraint_force") {
            closev("constraint force", &rd.constraint_force, &vector(cf), tol);
        }
        // The DAE formula with Ċ q̇ for C = [−sin φ, cos φ, −d, 0…].
        let qdot = &n_c * &v;
        let phi = q[2];
        let cdot_qdot =
            DVector::from_element(1, (-phi.cos() * qdot[0] - phi.sin() * qdot[1]) * qdot[2]);
        let lambda_dae = lagrange_multipliers_dae(&terms, &c, &cdot_qdot).unwrap();
        closev("lambda (DAE)", &lambda_dae, &rd.lambda, 1e-9);
        // C q̇ = 0 and C N_C = 0.
        assert!((&c * &n_c).norm() < 1e-12);
        count += 1;
    }
    count
}

#[test]
fn m1_unicycle_reduced_dynamics_match_the_reference() {
    assert!(check_model("m1_unicycle.json", "M") >= 5);
}

#[test]
fn m2_platform_arm_reduced_dynamics_match_the_reference() {
    assert!(check_model("m2_platform_planar_arm.json", "H") >= 5);
}

#[test]
fn m5_mobile_manipulator_reduced_dynamics_match_the_reference() {
    assert!(check_model("m5_mobile_manipulator_3d.json", "H") >= 5);
}

#[test]
fn indefinite_reduced_mass_is_reported_not_divided_by() {
    // A basis with a zero column makes Mr singular.
    let h = DMatrix::<f64>::identity(3, 3);
    let z = DVector::zeros(3);
    let terms = JointSpaceTerms {
        mass_matrix: &h,
        velocity_terms: &z,
        gravity: &z,
        force: &z,
    };
    let n_c = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let mut rd = ReducedDynamics::new(3, 2, 1);
    let err = rd
        .compute(&terms, &n_c, &DMatrix::zeros(3, 2), &DVector::zeros(2))
        .unwrap_err();
    assert!(matches!(err, moma::Error::Singular { .. }), "{err}");
}

#[test]
fn numeric_null_space_basis_gives_the_same_accelerations_and_multipliers() {
    // q̈ and λ do not depend on the choice of basis: the orthonormal numeric N_C with its
    // parallel-transport Ṅ_C must reproduce the reference (computed with the analytic one).
    use moma::mobile::NullSpaceBasis;
    for file in [
        "m2_platform_planar_arm.json",
        "m5_mobile_manipulator_3d.json",
    ] {
        let data = load(file);
        for case in data["cases"].as_array().unwrap() {
            let out = &case["outputs"];
            let q = vector(&case["state"]["q"]);
            let n = q.len();
            let qdot = vector(&out["qdot"]);
            let c = matrix(&out["C"]);
            let phi = q[2];
            let mut c_dot = DMatrix::zeros(1, n);
            c_dot[(0, 0)] = -phi.cos() * qdot[2];
            c_dot[(0, 1)] = -phi.sin() * qdot[2];
            let mut nb = NullSpaceBasis::new(n, 1).unwrap();
            nb.update(&c, &c_dot).unwrap();
            let v = nb.basis.transpose() * &qdot;
            assert!(
                (&nb.basis * &v - &qdot).norm() < 1e-12,
                "q̇ lies in the null space"
            );
            let h_mat = matrix(&out["H"]);
            let h_vec = vector(&out["h"]);
            let g = out
                .get("G")
                .map(vector)
                .unwrap_or_else(|| DVector::zeros(n));
            let q_force = vector(&out["Q"]);
            let terms = JointSpaceTerms {
                mass_matrix: &h_mat,
                velocity_terms: &h_vec,
                gravity: &g,
                force: &q_force,
            };
            let mut rd = ReducedDynamics::new(n, n - 1, 1);
            rd.compute(&terms, &nb.basis, &nb.basis_dot, &v).unwrap();
            rd.compute_multipliers(&terms, &c).unwrap();
            closev(
                "qddot (numeric basis)",
                &rd.qddot,
                &vector(&out["qddot"]),
                1e-9,
            );
            closev(
                "lambda (numeric basis)",
                &rd.lambda,
                &vector(&out["lambda"]),
                1e-9,
            );
        }
    }
}
