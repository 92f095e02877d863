//! A recorded trajectory: times, states, inputs, energies and constraint residuals.

use serde::Serialize;

/// One sampled trajectory, stored row by row in flat buffers (one row per sample).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Recorder {
    /// Names of the configuration coordinates q.
    pub q_names: Vec<String>,
    /// Names of the reduced velocities v.
    pub v_names: Vec<String>,
    /// Names of the inputs u.
    pub u_names: Vec<String>,
    /// SI units of q, v and u (each empty, or one per name), for the CSV header.
    pub units: [Vec<String>; 3],
    /// Sample times (s).
    pub times: Vec<f64>,
    /// Configurations, `times.len() × q_names.len()` row-major.
    pub q: Vec<f64>,
    /// Reduced velocities, `times.len() × v_names.len()` row-major.
    pub v: Vec<f64>,
    /// Inputs, `times.len() × u_names.len()` row-major.
    pub u: Vec<f64>,
    /// Kinetic energy T (J) per sample.
    pub kinetic: Vec<f64>,
    /// Potential energy V (J) per sample.
    pub potential: Vec<f64>,
    /// Work done by the inputs since the start, W = ∫ Qᵀ q̇ dt (J), per sample.
    pub work: Vec<f64>,
    /// Constraint residual ‖C(q) q̇‖ per sample.
    pub residual: Vec<f64>,
    /// Names of the Lagrange multipliers (empty if not recorded).
    pub lambda_names: Vec<String>,
    /// Lagrange multipliers λ, `times.len() × lambda_names.len()` row-major.
    pub lambda: Vec<f64>,
}

impl Recorder {
    /// An empty recorder with the given channel names and room for `capacity` samples.
    pub fn new(
        q_names: Vec<String>,
        v_names: Vec<String>,
        u_names: Vec<String>,
        capacity: usize,
    ) -> Self {
        let (nq, nv, nu) = (q_names.len(), v_names.len(), u_names.len());
        Self {
            q_names,
            v_names,
            u_names,
            units: Default::default(),
            times: Vec::with_capacity(capacity),
            q: Vec::with_capacity(capacity * nq),
            v: Vec::with_capacity(capacity * nv),
            u: Vec::with_capacity(capacity * nu),
            kinetic: Vec::with_capacity(capacity),
            potential: Vec::with_capacity(capacity),
            work: Vec::with_capacity(capacity),
            residual: Vec::with_capacity(capacity),
            lambda_names: Vec::new(),
            lambda: Vec::new(),
        }
    }

    /// Appends one sample.
    ///
    /// # Panics
    /// If a slice length does not match the channel names.
    pub fn push(&mut self, sample: Sample<'_>) {
        assert_eq!(sample.q.len(), self.q_names.len(), "q length");
        assert_eq!(sample.v.len(), self.v_names.len(), "v length");
        assert_eq!(sample.u.len(), self.u_names.len(), "u length");
        self.times.push(sample.t);
        self.q.extend_from_slice(sample.q);
        self.v.extend_from_slice(sample.v);
        self.u.extend_from_slice(sample.u);
        self.kinetic.push(sample.kinetic);
        self.potential.push(sample.potential);
        self.work.push(sample.work);
        self.residual.push(sample.residual);
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True if nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Configuration of sample `i`.
    pub fn q_row(&self, i: usize) -> &[f64] {
        let n = self.q_names.len();
        &self.q[i * n..(i + 1) * n]
    }

    /// Reduced velocity of sample `i`.
    pub fn v_row(&self, i: usize) -> &[f64] {
        let n = self.v_names.len();
        &self.v[i * n..(i + 1) * n]
    }

    /// Input of sample `i`.
    pub fn u_row(&self, i: usize) -> &[f64] {
        let n = self.u_names.len();
        &self.u[i * n..(i + 1) * n]
    }

    /// Multipliers λ of sample `i` (empty if not recorded).
    pub fn lambda_row(&self, i: usize) -> &[f64] {
        let n = self.lambda_names.len();
        if n == 0 || self.lambda.len() < (i + 1) * n {
            return &[];
        }
        &self.lambda[i * n..(i + 1) * n]
    }

    /// Energy balance error of sample `i`: `(T + V) − (T₀ + V₀) − W` (J). Zero for an
    /// exact solution, because the constraint forces do no work.
    pub fn energy_error(&self, i: usize) -> f64 {
        (self.kinetic[i] + self.potential[i]) - (self.kinetic[0] + self.potential[0]) - self.work[i]
    }

    /// Sets the units of q, v and u (one per name each).
    ///
    /// # Panics
    /// If a length does not match the channel names.
    pub fn set_units(&mut self, q: Vec<&str>, v: Vec<&str>, u: Vec<&str>) {
        assert_eq!(q.len(), self.q_names.len(), "q units");
        assert_eq!(v.len(), self.v_names.len(), "v units");
        assert_eq!(u.len(), self.u_names.len(), "u units");
        let own = |x: Vec<&str>| x.into_iter().map(String::from).collect();
        self.units = [own(q), own(v), own(u)];
    }

    /// The CSV header: every column `name [unit]` (`t [s]`, `x [m]`, `kinetic [J]`, the
    /// residual ‖C q̇‖ in m/s, the multipliers in N); a q, v or u column without a set
    /// unit is the bare name.
    pub fn csv_header(&self) -> String {
        let mut cols = vec!["t [s]".to_string()];
        for (names, units) in [&self.q_names, &self.v_names, &self.u_names]
            .into_iter()
            .zip(&self.units)
        {
            for (i, n) in names.iter().enumerate() {
                cols.push(match units.get(i) {
                    Some(u) => format!("{n} [{u}]"),
                    None => n.clone(),
                });
            }
        }
        for c in ["kinetic", "potential", "work", "energy_error"] {
            cols.push(format!("{c} [J]"));
        }
        cols.push("residual [m/s]".into());
        cols.extend(self.lambda_names.iter().map(|n| format!("{n} [N]")));
        cols.join(",")
    }

    /// The trajectory as CSV text: the header of [`Recorder::csv_header`]
    /// (`t,q…,v…,u…,kinetic,potential,work,energy_error,residual[,lambda…]`, with units)
    /// and one line per sample (full precision).
    pub fn to_csv(&self) -> String {
        let mut out = self.csv_header();
        out.push('\n');
        for i in 0..self.len() {
            let mut line = format!("{:e}", self.times[i]);
            for x in self
                .q_row(i)
                .iter()
                .chain(self.v_row(i))
                .chain(self.u_row(i))
            {
                line.push_str(&format!(",{x:e}"));
            }
            line.push_str(&format!(
                ",{:e},{:e},{:e},{:e},{:e}",
                self.kinetic[i],
                self.potential[i],
                self.work[i],
                self.energy_error(i),
                self.residual[i]
            ));
            for x in self.lambda_row(i) {
                line.push_str(&format!(",{x:e}"));
            }
            line.push('\n');
            out.push_str(&line);
        }
        out
    }
}

/// One sample handed to [`Recorder::push`].
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// Time (s).
    pub t: f64,
    /// Configuration q.
    pub q: &'a [f64],
    /// Reduced velocity v.
    pub v: &'a [f64],
    /// Input u.
    pub u: &'a [f64],
    /// Kinetic energy (J).
    pub kinetic: f64,
    /// Potential energy (J).
    pub potential: f64,
    /// Work done by the inputs so far (J).
    pub work: f64,
    /// Constraint residual ‖C q̇‖.
    pub residual: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_rows_and_writes_csv() {
        let mut r = Recorder::new(vec!["x".into()], vec!["v".into()], vec!["u".into()], 2);
        for i in 0..2 {
            let t = i as f64;
            r.push(Sample {
                t,
                q: &[t],
                v: &[1.0],
                u: &[0.0],
                kinetic: 0.5,
                potential: t,
                work: t,
                residual: 0.0,
            });
        }
        assert_eq!(r.len(), 2);
        assert_eq!(r.q_row(1), &[1.0]);
        assert_eq!(r.energy_error(1), 0.0);
        let csv = r.to_csv();
        assert!(csv.starts_with(
            "t [s],x,v,u,kinetic [J],potential [J],work [J],energy_error [J],residual [m/s]\n"
        ));
        r.set_units(vec!["m"], vec!["m/s"], vec!["N"]);
        assert!(
            r.to_csv()
                .starts_with("t [s],x [m],v [m/s],u [N],kinetic [J]")
        );
        assert_eq!(csv.lines().count(), 3);
    }
}
