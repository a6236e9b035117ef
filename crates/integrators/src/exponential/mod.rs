//! Exponential (Magnus) integrators for linear time-varying second-order systems.
//!
//! A system that is linear in its state,
//!
//! ```text
//! x_b'' + D_b x_b' + S_b(t) x_b = g_b(t)      for each block b (x_b has r_b coordinates),
//! S_b(t) = sum_n s_bn(t) S_bn,   g_b(t) = sum_m e_bm(t) g_bm,
//! ```
//!
//! with constant symmetric matrices `S_bn`, constant vectors `g_bm`, a constant damping
//! matrix `D_b` and a few scalar coefficient functions `s_bn(t)`, `e_bm(t)`, offers this form
//! through [`LinearSecondOrder`] (reached from [`crate::OdeSystem::linear_form`]). The state of
//! the [`crate::OdeSystem`] is `y = (q_1, ..., q_B, q_1', ..., q_B')` with `q_b = T_b x_b` for a
//! constant invertible `T_b` the system chooses (e.g. its unloaded mode shapes, which make
//! `S_b` symmetric and `D_b` diagonal).
//!
//! [`Magnus`] integrates such systems with steps set by the motion, not by the highest
//! frequency: each step freezes the eigenbasis of `S_b` at the step's midpoint and advances
//! every mode with the closed-form exponential of its 2 x 2 Magnus generator, the forcing
//! integrated exactly for a quadratic in time (see [`Magnus`] for the method and sources).

mod auto;
mod functions;
mod jacobi;
mod magnus;

pub use auto::Auto;
pub use magnus::{Magnus, MagnusOrder, MagnusStepper};

/// The constant operators of one block of a [`LinearSecondOrder`] system.
///
/// All matrices are `r x r` row-major with `r = size`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BlockOperators {
    /// Number of coordinates `r_b` of the block.
    pub size: usize,
    /// The stiffness terms `S_bn` (symmetric), one matrix per coefficient `s_bn(t)`.
    pub stiffness: Vec<Vec<f64>>,
    /// The forcing terms `g_bm`, one vector per coefficient `e_bm(t)`.
    pub forcing: Vec<Vec<f64>>,
    /// The damping matrix `D_b`, or `None` for no damping.
    pub damping: Option<Vec<f64>>,
    /// `(T_b, T_b^-1)` mapping the coordinates `x_b` to the state's `q_b = T_b x_b` and back,
    /// or `None` when `q_b = x_b`.
    pub transform: Option<(Vec<f64>, Vec<f64>)>,
}

impl BlockOperators {
    /// Checks the sizes and the symmetry of the stiffness terms.
    ///
    /// # Errors
    /// A message naming the block, the operator and what is wrong.
    pub fn validate(&self, block: usize) -> Result<(), String> {
        let r = self.size;
        if r == 0 {
            return Err(format!("block {block} has no coordinates"));
        }
        for (n, s) in self.stiffness.iter().enumerate() {
            if s.len() != r * r {
                return Err(format!(
                    "stiffness term {n} of block {block} has {} entries, expected {r} x {r}",
                    s.len()
                ));
            }
            for i in 0..r {
                for j in 0..i {
                    let (a, b) = (s[i * r + j], s[j * r + i]);
                    if (a - b).abs() > 1e-10 * (a.abs() + b.abs()) + f64::MIN_POSITIVE {
                        return Err(format!(
                            "stiffness term {n} of block {block} is not symmetric: entry ({i}, {j}) = {a:e} but ({j}, {i}) = {b:e}"
                        ));
                    }
                }
            }
            if let Some(k) = s.iter().position(|v| !v.is_finite()) {
                return Err(format!(
                    "stiffness term {n} of block {block} has a non-finite entry at {k}"
                ));
            }
        }
        for (m, g) in self.forcing.iter().enumerate() {
            if g.len() != r {
                return Err(format!(
                    "forcing term {m} of block {block} has {} entries, expected {r}",
                    g.len()
                ));
            }
        }
        if let Some(d) = &self.damping {
            if d.len() != r * r {
                return Err(format!(
                    "the damping matrix of block {block} has {} entries, expected {r} x {r}",
                    d.len()
                ));
            }
        }
        if let Some((t, ti)) = &self.transform {
            if t.len() != r * r || ti.len() != r * r {
                return Err(format!(
                    "the coordinate transform of block {block} is not {r} x {r}"
                ));
            }
        }
        Ok(())
    }
}

/// A linear time-varying second-order system in block form (see the [module](self) docs).
///
/// Implement it for a system whose equations are linear in the state and return it from
/// [`crate::OdeSystem::linear_form`]; [`Magnus`] then integrates it.
///
/// ```
/// use flexprr_integrators::{
///     BlockOperators, Integrator, LinearSecondOrder, Magnus, OdeSystem, Options,
/// };
///
/// /// x'' + (4 + sin t) x = cos t: one block, one coordinate, two stiffness terms.
/// struct Mathieu;
/// impl LinearSecondOrder for Mathieu {
///     fn block_count(&self) -> usize { 1 }
///     fn block_operators(&self, _block: usize) -> BlockOperators {
///         BlockOperators {
///             size: 1,
///             stiffness: vec![vec![4.0], vec![1.0]],
///             forcing: vec![vec![1.0]],
///             damping: None,
///             transform: None,
///         }
///     }
///     fn coefficients(&mut self, t: f64, stiffness: &mut [f64], forcing: &mut [f64]) {
///         stiffness[0] = 1.0;
///         stiffness[1] = t.sin();
///         forcing[0] = t.cos();
///     }
/// }
/// impl OdeSystem for Mathieu {
///     fn dim(&self) -> usize { 2 }
///     fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
///         dy[0] = y[1];
///         dy[1] = t.cos() - (4.0 + t.sin()) * y[0];
///     }
///     fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> { Some(self) }
/// }
///
/// let opts = Options::default().rtol(1e-10).atol(1e-12);
/// let exp = Magnus::magnus6(opts.clone()).solve(&mut Mathieu, 0.0, &[1.0, 0.0], &[5.0]).unwrap();
/// let rk = flexprr_integrators::Rk45::new(opts).solve(&mut Mathieu, 0.0, &[1.0, 0.0], &[5.0]).unwrap();
/// assert!((exp.y(0)[0] - rk.y(0)[0]).abs() < 1e-8);
/// assert!(exp.stats.accepted_steps < rk.stats.accepted_steps);
/// ```
pub trait LinearSecondOrder {
    /// Number of blocks `B`.
    fn block_count(&self) -> usize;

    /// The constant operators of block `block` (called once when an integration starts, so
    /// it may allocate).
    fn block_operators(&self, block: usize) -> BlockOperators;

    /// The coefficient functions at time `t`: `stiffness` receives `s_bn(t)` block after
    /// block (as many per block as that block has stiffness terms), `forcing` receives
    /// `e_bm(t)` likewise. Called a few times per step: must not allocate. A failure (e.g.
    /// the kinematics) writes NaN, which the integrator reports as non-finite at `t`.
    fn coefficients(&mut self, t: f64, stiffness: &mut [f64], forcing: &mut [f64]);
}
