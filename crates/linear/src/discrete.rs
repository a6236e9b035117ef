//! The exact discrete-time model of a sampled control loop (docs/linear.md, "Discrete
//! time").
//!
//! A sampled law (the slider law with `control.period > 0`, the vibration law with
//! `vibration_control.period > 0`) takes its sample at `t_k = t0 + k T`: it reads the
//! machine at `t_k`, computes its command `u_k` (and advances its own states by
//! `z_{k+1} = z_k + T z'_k`, forward Euler, as the time model does), and holds `u_k` until
//! `t_{k+1}`. About an operating point, with the plant `x' = A x + B_u u + B_w w` (the model
//! with that law's loop open at its commands, every continuous law closed inside it) and the
//! law linearised as `u_k = K_x x_k + K_z z_k + K_w w_k`, `z'_k = L_x x_k + L_z z_k + L_w w_k`:
//!
//! ```text
//! [Ad Bd_u Bd_w] = first block row of exp([[A B_u B_w]; [0 0 0]] T)   (zero-order hold)
//! x_{k+1} = (Ad + Bd_u K_x) x_k + Bd_u K_z z_k + (Bd_w + Bd_u K_w) w_k
//! z_{k+1} = T L_x x_k + (I + T L_z) z_k + T L_w w_k
//! y_k     = (C_x + G_u K_x) x_k + G_u K_z z_k + (D_w + G_u K_w) w_k
//! ```
//!
//! with the inputs `w` held over the period as well (the zero-order-hold discretisation of
//! the external inputs; setpoints enter through the law at the sample), and `G_u` the
//! outputs' dependence on the command (a motor torque, an accelerometer). There is no
//! computation delay: the command of a sample acts from that sample on, as in the time
//! model. The exponential is [`crate::expm::expm`] (Van Loan 1978 for the hold integral).

use faer::Mat;
use flexprr_dynamics::{ExternalLoads, LawSample, SampledLaws, SceneModel};

use crate::LinearError;
use crate::linearize::{PlantInput, differentiate, input_derivative};
use crate::outputs::PlantOutputs;
use crate::relax::Relaxation;

/// The one sample period of a model's sampled laws (0 when none is sampled).
///
/// # Errors
/// Two sampled laws with different periods: a single-rate discrete model cannot hold both.
pub(crate) fn common_period(laws: &SampledLaws) -> Result<f64, LinearError> {
    let (s, p) = (laws.slider_period, laws.patch_period);
    if s > 0.0 && p > 0.0 && (s - p).abs() > 1e-9 * s.max(p) {
        return Err(LinearError::Channel(format!(
            "the slider control law samples every {s} s and the vibration control law every {p} s: \
             a discrete-time linear model needs one period (give control.period and \
             vibration_control.period the same value)"
        )));
    }
    Ok(s.max(p))
}

/// The discrete-time closed loop.
#[derive(Debug, Clone)]
pub(crate) struct Closed {
    pub(crate) a: Mat<f64>,
    pub(crate) b: Mat<f64>,
    pub(crate) c: Mat<f64>,
    pub(crate) d: Mat<f64>,
}

/// The sampled laws' outputs as one vector: the slider commands (when that law is
/// sampled), the patch commands (when that law is sampled), the slider law's state rates.
fn law_vector(sample: &LawSample, laws: &SampledLaws, out: &mut [f64]) {
    let mut k = 0;
    if laws.slider_period > 0.0 {
        out[..3].copy_from_slice(&sample.slider_command);
        k = 3;
    }
    if laws.patch_period > 0.0 {
        out[k..k + sample.patch_command.len()].copy_from_slice(&sample.patch_command);
        k += sample.patch_command.len();
    }
    out[k..k + sample.slider_rates.len()].copy_from_slice(&sample.slider_rates);
}

/// The discrete-time model of the loop closed by the sampled laws (module documentation):
/// `a`, `b` the relaxed plant's (the first `commands` columns of `b` the laws' commands,
/// the rest `users`), `plant` its output rows.
#[allow(clippy::too_many_arguments)]
pub(crate) fn close_sampled_loop(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    base: &ExternalLoads,
    layout: &Relaxation<'_>,
    laws: &SampledLaws,
    sample: &LawSample,
    period: f64,
    a: &Mat<f64>,
    b: &Mat<f64>,
    commands: usize,
    users: &[PlantInput],
    plant: &PlantOutputs,
    opened: &[bool],
) -> Result<Closed, LinearError> {
    let n = layout.dim();
    let nz = laws.slider_states.len();
    let mw = users.len();
    let width = commands + nz;
    let z0 = laws.slider_states.clone();
    let evaluate = |model: &mut dyn SceneModel,
                    probe: &[f64],
                    states: &[f64],
                    out: &mut [f64]|
     -> Result<(), LinearError> {
        let s = model.law_sample(t, probe, states)?;
        law_vector(&s, laws, out);
        Ok(())
    };
    let mut check = vec![0.0; width];
    law_vector(sample, laws, &mut check);
    // The law's gradients in the model's state, its own states and the inputs.
    let mut k_x = Mat::<f64>::zeros(width, n);
    differentiate(
        y,
        0..layout.model_dim,
        width,
        &mut |probe, out| evaluate(model, probe, &z0, out),
        &mut |j, column| {
            for (row, v) in column.iter().enumerate() {
                k_x[(row, layout.index(j))] = *v;
            }
        },
    )?;
    let mut k_z = Mat::<f64>::zeros(width, nz);
    if nz > 0 {
        differentiate(
            &z0,
            0..nz,
            width,
            &mut |probe, out| evaluate(model, y, probe, out),
            &mut |j, column| {
                for (row, v) in column.iter().enumerate() {
                    k_z[(row, j)] = *v;
                }
            },
        )?;
    }
    let mut k_w = Mat::<f64>::zeros(width, mw);
    for (k, input) in users.iter().enumerate() {
        let column = input_derivative(model, base, *input, width, &mut |m, _, out| {
            evaluate(m, y, &z0, out)
        })?;
        for (row, v) in column.into_iter().enumerate() {
            k_w[(row, k)] = v;
        }
    }
    // The zero-order hold of the plant with its commands and inputs.
    let m_all = commands + mw;
    let size = n + m_all;
    let augmented = Mat::from_fn(size, size, |i, j| {
        if i >= n {
            0.0
        } else if j < n {
            a[(i, j)] * period
        } else {
            b[(i, j - n)] * period
        }
    });
    let e = crate::expm::expm(&augmented)?;
    let ad = |i: usize, j: usize| e[(i, j)];
    // A command whose loop is broken at its actuator comes from an input (its column
    // among the users'), not from the law.
    let bd_u = |i: usize, k: usize| if opened[k] { 0.0 } else { e[(i, n + k)] };
    let bd_w = |i: usize, k: usize| e[(i, n + commands + k)];
    let total = n + nz;
    let mut a_cl = Mat::<f64>::zeros(total, total);
    let mut b_cl = Mat::<f64>::zeros(total, mw);
    for i in 0..n {
        for j in 0..n {
            let mut v = ad(i, j);
            for k in 0..commands {
                v += bd_u(i, k) * k_x[(k, j)];
            }
            a_cl[(i, j)] = v;
        }
        for j in 0..nz {
            a_cl[(i, n + j)] = (0..commands).map(|k| bd_u(i, k) * k_z[(k, j)]).sum();
        }
        for w in 0..mw {
            b_cl[(i, w)] =
                bd_w(i, w) + (0..commands).map(|k| bd_u(i, k) * k_w[(k, w)]).sum::<f64>();
        }
    }
    for r in 0..nz {
        let row = commands + r;
        for j in 0..n {
            a_cl[(n + r, j)] = period * k_x[(row, j)];
        }
        for j in 0..nz {
            a_cl[(n + r, n + j)] = f64::from(u8::from(r == j)) + period * k_z[(row, j)];
        }
        for w in 0..mw {
            b_cl[(n + r, w)] = period * k_w[(row, w)];
        }
    }
    let p = plant.c.nrows();
    let mut c_cl = Mat::<f64>::zeros(p, total);
    let mut d_cl = Mat::<f64>::zeros(p, mw);
    for o in 0..p {
        for j in 0..n {
            c_cl[(o, j)] = plant.c[(o, j)]
                + (0..commands)
                    .map(|k| plant.g_u[(o, k)] * k_x[(k, j)])
                    .sum::<f64>();
        }
        for j in 0..nz {
            c_cl[(o, n + j)] = (0..commands).map(|k| plant.g_u[(o, k)] * k_z[(k, j)]).sum();
        }
        for w in 0..mw {
            d_cl[(o, w)] = plant.d[(o, w)]
                + (0..commands)
                    .map(|k| plant.g_u[(o, k)] * k_w[(k, w)])
                    .sum::<f64>();
        }
    }
    let finite =
        |m: &Mat<f64>| (0..m.ncols()).all(|j| (0..m.nrows()).all(|i| m[(i, j)].is_finite()));
    if !(finite(&a_cl) && finite(&b_cl) && finite(&c_cl) && finite(&d_cl)) {
        return Err(LinearError::Numerics(
            "the discrete-time model of the sampled loop is not finite".into(),
        ));
    }
    Ok(Closed {
        a: a_cl,
        b: b_cl,
        c: c_cl,
        d: d_cl,
    })
}
