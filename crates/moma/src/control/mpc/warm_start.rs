//! Warm start between receding-horizon solves: the previous solution shifted by one
//! stage (the solve at time t + Δt starts from the inputs planned for t + Δt … and
//! repeats the last one), and the multipliers shifted alongside.

use nalgebra::DVector;

/// Shifts the inputs `us` and the multipliers `lambda` (one per knot) by one stage, in
/// place (`clone_from` on same-sized vectors: no allocation).
pub fn shift_solution(us: &mut [DVector<f64>], lambda: &mut [DVector<f64>]) {
    shift_in_place(us);
    shift_in_place(lambda);
}

fn shift_in_place(v: &mut [DVector<f64>]) {
    let n = v.len();
    if n < 2 {
        return;
    }
    v.rotate_left(1);
    let (head, tail) = v.split_at_mut(n - 1);
    tail[0].copy_from(&head[n - 2]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifts_by_one_and_repeats_the_last() {
        let mut us: Vec<DVector<f64>> = (0..4)
            .map(|i| DVector::from_element(2, f64::from(i)))
            .collect();
        let mut lam: Vec<DVector<f64>> = (0..5)
            .map(|i| DVector::from_element(1, f64::from(10 * i)))
            .collect();
        shift_solution(&mut us, &mut lam);
        let got: Vec<f64> = us.iter().map(|u| u[0]).collect();
        assert_eq!(got, vec![1.0, 2.0, 3.0, 3.0]);
        let got: Vec<f64> = lam.iter().map(|l| l[0]).collect();
        assert_eq!(got, vec![10.0, 20.0, 30.0, 40.0, 40.0]);
    }
}
