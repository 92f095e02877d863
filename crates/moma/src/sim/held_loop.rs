//! The one stepping loop of a plant under held inputs: at every control tick it measures
//! the plant's state (through the sensor noise, if any), calls the law's tick (which
//! writes the inputs, records, and may end the run), then advances the plant over one
//! control period with those inputs held (zero-order hold).
//!
//! The sensor noise is the loop's argument and nothing else's: every run with noisy
//! measurements (`moma simulate`'s closed loop on the rolling or the contact plant,
//! `moma mission`) hands its noise here, the law reads the noisy state
//! ([`Tick::q`], [`Tick::v`]) and the record keeps the plant's own ([`Tick::q_plant`],
//! [`Tick::v_plant`]).
//!
//! The plant is a [`HeldPlant`]: the rolling model integrated on its grid
//! (`sim::rolling_plant`) or the contact plant stepped at its own `dt`. The law is a
//! [`TickLaw`]: `moma simulate`'s closed loop (a feedback law with its recorder,
//! `sim::closed_loop`), its contact-plant run (`sim::contact_run`), and `moma mission`'s
//! phased law all run here. The loop imports none of them.

use crate::error::{Error, Result};
use crate::sim::sensor_noise::SensorNoise;

/// A plant whose inputs are held over each control period.
pub trait HeldPlant {
    /// Number of configuration coordinates the law measures.
    fn nq(&self) -> usize;
    /// Number of reduced velocities the law measures.
    fn nv(&self) -> usize;
    /// Number of inputs.
    fn nu(&self) -> usize;
    /// The present time (s).
    fn time(&self) -> f64;
    /// Writes the present state in the law's reduced coordinates `(q, v)`.
    fn state(&mut self, q: &mut [f64], v: &mut [f64]);
    /// Advances over one control period with the inputs `u` held. `first_stage`, when
    /// given, is the plant's state derivative at its present state under `u`, evaluated by
    /// the law; a plant integrated by RK4 takes it as its first stage.
    ///
    /// # Errors
    /// The plant's (a blow-up, a singular state, a step budget run out).
    fn advance(&mut self, u: &[f64], first_stage: Option<&[f64]>) -> Result<()>;
}

/// What the loop hands the law at a tick.
pub struct Tick<'a> {
    /// The tick's index (0 at the start; a repeated tick keeps its index).
    pub k: usize,
    /// The tick's time (s), the plant's.
    pub t: f64,
    /// The plant's own configuration.
    pub q_plant: &'a [f64],
    /// The plant's own reduced velocity.
    pub v_plant: &'a [f64],
    /// The configuration the law measures (the plant's, through the sensor noise if any
    /// and [`TickLaw::measures`] this tick).
    pub q: &'a [f64],
    /// The reduced velocity the law measures.
    pub v: &'a [f64],
    /// The inputs held over the next period: the previous tick's until the law writes
    /// them (zero at the start).
    pub u: &'a mut [f64],
}

/// How a tick ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TickEnd {
    /// The plant advances with the inputs held; the next tick follows.
    Hold,
    /// The run ends at this state: the tick is taken again (measured again, without
    /// advancing) for the law to record its last sample.
    Again,
    /// The run is over.
    Stop,
}

/// A law run by [`run_held_loop`] on a plant `P`.
pub trait TickLaw<P: ?Sized> {
    /// One control tick: writes `now.u`, records what it records, says how the tick ends.
    /// It may change `plant` (a payload attached).
    ///
    /// # Errors
    /// The law's errors end the run.
    fn tick(&mut self, plant: &mut P, now: &mut Tick<'_>) -> Result<TickEnd>;

    /// The plant's state derivative at the tick's state under the inputs just written,
    /// when the law evaluated it exactly (the plant's own model and state); `None` by
    /// default.
    fn first_stage(&self) -> Option<&[f64]> {
        None
    }

    /// Whether the law reads the measured state at tick `k` (every tick by default). On a
    /// tick it does not, the loop draws no noise and [`Tick::q`], [`Tick::v`] are the
    /// plant's own: a law sampled every few ticks (the contact run's, whose tick is one
    /// contact step) draws the noise once per evaluation.
    fn measures(&self, _k: usize) -> bool {
        true
    }

    /// The sensor noise failed at time `t`: by default the run ends with `e`; a law that
    /// returns `Ok` goes on with the tick (the measured state as the noise left it).
    ///
    /// # Errors
    /// `e` or the law's.
    fn measurement_failed(&mut self, _t: f64, e: Error) -> Result<()> {
        Err(e)
    }

    /// The plant failed to advance from time `t`: by default the run ends with `e`; a law
    /// that returns `Ok` has the tick taken again at the state before the failure.
    ///
    /// # Errors
    /// `e` or the law's.
    fn advance_failed(&mut self, _plant: &mut P, _t: f64, e: Error) -> Result<()> {
        Err(e)
    }
}

/// Runs `law` on `plant` until the law stops it; the measured state goes through `noise`
/// when given (a fresh draw at every tick the law [`TickLaw::measures`]). Returns the number of control periods the plant advanced.
///
/// # Errors
/// Those of the law, and those of the plant and the noise the law does not take over.
pub fn run_held_loop<P: HeldPlant + ?Sized, L: TickLaw<P> + ?Sized>(
    plant: &mut P,
    law: &mut L,
    mut noise: Option<&mut SensorNoise>,
) -> Result<usize> {
    let (nq, nv) = (plant.nq(), plant.nv());
    let (mut q_plant, mut v_plant) = (vec![0.0; nq], vec![0.0; nv]);
    let (mut q, mut v) = (vec![0.0; nq], vec![0.0; nv]);
    let mut u = vec![0.0; plant.nu()];
    let mut k = 0;
    loop {
        let t = plant.time();
        plant.state(&mut q_plant, &mut v_plant);
        match noise.as_deref_mut().filter(|_| law.measures(k)) {
            Some(noise) => {
                if let Err(e) = noise.measure(&q_plant, &v_plant, &mut q, &mut v) {
                    law.measurement_failed(t, e)?;
                }
            }
            None => {
                q.copy_from_slice(&q_plant);
                v.copy_from_slice(&v_plant);
            }
        }
        let mut now = Tick {
            k,
            t,
            q_plant: &q_plant,
            v_plant: &v_plant,
            q: &q,
            v: &v,
            u: &mut u,
        };
        match law.tick(plant, &mut now)? {
            TickEnd::Stop => return Ok(k),
            TickEnd::Again => {}
            TickEnd::Hold => match plant.advance(&u, law.first_stage()) {
                Ok(()) => k += 1,
                Err(e) => law.advance_failed(plant, t, e)?,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ẋ = u` on a grid of 0.5 s periods, stepped exactly; fails its `fail_at`-th advance.
    struct Integrator {
        x: f64,
        t: f64,
        advances: usize,
        fail_at: Option<usize>,
    }

    impl HeldPlant for Integrator {
        fn nq(&self) -> usize {
            1
        }
        fn nv(&self) -> usize {
            1
        }
        fn nu(&self) -> usize {
            1
        }
        fn time(&self) -> f64 {
            self.t
        }
        fn state(&mut self, q: &mut [f64], v: &mut [f64]) {
            q[0] = self.x;
            v[0] = 0.0;
        }
        fn advance(&mut self, u: &[f64], first_stage: Option<&[f64]>) -> Result<()> {
            assert_eq!(first_stage, Some(&[u[0]][..]));
            self.advances += 1;
            if self.fail_at == Some(self.advances) {
                return Err(Error::Numerical {
                    t: self.t,
                    message: "step failed".into(),
                });
            }
            self.x += 0.5 * u[0];
            self.t += 0.5;
            Ok(())
        }
    }

    /// `u = 1 − x` until tick 4, which it takes again once before stopping; logs every
    /// tick as `(k, t, q_plant, q)`; takes a failed advance over when `retry` is set;
    /// measures at every `measure_every`-th tick.
    struct Law {
        log: Vec<(usize, f64, f64, f64)>,
        again: bool,
        retry: bool,
        first: [f64; 1],
        measure_every: usize,
    }

    impl TickLaw<Integrator> for Law {
        fn tick(&mut self, _plant: &mut Integrator, now: &mut Tick<'_>) -> Result<TickEnd> {
            self.log.push((now.k, now.t, now.q_plant[0], now.q[0]));
            if now.k == 4 {
                self.again = !self.again;
                return Ok(if self.again {
                    TickEnd::Again
                } else {
                    TickEnd::Stop
                });
            }
            now.u[0] = 1.0 - now.q[0];
            self.first[0] = now.u[0];
            Ok(TickEnd::Hold)
        }
        fn first_stage(&self) -> Option<&[f64]> {
            Some(&self.first)
        }
        fn advance_failed(&mut self, _plant: &mut Integrator, _t: f64, e: Error) -> Result<()> {
            if self.retry { Ok(()) } else { Err(e) }
        }
        fn measures(&self, k: usize) -> bool {
            k.is_multiple_of(self.measure_every)
        }
    }

    fn run(
        fail_at: Option<usize>,
        retry: bool,
        noise: Option<&mut SensorNoise>,
    ) -> (Result<usize>, Law, Integrator) {
        run_measuring(fail_at, retry, noise, 1)
    }

    fn run_measuring(
        fail_at: Option<usize>,
        retry: bool,
        noise: Option<&mut SensorNoise>,
        measure_every: usize,
    ) -> (Result<usize>, Law, Integrator) {
        let mut plant = Integrator {
            x: 0.0,
            t: 0.0,
            advances: 0,
            fail_at,
        };
        let mut law = Law {
            log: Vec::new(),
            again: false,
            retry,
            first: [0.0],
            measure_every,
        };
        let r = run_held_loop(&mut plant, &mut law, noise);
        (r, law, plant)
    }

    #[test]
    fn the_law_holds_its_inputs_over_each_period_and_ends_the_run_with_a_repeated_tick() {
        let (r, law, plant) = run(None, false, None);
        assert_eq!(r.unwrap(), 4);
        assert_eq!(plant.advances, 4);
        // x_{k+1} = x_k + (1 − x_k) / 2: 0, 1/2, 3/4, 7/8, 15/16; tick 4 taken twice
        let xs = [0.0, 0.5, 0.75, 0.875, 0.9375, 0.9375];
        let ks = [0, 1, 2, 3, 4, 4];
        assert_eq!(law.log.len(), 6);
        for (i, &(k, t, xp, xm)) in law.log.iter().enumerate() {
            assert_eq!(k, ks[i]);
            assert_eq!(t, 0.5 * ks[i] as f64);
            assert_eq!((xp, xm), (xs[i], xs[i]));
        }
    }

    #[test]
    fn a_failed_advance_ends_the_run_unless_the_law_takes_the_tick_again() {
        let (r, _, _) = run(Some(2), false, None);
        assert!(r.unwrap_err().to_string().contains("step failed"));
        let (r, law, plant) = run(Some(2), true, None);
        assert_eq!(r.unwrap(), 4);
        assert_eq!(plant.advances, 5);
        let ks: Vec<usize> = law.log.iter().map(|e| e.0).collect();
        assert_eq!(ks, [0, 1, 1, 2, 3, 4, 4]);
        assert_eq!(law.log[1].2, law.log[2].2);
    }

    #[test]
    fn the_law_measures_through_the_noise_and_the_plant_keeps_its_own_state() {
        let mut noise = SensorNoise::new(vec![0.1], vec![0.0], 7).unwrap();
        let (r, law, _) = run(None, false, Some(&mut noise));
        assert_eq!(r.unwrap(), 4);
        assert_eq!(law.log[0].2, 0.0);
        for &(_, _, xp, xm) in &law.log {
            assert!(xm != xp && (xm - xp).abs() < 1.0);
        }
        // the repeated tick draws a new measurement of the same plant state
        let (a, b) = (law.log[4], law.log[5]);
        assert_eq!(a.2, b.2);
        assert_ne!(a.3, b.3);
    }

    #[test]
    fn the_noise_is_drawn_only_at_the_ticks_the_law_measures() {
        let mut noise = SensorNoise::new(vec![0.1], vec![0.0], 7).unwrap();
        let mut draws = noise.clone();
        let (r, law, _) = run_measuring(None, false, Some(&mut noise), 2);
        assert_eq!(r.unwrap(), 4);
        let (mut q, mut v) = ([0.0], [0.0]);
        for &(k, _, xp, xm) in &law.log {
            if k % 2 == 0 {
                // the next draw of the seed's sequence: none was spent on the odd ticks
                draws.measure(&[xp], &[0.0], &mut q, &mut v).unwrap();
                assert_eq!(xm, q[0]);
                assert_ne!(xm, xp);
            } else {
                assert_eq!(xm, xp);
            }
        }
    }
}
