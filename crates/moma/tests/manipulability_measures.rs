//! Manipulability measures against the theory notes' worked numbers (section 4.5) and the
//! chapter's model m3 reference vectors, plus the properties of section 4.6.

use moma::manipulability::{JacobianSvd, Measure, evaluate, report};
use nalgebra::DMatrix;
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!(
        "{}/tests/data/manipulability/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    let m = rows.len();
    let n = rows[0].len();
    DMatrix::from_fn(m, n, |i, j| rows[i][j])
}

fn vecf(v: &Value) -> Vec<f64> {
    serde_json::from_value(v.clone()).unwrap()
}

fn close(a: f64, b: f64, rel: f64, what: &str) {
    let tol = rel * b.abs().max(1e-300) + 1e-15;
    assert!((a - b).abs() <= tol, "{what}: got {a}, expected {b}");
}

fn check_example_block(j: &DMatrix<f64>, m: &Value) {
    let svd = JacobianSvd::new(j).unwrap();
    let sv = vecf(&m["singular_values"]);
    for (i, s) in sv.iter().enumerate() {
        close(svd.singular_values[i], *s, 1e-9, "singular value");
    }
    let f = |k: &str| m[k].as_f64().unwrap();
    close(
        evaluate(&Measure::Yoshikawa, j).unwrap(),
        f("w_yoshikawa"),
        1e-9,
        "w",
    );
    close(
        evaluate(&Measure::InverseCondition, j).unwrap(),
        f("inverse_condition_sigma_min_over_max"),
        1e-9,
        "1/kappa",
    );
    close(
        evaluate(&Measure::Condition, j).unwrap(),
        f("condition_number"),
        1e-9,
        "kappa",
    );
    close(
        evaluate(&Measure::MinSingularValue, j).unwrap(),
        f("sigma_min"),
        1e-9,
        "sigma_min",
    );
    close(
        evaluate(&Measure::GeometricMean, j).unwrap(),
        f("geometric_mean_w_pow_1_over_m"),
        1e-9,
        "geometric mean",
    );
    close(
        evaluate(&Measure::Eccentricity, j).unwrap(),
        f("eccentricity_sqrt_1_minus_ratio_sq"),
        1e-9,
        "eccentricity",
    );
    let u = vecf(&m["direction"]);
    close(
        evaluate(&Measure::Directional(u.clone()), j).unwrap(),
        f("velocity_radius_along_u"),
        1e-9,
        "r_v",
    );
    close(
        svd.velocity_support(&u).unwrap(),
        f("velocity_support_along_u_norm_JT_u"),
        1e-9,
        "|J^T u|",
    );
    close(
        svd.force_radius(&u).unwrap(),
        f("force_ellipsoid_radius_along_u"),
        1e-9,
        "r_f",
    );
    close(
        svd.projection_sum(&u).unwrap(),
        f("projection_sum_sum_sigma_abs_u_dot_Ui"),
        1e-9,
        "projection sum",
    );
    // Ellipsoid axes: columns of U, equal up to sign.
    let axes = mat(&m["ellipsoid_axes_U_columns"]);
    let e = svd.ellipsoid();
    for i in 0..axes.ncols() {
        let d = e.axes.column(i).dot(&axes.column(i)).abs();
        close(d, 1.0, 1e-9, "ellipsoid axis");
        close(e.lengths[i], sv[i], 1e-9, "ellipsoid length");
    }
    // The full report agrees with the single measures.
    let r = report(j, Some(&u)).unwrap();
    close(r.yoshikawa.unwrap(), f("w_yoshikawa"), 1e-9, "report w");
    assert_eq!(
        r.det_jtj.is_none(),
        j.nrows() < j.ncols(),
        "det(J^T J) only for m >= n"
    );
}

#[test]
fn theory_worked_numbers_arm_and_mobile() {
    let d = load("manipulability_examples.json");
    // Planar 2R arm: build J from the link lengths and angles, compare with the stored J.
    let arm = &d["arm"];
    let l1 = arm["l1"].as_f64().unwrap();
    let l2 = arm["l2"].as_f64().unwrap();
    let q = vecf(&arm["q"]);
    let j_arm = planar_2r_jacobian(l1, l2, q[0], q[1]);
    let j_ref = mat(&arm["J"]);
    assert!((&j_arm - &j_ref).abs().max() < 1e-12);
    check_example_block(&j_arm, &arm["measures"]);
    close(
        evaluate(&Measure::DetJtJ, &j_arm).unwrap(),
        arm["det_J"].as_f64().unwrap().powi(2),
        1e-9,
        "det(J^T J) = det(J)^2 for square J",
    );

    // Same arm on a differential-drive base, inputs (v, ω, q̇1, q̇2): J̄ = [[cosθ; sinθ], [-r_y; r_x], R(θ) J_arm].
    let mobile = &d["mobile"];
    let th = mobile["phi"].as_f64().unwrap();
    let a = mobile["a_axle_to_arm_base"].as_f64().unwrap();
    let jbar = planar_mobile_jacobian(l1, l2, q[0], q[1], th, a);
    assert!((&jbar - &mat(&mobile["Jbar"])).abs().max() < 1e-12);
    check_example_block(&jbar, &mobile["measures"]);

    // Wheel-rate inputs: (θ̇_R, θ̇_L) → (v, ω) = (r/2 (R+L), r/(2b) (R−L)).
    let wi = &d["mobile_wheel_inputs"];
    let rw = wi["rw"].as_f64().unwrap();
    let b = wi["b_half_track"].as_f64().unwrap();
    let mut w = DMatrix::<f64>::identity(4, 4);
    w[(0, 0)] = rw / 2.0;
    w[(0, 1)] = rw / 2.0;
    w[(1, 0)] = rw / (2.0 * b);
    w[(1, 1)] = -rw / (2.0 * b);
    let jw = &jbar * w;
    assert!((&jw - &mat(&wi["Jbar"])).abs().max() < 1e-12);
    check_example_block(&jw, &wi["measures"]);

    // The platform adds columns: w_mm ≥ w_arm.
    assert!(
        evaluate(&Measure::Yoshikawa, &jbar).unwrap()
            >= evaluate(&Measure::Yoshikawa, &j_arm).unwrap()
    );
}

fn planar_2r_jacobian(l1: f64, l2: f64, q1: f64, q2: f64) -> DMatrix<f64> {
    let (s1, c1) = q1.sin_cos();
    let (s12, c12) = (q1 + q2).sin_cos();
    DMatrix::from_row_slice(
        2,
        2,
        &[-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12],
    )
}

fn planar_mobile_jacobian(l1: f64, l2: f64, q1: f64, q2: f64, th: f64, a: f64) -> DMatrix<f64> {
    let (s, c) = th.sin_cos();
    let ja = planar_2r_jacobian(l1, l2, q1, q2);
    // End effector relative to the axle midpoint, platform axes then world axes.
    let px = a + l1 * q1.cos() + l2 * (q1 + q2).cos();
    let py = l1 * q1.sin() + l2 * (q1 + q2).sin();
    let rx = c * px - s * py;
    let ry = s * px + c * py;
    let rot = DMatrix::from_row_slice(2, 2, &[c, -s, s, c]);
    let jr = rot * ja;
    DMatrix::from_row_slice(
        2,
        4,
        &[
            c,
            -ry,
            jr[(0, 0)],
            jr[(0, 1)],
            s,
            rx,
            jr[(1, 0)],
            jr[(1, 1)],
        ],
    )
}

/// m3's whole-body Jacobian (5×5), rebuilt from the closed form of chapter-models m3(b).
fn m3_jacobian(p: &Value, q: &[f64]) -> DMatrix<f64> {
    let g = |k: &str| p[k].as_f64().unwrap();
    let (rw, b, d, l, l1, l2) = (g("r_w"), g("b"), g("d"), g("L"), g("L1"), g("L2"));
    let (phi, phi1, th1, th2) = (q[2], q[3], q[4], q[5]);
    let th12 = th1 - th2;
    let (s, c) = phi.sin_cos();
    let k = rw / (2.0 * b);
    let dl = d + l;
    let jp = [
        [k * (b * c + dl * s), k * (b * c - dl * s)],
        [k * (b * s - dl * c), k * (b * s + dl * c)],
    ];
    let rho = l1 * th1.sin() + l2 * th12.sin();
    let eta = l1 * th1.cos() + l2 * th12.cos();
    let phit = phi + phi1;
    let (st, ct) = phit.sin_cos();
    let mut j = DMatrix::zeros(5, 5);
    for r in 0..2 {
        for cidx in 0..2 {
            j[(r, cidx)] = jp[r][cidx];
        }
    }
    j[(2, 0)] = jp[0][0] + k * rho * st;
    j[(2, 1)] = jp[0][1] - k * rho * st;
    j[(2, 2)] = -rho * st;
    j[(2, 3)] = eta * ct;
    j[(2, 4)] = -l2 * th12.cos() * ct;
    j[(3, 0)] = jp[1][0] - k * rho * ct;
    j[(3, 1)] = jp[1][1] + k * rho * ct;
    j[(3, 2)] = rho * ct;
    j[(3, 3)] = eta * st;
    j[(3, 4)] = -l2 * th12.cos() * st;
    j[(4, 3)] = -rho;
    j[(4, 4)] = l2 * th12.sin();
    j
}

/// m3's arm Jacobian in platform axes, d(E−B)/d[φ1, θ1, θ2].
fn m3_jmv(p: &Value, q: &[f64]) -> DMatrix<f64> {
    let g = |k: &str| p[k].as_f64().unwrap();
    let (l1, l2) = (g("L1"), g("L2"));
    let (phi1, th1, th2) = (q[3], q[4], q[5]);
    let th12 = th1 - th2;
    let rho = l1 * th1.sin() + l2 * th12.sin();
    let eta = l1 * th1.cos() + l2 * th12.cos();
    let (s1, c1) = phi1.sin_cos();
    DMatrix::from_row_slice(
        3,
        3,
        &[
            -rho * s1,
            eta * c1,
            -l2 * th12.cos() * c1,
            rho * c1,
            eta * s1,
            -l2 * th12.cos() * s1,
            0.0,
            -rho,
            l2 * th12.sin(),
        ],
    )
}

fn check_m3_block(j: &DMatrix<f64>, b: &Value, what: &str) {
    let shape: Vec<usize> = serde_json::from_value(b["shape"].clone()).unwrap();
    assert_eq!(j.shape(), (shape[0], shape[1]), "{what} shape");
    let svd = JacobianSvd::new(j).unwrap();
    for (i, s) in vecf(&b["singular_values"]).iter().enumerate() {
        close(
            svd.singular_values[i],
            *s,
            1e-9,
            &format!("{what} sigma[{i}]"),
        );
    }
    let f = |k: &str| b[k].as_f64().unwrap();
    close(
        svd.yoshikawa().unwrap(),
        f("yoshikawa_sqrt_det_JJt"),
        1e-9,
        &format!("{what} yoshikawa"),
    );
    close(
        svd.inverse_condition(),
        f("w2_sigma_ratio"),
        1e-9,
        &format!("{what} w2"),
    );
    close(
        svd.eccentricity(),
        f("w5_bayle_eccentricity"),
        1e-9,
        &format!("{what} w5"),
    );
    if j.nrows() >= j.ncols() {
        close(
            svd.det_jtj().unwrap(),
            f("det_JtJ"),
            1e-8,
            &format!("{what} det(J^T J)"),
        );
    } else {
        // Wide: the chapter's measure is identically zero (the reference holds round-off).
        assert!(f("det_JtJ").abs() < 1e-20);
        let err = svd.det_jtj().unwrap_err().to_string();
        assert!(err.contains("identically zero"), "{err}");
    }
}

#[test]
fn m3_reference_measures() {
    let d = load("m3_diffdrive_kinematics.json");
    let cases = d["cases"].as_array().unwrap();
    assert!(!cases.is_empty());
    for case in cases {
        let q = vecf(&case["state"]["q"]);
        let out = &case["outputs"];
        let j = m3_jacobian(&case["params"], &q);
        let j_ref = mat(&out["J"]);
        assert!(
            (&j - &j_ref).abs().max() < 1e-12,
            "m3 J case {}",
            case["id"]
        );
        close(
            j.determinant(),
            out["det_J"].as_f64().unwrap(),
            1e-9,
            "det J",
        );
        check_m3_block(&j, &out["manipulability_J"], "J");
        let jee = moma::manipulability::select_rows(&j, &[2, 3, 4]).unwrap();
        check_m3_block(&jee, &out["manipulability_J_endeffector"], "J_endeffector");
        let jmv = m3_jmv(&case["params"], &q);
        assert!((&jmv - &mat(&out["J_mV"])).abs().max() < 1e-12);
        check_m3_block(&jmv, &out["manipulability_J_mV"], "J_mV");
    }
}

#[test]
fn measure_names_round_trip_and_errors() {
    for m in Measure::SCALAR {
        assert_eq!(m.to_string().parse::<Measure>().unwrap(), m);
    }
    assert_eq!("w2".parse::<Measure>().unwrap(), Measure::InverseCondition);
    assert_eq!(
        "directional:1,0,0".parse::<Measure>().unwrap(),
        Measure::Directional(vec![1.0, 0.0, 0.0])
    );
    assert!("bogus".parse::<Measure>().is_err());
    assert!("directional:0,0".parse::<Measure>().is_err());
    assert!("directional:1,x".parse::<Measure>().is_err());
    // Non-finite and empty Jacobians are rejected, never NaN.
    let mut j = DMatrix::<f64>::identity(3, 3);
    j[(1, 2)] = f64::NAN;
    assert!(evaluate(&Measure::Yoshikawa, &j).is_err());
    assert!(evaluate(&Measure::Yoshikawa, &DMatrix::zeros(0, 3)).is_err());
    // Tall J: Yoshikawa is identically zero → error; det(J^T J) fine.
    let tall = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
    assert!(evaluate(&Measure::Yoshikawa, &tall).is_err());
    close(
        evaluate(&Measure::DetJtJ, &tall).unwrap(),
        4.0,
        1e-12,
        "det",
    );
    // Wrong direction length.
    assert!(evaluate(&Measure::Directional(vec![1.0, 0.0]), &tall).is_err());
}

#[test]
fn singular_configuration_limits() {
    // Planar 2R stretched out (q2 = 0): w = 0, 1/κ = 0, eccentricity 1, κ an error.
    let j = planar_2r_jacobian(1.0, 0.8, 0.4, 0.0);
    let svd = JacobianSvd::new(&j).unwrap();
    assert!(svd.yoshikawa().unwrap().abs() < 1e-15);
    assert!(svd.inverse_condition() < 1e-12);
    assert!((svd.eccentricity() - 1.0).abs() < 1e-12);
    assert!(svd.condition().is_err());
    assert_eq!(svd.rank(), 1);
    // Radially outward direction cannot be produced: velocity radius 0, no NaN.
    let radial = [0.4f64.cos(), 0.4f64.sin()];
    let rv = svd.velocity_radius(&radial).unwrap();
    assert!(rv.abs() < 1e-9, "{rv}");
    let r = report(&j, Some(&radial)).unwrap();
    assert!(r.condition.is_none());
    assert!(r.eccentricity.is_finite() && r.geometric_mean.is_finite());
    let d = r.directional.unwrap();
    assert!(d.velocity_radius.is_finite() && d.projection_sum.is_finite());
    // Eccentricity increases towards the singularity along q2 → 0.
    let mut prev = 0.0;
    for k in (1..=20).rev() {
        let q2 = 1.2 * k as f64 / 20.0;
        let e = JacobianSvd::new(&planar_2r_jacobian(1.0, 0.8, 0.3, q2))
            .unwrap()
            .eccentricity();
        assert!(e >= prev - 1e-12);
        prev = e;
    }
}

#[test]
fn invariance_scaling_and_ellipsoid_properties() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..50 {
        let m = rng.random_range(1..=6);
        let n = rng.random_range(m..=8);
        let j = DMatrix::from_fn(m, n, |_, _| rng.random_range(-1.0..1.0));
        let svd = JacobianSvd::new(&j).unwrap();
        // w = √det(J Jᵀ).
        let w = svd.yoshikawa().unwrap();
        close(
            w,
            (&j * j.transpose()).determinant().abs().sqrt(),
            1e-8,
            "w",
        );
        // Task rotation (orthogonal Q) leaves w and 1/κ unchanged.
        let a = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
        let qr = a.qr().q();
        let svd2 = JacobianSvd::new(&(&qr * &j)).unwrap();
        close(svd2.yoshikawa().unwrap(), w, 1e-9, "rotated w");
        close(
            svd2.inverse_condition(),
            svd.inverse_condition(),
            1e-8,
            "rot 1/k",
        );
        // Scaling by c: w scales by |c|^m, ratios unchanged.
        let c = -2.5;
        let svd3 = JacobianSvd::new(&(&j * c)).unwrap();
        close(
            svd3.yoshikawa().unwrap(),
            w * c.abs().powi(m as i32),
            1e-9,
            "scaled w",
        );
        close(svd3.eccentricity(), svd.eccentricity(), 1e-8, "scaled ecc");
        // Extra columns never decrease w.
        let extra = DMatrix::from_fn(m, 2, |_, _| rng.random_range(-1.0..1.0));
        let wide = DMatrix::from_fn(
            m,
            n + 2,
            |i, k| {
                if k < n { j[(i, k)] } else { extra[(i, k - n)] }
            },
        );
        assert!(JacobianSvd::new(&wide).unwrap().yoshikawa().unwrap() >= w * (1.0 - 1e-12));
        // Directional ordering: projection sum ≥ |Jᵀu| ≥ r_v(u); equal along uᵢ.
        let u: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let ps = svd.projection_sum(&u).unwrap();
        let sup = svd.velocity_support(&u).unwrap();
        let rv = svd.velocity_radius(&u).unwrap();
        assert!(ps >= sup * (1.0 - 1e-12) && sup >= rv * (1.0 - 1e-12));
        for i in 0..m {
            let ui: Vec<f64> = svd.u.column(i).iter().copied().collect();
            close(
                svd.velocity_radius(&ui).unwrap(),
                svd.singular_values[i],
                1e-8,
                "r_v(u_i)",
            );
        }
        // Points J q̇ with |q̇| = 1 lie inside or on the ellipsoid: xᵀ (J Jᵀ)⁻¹ x ≤ 1.
        let qd = nalgebra::DVector::<f64>::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let qd = &qd / qd.norm();
        let x = &j * qd;
        let jjt = &j * j.transpose();
        if let Some(inv) = jjt.try_inverse() {
            let val = (x.transpose() * inv * &x)[(0, 0)];
            assert!(val <= 1.0 + 1e-8, "{val}");
        }
    }
}

/// At singular postures the Jacobian is rank deficient, the case where nalgebra 0.35's
/// SVD with vectors returned wrong values and axes (random rank-r products of every shape
/// up to 7 × 9; about one in seven failed before). The measures and the ellipsoid must
/// stay exact there: `J Jᵀ uᵢ = σᵢ² uᵢ` with orthonormal axes, the values equal to the
/// square roots of the eigenvalues of `J Jᵀ`, and the rank equal to r.
#[test]
fn rank_deficient_jacobians_keep_exact_values_and_axes() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1172);
    for trial in 0..500 {
        let m = rng.random_range(2..=7usize);
        let n = rng.random_range(2..=9usize);
        let r = rng.random_range(1..m.min(n));
        let a = DMatrix::from_fn(m, r, |_, _| rng.random_range(-1.0..1.0));
        let b = DMatrix::from_fn(r, n, |_, _| rng.random_range(-1.0..1.0));
        let j = a * b;
        let svd = JacobianSvd::new(&j).unwrap();
        assert_eq!(
            svd.rank(),
            r,
            "trial {trial}: rank of a {m} x {n} product of rank {r}"
        );
        let jjt = &j * j.transpose();
        let mut eig: Vec<f64> = jjt
            .clone()
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .collect();
        eig.sort_by(|x, y| y.total_cmp(x));
        let axes = svd.ellipsoid().axes;
        let gram = axes.transpose() * &axes;
        for i in 0..svd.singular_values.len() {
            let s = svd.singular_values[i];
            assert!(
                (s * s - eig[i]).abs() < 1e-10,
                "trial {trial}: σ{i}² = λ{i}"
            );
            let u = axes.column(i);
            let residual = (&jjt * u - u * (s * s)).amax();
            assert!(
                residual < 1e-10,
                "trial {trial}: J Jᵀ u{i} = σ{i}² u{i} ({residual:e})"
            );
            for k in 0..svd.singular_values.len() {
                let want = if i == k { 1.0 } else { 0.0 };
                assert!(
                    (gram[(i, k)] - want).abs() < 1e-12,
                    "trial {trial}: axes orthonormal"
                );
            }
        }
        // the velocity ellipsoid's support along an axis is its semi-axis length
        let u0: Vec<f64> = axes.column(0).iter().copied().collect();
        let support = svd.velocity_support(&u0).unwrap();
        assert!((support - svd.singular_values[0]).abs() < 1e-10);
    }
}
