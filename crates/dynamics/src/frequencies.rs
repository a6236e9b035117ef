//! Configuration-dependent frequencies of the links along the motion (the paper's section 4,
//! eq. 22, and model.md section 7) and buckling detection.
//!
//! At each instant the stiffness of link `i` is `K = Kf + Kp(P_i(t)) [- b'^2 M]` (the
//! softening term when the formulation has it). With diagonal `Kp` the frequencies are the
//! paper's eq. (22), `omega_j^2 = (kf_jj + kp_jj) / m_jj`, in basis order; with full `Kp` they
//! are the eigenvalues of the pencil `(K, M)`, ascending. A non-positive eigenvalue means the
//! link is statically unstable (buckling) at that instant: it is reported as an interval with
//! its margin, never as NaN.

use faer::Mat;
use flexprr_beam::{AxialLoad, FrequencySolver};

use crate::{DynamicsError, ModalSystem};

/// Frequencies of the three links at one instant, reusable without allocation.
#[derive(Debug)]
pub struct FrequencyTracker {
    solvers: [FrequencySolver; 3],
    stiffness: [Mat<f64>; 3],
    eigenvalues: [Vec<f64>; 3],
    nominal: [Vec<f64>; 3],
}

impl FrequencyTracker {
    /// Prepares the solvers for the links of `system` (factoring each `M` once) and the
    /// unloaded eigenvalues of `(Kf, M)`.
    ///
    /// # Errors
    /// A mass matrix that is not positive definite, or an eigenproblem that fails.
    pub fn new(system: &ModalSystem) -> Result<Self, DynamicsError> {
        let coupling = system.formulation().geometric_stiffness;
        let machine = system.machine();
        let mut solvers = Vec::with_capacity(3);
        let mut nominal = Vec::with_capacity(3);
        for link in &machine.links {
            let mut solver = FrequencySolver::new(&link.integrals, coupling)?;
            let mut ev = vec![0.0; link.modes()];
            solver.eigenvalues(link.integrals.stiffness.as_ref(), &mut ev)?;
            solvers.push(solver);
            nominal.push(ev);
        }
        let solvers: [FrequencySolver; 3] = solvers.try_into().expect("three links");
        let nominal: [Vec<f64>; 3] = nominal.try_into().expect("three links");
        Ok(Self {
            stiffness: std::array::from_fn(|i| {
                Mat::zeros(machine.links[i].modes(), machine.links[i].modes())
            }),
            eigenvalues: std::array::from_fn(|i| vec![0.0; machine.links[i].modes()]),
            solvers,
            nominal,
        })
    }

    /// Unloaded eigenvalues `omega^2` of each link (rad^2/s^2).
    pub fn nominal(&self) -> &[Vec<f64>; 3] {
        &self.nominal
    }

    /// Eigenvalues `omega^2` (rad^2/s^2) of each link at time `t`, with the axial loads used.
    ///
    /// # Errors
    /// Kinematic or inverse-dynamics failure at `t`; a failed eigenproblem.
    pub fn at(
        &mut self,
        system: &mut ModalSystem,
        t: f64,
    ) -> Result<(&[Vec<f64>; 3], [AxialLoad; 3]), DynamicsError> {
        let inst = system.instant(t)?;
        let softening = system.formulation().centrifugal_softening;
        for i in 0..3 {
            let ints = &system.machine().links[i].integrals;
            let k = &mut self.stiffness[i];
            ints.total_stiffness_into(&inst.loads[i], k.as_mut());
            if softening {
                let w2 = inst.state.legs[i].beta_dot.powi(2);
                let r = ints.r();
                for c in 0..r {
                    for rr in 0..r {
                        k[(rr, c)] -= w2 * ints.mass[(rr, c)];
                    }
                }
            }
            self.solvers[i].eigenvalues(k.as_ref(), &mut self.eigenvalues[i])?;
        }
        Ok((&self.eigenvalues, inst.loads))
    }
}

/// Frequency in Hz of an eigenvalue `omega^2`; 0 for a buckled (non-positive) one, which is
/// always reported separately as a [`BucklingInterval`].
pub fn hz(omega_squared: f64) -> f64 {
    omega_squared.max(0.0).sqrt() / std::f64::consts::TAU
}

/// Range of one mode of one link over the sampled motion.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeRange {
    /// Link index (0-based).
    pub link: usize,
    /// Mode index (0-based).
    pub mode: usize,
    /// Unloaded frequency (Hz).
    pub nominal_hz: f64,
    /// Lowest frequency (Hz) and when.
    pub min_hz: f64,
    /// Time of the lowest frequency (s).
    pub t_min: f64,
    /// Highest frequency (Hz).
    pub max_hz: f64,
    /// Time of the highest frequency (s).
    pub t_max: f64,
    /// Lowest `omega^2 / omega_nominal^2` over the motion: 1 unloaded, 0 at the onset of
    /// buckling, negative when buckled.
    pub min_stiffness_ratio: f64,
}

/// A time interval during which a link's stiffness is not positive definite.
#[derive(Debug, Clone, PartialEq)]
pub struct BucklingInterval {
    /// Link index (0-based).
    pub link: usize,
    /// Start (s), linearly interpolated between samples.
    pub t_start: f64,
    /// End (s), linearly interpolated between samples (the last sample if still buckled).
    pub t_end: f64,
    /// Most negative `omega^2` in the interval (rad^2/s^2).
    pub min_eigenvalue: f64,
    /// Its ratio to the unloaded lowest eigenvalue (the buckling margin, negative).
    pub margin: f64,
}

/// Frequencies of every link and mode at sampled times.
#[derive(Debug, Clone, PartialEq)]
pub struct FrequencyHistory {
    /// Sample times (s).
    pub t: Vec<f64>,
    /// `omega_squared[link][mode][k]` at `t[k]` (rad^2/s^2).
    pub omega_squared: [Vec<Vec<f64>>; 3],
    /// Axial force at `B` (`x = 0`) and `C` (`x = l`) of each link: `end_forces[link][k]` (N).
    pub end_forces: [Vec<(f64, f64)>; 3],
    /// Range of each mode.
    pub ranges: Vec<ModeRange>,
    /// Buckling intervals of all links.
    pub buckling: Vec<BucklingInterval>,
}

impl FrequencyHistory {
    /// Samples the frequencies of `system` at the times `t` (no ODE is integrated).
    ///
    /// # Errors
    /// As [`FrequencyTracker::at`], with the time.
    pub fn sample(system: &mut ModalSystem, t: &[f64]) -> Result<Self, DynamicsError> {
        let mut tracker = FrequencyTracker::new(system)?;
        let r: [usize; 3] = std::array::from_fn(|i| system.machine().links[i].modes());
        let mut omega_squared: [Vec<Vec<f64>>; 3] =
            std::array::from_fn(|i| vec![Vec::with_capacity(t.len()); r[i]]);
        let mut end_forces: [Vec<(f64, f64)>; 3] =
            std::array::from_fn(|_| Vec::with_capacity(t.len()));
        let lengths: [f64; 3] = std::array::from_fn(|i| system.machine().links[i].length());
        for &tk in t {
            let (ev, loads) = tracker.at(system, tk)?;
            for i in 0..3 {
                for (j, e) in ev[i].iter().enumerate() {
                    omega_squared[i][j].push(*e);
                }
                end_forces[i].push(crate::end_forces(&loads[i], lengths[i]));
            }
        }
        let nominal = tracker.nominal().clone();
        let mut ranges = Vec::new();
        let mut buckling = Vec::new();
        for i in 0..3 {
            for j in 0..r[i] {
                let series = &omega_squared[i][j];
                let (mut kmin, mut kmax) = (0, 0);
                for (k, v) in series.iter().enumerate() {
                    if *v < series[kmin] {
                        kmin = k;
                    }
                    if *v > series[kmax] {
                        kmax = k;
                    }
                }
                if series.is_empty() {
                    continue;
                }
                ranges.push(ModeRange {
                    link: i,
                    mode: j,
                    nominal_hz: hz(nominal[i][j]),
                    min_hz: hz(series[kmin]),
                    t_min: t[kmin],
                    max_hz: hz(series[kmax]),
                    t_max: t[kmax],
                    min_stiffness_ratio: series[kmin] / nominal[i][j],
                });
            }
            // Buckling: the lowest eigenvalue over all modes at each sample.
            let lowest: Vec<f64> = (0..t.len())
                .map(|k| {
                    (0..r[i])
                        .map(|j| omega_squared[i][j][k])
                        .fold(f64::INFINITY, f64::min)
                })
                .collect();
            let nominal_lowest = nominal[i].iter().copied().fold(f64::INFINITY, f64::min);
            let mut k = 0;
            while k < t.len() {
                if lowest[k] > 0.0 {
                    k += 1;
                    continue;
                }
                let start = k;
                while k < t.len() && lowest[k] <= 0.0 {
                    k += 1;
                }
                let end = k - 1;
                let cross = |a: usize, b: usize| {
                    let (la, lb) = (lowest[a], lowest[b]);
                    t[a] + (t[b] - t[a]) * la / (la - lb)
                };
                let t_start = if start > 0 {
                    cross(start - 1, start)
                } else {
                    t[start]
                };
                let t_end = if k < t.len() { cross(end, k) } else { t[end] };
                let min_eigenvalue = lowest[start..=end]
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min);
                buckling.push(BucklingInterval {
                    link: i,
                    t_start,
                    t_end,
                    min_eigenvalue,
                    margin: min_eigenvalue / nominal_lowest,
                });
            }
        }
        Ok(Self {
            t: t.to_vec(),
            omega_squared,
            end_forces,
            ranges,
            buckling,
        })
    }

    /// The range of link `link`, mode `mode` (0-based).
    pub fn range(&self, link: usize, mode: usize) -> Option<&ModeRange> {
        self.ranges
            .iter()
            .find(|r| r.link == link && r.mode == mode)
    }
}
