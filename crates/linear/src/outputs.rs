//! The outputs of a linear model: their values at the operating point and their gradients
//! in the state (`C`), in the inputs (`D`) and in the commands of a sampled law whose loop a
//! discretisation opens.

use faer::Mat;
use flexprr_dynamics::channel::{self, Output};
use flexprr_dynamics::{ExternalLoads, SceneModel};

use crate::LinearError;
use crate::linearize::{PlantInput, differentiate, input_derivative};
use crate::relax::Relaxation;

/// The outputs' rows of the plant (the model with a sampled law's loop open).
#[derive(Debug, Clone)]
pub(crate) struct PlantOutputs {
    /// Values at the operating point (0 for accelerations).
    pub(crate) values: Vec<f64>,
    /// `C` of the plant (`p x n`).
    pub(crate) c: Mat<f64>,
    /// `D` in the linear model's inputs (`p x m`).
    pub(crate) d: Mat<f64>,
    /// The gradient in the commands of a sampled law (`p x commands`).
    pub(crate) g_u: Mat<f64>,
}

/// Whether `output` depends on the state's coordinates only (not on rates or a law's
/// states).
fn of_coordinates(output: &Output) -> bool {
    matches!(
        output,
        Output::SliderPosition(_)
            | Output::Platform(_)
            | Output::Deflection { .. }
            | Output::Slope { .. }
            | Output::Acceleration { .. }
            | Output::PatchSensor(_)
    )
}

/// The normal of the chord of an acceleration output's link at the operating point (zero
/// for other outputs).
fn normals(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    outputs: &[Output],
) -> Result<Vec<[f64; 2]>, LinearError> {
    if !outputs
        .iter()
        .any(|o| matches!(o, Output::Acceleration { .. }))
    {
        return Ok(vec![[0.0; 2]; outputs.len()]);
    }
    let snapshot = model.snapshot(t, y)?;
    Ok(outputs
        .iter()
        .map(|o| match *o {
            Output::Acceleration { link, .. } => {
                let (b, c) = channel::chord(model, &snapshot, link);
                let (dx, dy) = (c[0] - b[0], c[1] - b[1]);
                let length = dx.hypot(dy);
                [-dy / length, dx / length]
            }
            _ => [0.0; 2],
        })
        .collect())
}

/// The plant's output rows at `(t, y)` under the loads `base` (already set on the model):
/// values, `C` in the relaxed state of `layout`, `D` in the user inputs among
/// `plant_inputs` (after the first `commands`), the gradient in those commands. `a` and
/// `b` are the relaxed plant's (for accelerations). With `slider_sampled`, a
/// `slider_command` output is the command itself.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plant_outputs(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    base: &ExternalLoads,
    layout: &Relaxation<'_>,
    a: &Mat<f64>,
    b: &Mat<f64>,
    plant_inputs: &[PlantInput],
    commands: usize,
    outputs: &[Output],
    slider_sampled: bool,
) -> Result<PlantOutputs, LinearError> {
    let p = outputs.len();
    let n = layout.dim();
    let users = plant_inputs.len() - commands;
    let mut c = Mat::zeros(p, n);
    let mut d = Mat::zeros(p, users);
    let mut g_u = Mat::zeros(p, commands);
    let mut values = vec![0.0; p];
    if p == 0 {
        return Ok(PlantOutputs { values, c, d, g_u });
    }
    let normals = normals(model, t, y, outputs)?;
    let measure = |model: &mut dyn SceneModel,
                   loads: &ExternalLoads,
                   probe: &[f64],
                   out: &mut [f64]|
     -> Result<(), LinearError> {
        channel::measure(model, t, probe, loads, outputs, &normals, out)?;
        Ok(())
    };
    measure(model, base, y, &mut values)?;
    // The gradients of every output in the model's state, one difference per component for
    // all outputs at once: the coordinates only when no output depends on more.
    let columns = if outputs.iter().all(of_coordinates) {
        layout.own
    } else {
        layout.model_dim
    };
    let mut gradient = Mat::<f64>::zeros(p, n);
    differentiate(
        y,
        0..columns,
        p,
        &mut |probe, out| measure(model, base, probe, out),
        &mut |j, column| {
            for (row, v) in column.iter().enumerate() {
                gradient[(row, layout.index(j))] = *v;
            }
        },
    )?;
    let (own, total) = (layout.own, layout.total);
    for (row, output) in outputs.iter().enumerate() {
        for (k, g) in layout.gradient(output).into_iter().enumerate() {
            gradient[(row, own + k)] = g;
        }
        for (k, g) in layout.rate_gradient(output).into_iter().enumerate() {
            gradient[(row, total + own + k)] = g;
        }
    }
    for (row, output) in outputs.iter().enumerate() {
        match output {
            Output::Acceleration { .. } => {
                // n . r'' = (d(n . r)/dq) q'' at rest: the acceleration rows of A x + B u.
                for j in 0..total {
                    let g = gradient[(row, j)];
                    if g == 0.0 {
                        continue;
                    }
                    for col in 0..n {
                        c[(row, col)] += g * a[(total + j, col)];
                    }
                    for col in 0..commands {
                        g_u[(row, col)] += g * b[(total + j, col)];
                    }
                    for col in 0..users {
                        d[(row, col)] += g * b[(total + j, commands + col)];
                    }
                }
                values[row] = 0.0;
            }
            Output::SliderCommand(i) if slider_sampled => {
                // The command a sample gives is the one held: the law's, which the
                // discretisation composes; the plant only passes it through.
                g_u[(row, *i)] = 1.0;
            }
            _ => {
                for j in 0..n {
                    c[(row, j)] = gradient[(row, j)];
                }
            }
        }
    }
    // D and the commands' gradient by differences in each input (accelerations above).
    let direct: Vec<usize> = (0..p)
        .filter(|&row| {
            let acceleration = matches!(outputs[row], Output::Acceleration { .. });
            let held = slider_sampled && matches!(outputs[row], Output::SliderCommand(_));
            !(acceleration || held)
        })
        .collect();
    if !direct.is_empty() {
        for (k, input) in plant_inputs.iter().enumerate() {
            let column = input_derivative(model, base, *input, p, &mut |m, loads, out| {
                measure(m, loads, y, out)
            })?;
            for &row in &direct {
                if k < commands {
                    g_u[(row, k)] = column[row];
                } else {
                    d[(row, k - commands)] = column[row];
                }
            }
        }
    }
    Ok(PlantOutputs { values, c, d, g_u })
}
