//! The linearisation of any scene model about a state: `x' = A x + B u`, `y = C x + D u`
//! with `x` the deviation of the model's state from the operating point.
//!
//! * `A` from the model's mechanical form `M`, `C`, `K` where the model says they are the
//!   exact derivatives there ([`flexprr_dynamics::SceneModel::exact_mechanical_form`]: the
//!   nonlinear model at rest without actuators or patches), `A = [0 I; -M^-1 K  -M^-1 C]`;
//! * elsewhere `A = df/dy` by central differences with one Richardson extrapolation (error of fourth
//!   order in the step; exact for the models' quadratic terms, Dahlquist & Bjorck,
//!   *Numerical Methods in Scientific Computing*, 2008, 3.3.4);
//! * `B`: the right-hand side is affine in the external loads
//!   ([`flexprr_dynamics::SceneModel::set_loads`]), so the difference of the right-hand
//!   sides with a unit load and without is exact;
//! * `C`: outputs that are functions of the coordinates (slider positions and platform pose
//!   from the model's snapshot, deflection and slope from the model) by the same differences;
//!   the acceleration of a link point is `n . dr/dq q''` with `q''` the acceleration rows of
//!   `A x + B u`, which gives its `C` and `D` rows.

use faer::Mat;
use flexprr_dynamics::{ExternalLoads, PointForce, SceneModel};

use crate::{Axis, Input, LinearError, Output};

/// A linear model of a scene model about an operating point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// The time of the operating point (s).
    pub t: f64,
    /// The operating point (the model's state).
    pub state: Vec<f64>,
    /// Number of generalized coordinates (the state holds them, their rates, then the
    /// control law's states).
    pub coordinates: usize,
    /// `A` (`n x n`).
    pub a: Mat<f64>,
    /// The inputs, in the order of `B`'s columns.
    pub inputs: Vec<Input>,
    /// `B` (`n x m`).
    pub b: Mat<f64>,
    /// The outputs, in the order of `C`'s rows.
    pub outputs: Vec<Output>,
    /// `C` (`p x n`).
    pub c: Mat<f64>,
    /// `D` (`p x m`).
    pub d: Mat<f64>,
    /// The outputs' values at the operating point.
    pub output_values: Vec<f64>,
    /// Whether the model's axially rigid chords were relaxed into the links' axial springs
    /// (a model that offers it, at rest: [`flexprr_dynamics::SceneModel::chord_compliance`]).
    /// Then the coordinates are the model's followed by the platform's deviation `(dx, dy,
    /// dphi)` from the pose the rigid chords impose, and the state is those coordinates,
    /// their rates, then the control law's states.
    pub elastic_chords: bool,
    /// How `A` was obtained.
    pub derivatives: Derivatives,
}

/// The number of coordinates the relaxed chords add (the platform deviation).
const DEVIATION: usize = 3;

impl Linearization {
    /// The model's own state component of linear state component `k`, or `None` for a
    /// coordinate or rate of the platform deviation that relaxed chords add.
    pub fn model_component(&self, k: usize) -> Option<usize> {
        if !self.elastic_chords {
            return Some(k);
        }
        let total = self.coordinates;
        let own = total - DEVIATION;
        if k < own {
            Some(k)
        } else if k < total {
            None
        } else if k < total + own {
            Some(k - DEVIATION)
        } else if k < 2 * total {
            None
        } else {
            Some(k - 2 * DEVIATION)
        }
    }

    /// A reader's name of linear state component `k` that the model does not have (the
    /// platform deviation of relaxed chords), or `None` for the model's own components.
    pub fn added_component_name(&self, k: usize) -> Option<String> {
        if self.model_component(k).is_some() {
            return None;
        }
        let total = self.coordinates;
        let (index, rate) = if k < total {
            (k + DEVIATION - total, false)
        } else {
            (k + DEVIATION - 2 * total, true)
        };
        let axis = ["x", "y", "phi"][index];
        Some(if rate {
            format!("rate of the platform deviation {axis} on the elastic chords")
        } else {
            format!("platform deviation {axis} on the elastic chords")
        })
    }
}

/// Relative step of the central differences (with Richardson extrapolation the truncation
/// error is `O(h^4)`; round-off grows as `eps / h`).
const RELATIVE_STEP: f64 = 1e-5;

/// Smallest scale of a state component for the step (m, rad, m/s, rad/s).
const STEP_FLOOR: f64 = 1e-2;

/// The difference step of state component `j`.
fn step(y: f64) -> f64 {
    RELATIVE_STEP * y.abs().max(STEP_FLOOR)
}

/// A function of the state written into a slice, or the model's failure.
type StateFunction<'a> = dyn FnMut(&[f64], &mut [f64]) -> Result<(), LinearError> + 'a;

/// `(g(y + h e_j) - g(y - h e_j)) / 2h` extrapolated from `h` and `h / 2`, for every `j` of
/// `columns`, written column by column by `put(j, derivative)`.
fn differentiate(
    y: &[f64],
    columns: std::ops::Range<usize>,
    width: usize,
    g: &mut StateFunction<'_>,
    put: &mut dyn FnMut(usize, &[f64]),
) -> Result<(), LinearError> {
    let mut probe = y.to_vec();
    let (mut plus, mut minus) = (vec![0.0; width], vec![0.0; width]);
    let mut coarse = vec![0.0; width];
    let mut column = vec![0.0; width];
    for j in columns {
        for (level, h) in [step(y[j]), 0.5 * step(y[j])].into_iter().enumerate() {
            probe[j] = y[j] + h;
            g(&probe, &mut plus)?;
            probe[j] = y[j] - h;
            g(&probe, &mut minus)?;
            probe[j] = y[j];
            let target = if level == 0 { &mut coarse } else { &mut column };
            for k in 0..width {
                target[k] = (plus[k] - minus[k]) / (2.0 * h);
            }
        }
        for k in 0..width {
            column[k] = (4.0 * column[k] - coarse[k]) / 3.0;
        }
        put(j, &column);
    }
    Ok(())
}

/// The right-hand side of `model` at `(t, y)`, or the model's failure there.
fn rhs(model: &mut dyn SceneModel, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), LinearError> {
    model.rhs(t, y, dy);
    if let Some(e) = model.take_failure() {
        return Err(LinearError::Model(e));
    }
    if dy.iter().any(|v| !v.is_finite()) {
        return Err(LinearError::Channel(format!(
            "the {} model's right-hand side is not finite near the operating point",
            model.kind()
        )));
    }
    Ok(())
}

/// The loads of one unit input.
fn unit_load(input: &Input) -> ExternalLoads {
    match *input {
        Input::SliderForce(i) => {
            let mut loads = ExternalLoads::default();
            loads.slider[i] = 1.0;
            loads
        }
        Input::PointForce { link, xi } => ExternalLoads {
            point: vec![PointForce {
                link,
                xi,
                force: 1.0,
            }],
            ..ExternalLoads::default()
        },
    }
}

/// Every output's value at `(t, y)` into `out`: those that are functions of the coordinates
/// (all but accelerations) as they are, an acceleration as the position of its link point
/// projected on its fixed normal `normals[k]`. The model's snapshot is taken once.
fn output_values(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    outputs: &[Output],
    normals: &[[f64; 2]],
    out: &mut [f64],
) -> Result<(), LinearError> {
    let needs_snapshot = outputs
        .iter()
        .any(|o| !matches!(o, Output::Deflection { .. } | Output::Slope { .. }));
    let snapshot = if needs_snapshot {
        Some(model.snapshot(t, y)?)
    } else {
        None
    };
    for (k, output) in outputs.iter().enumerate() {
        let machine = snapshot.as_ref();
        out[k] = match (*output, machine) {
            (Output::SliderPosition(i), Some(s)) => s.sliders[i].position,
            (Output::Platform(axis), Some(s)) => match axis {
                Axis::X => s.platform.pose.x,
                Axis::Y => s.platform.pose.y,
                Axis::Phi => s.platform.pose.phi,
            },
            (Output::Deflection { link, xi }, _) => model.deflection(t, link, xi, y)?,
            (Output::Slope { link, xi }, _) => model.slope(t, link, xi, y)?,
            (Output::Acceleration { link, xi }, Some(s)) => {
                let (b, c) = chord_of(model, s, link);
                let w = model.deflection(t, link, xi, y)?;
                let (dx, dy) = (c[0] - b[0], c[1] - b[1]);
                let length = dx.hypot(dy);
                let point = [
                    b[0] + xi * dx - w * dy / length,
                    b[1] + xi * dy + w * dx / length,
                ];
                point[0] * normals[k][0] + point[1] * normals[k][1]
            }
            _ => unreachable!("the snapshot is taken for these outputs"),
        };
    }
    Ok(())
}

/// The chord `B_i`, `C_i` of link `link` in the machine `snapshot`.
fn chord_of(
    model: &dyn SceneModel,
    snapshot: &flexprr_dynamics::MachineSnapshot,
    link: usize,
) -> ([f64; 2], [f64; 2]) {
    let leg = &model.machine().geometry.legs[link];
    let u = leg.guide.direction.into_inner();
    let rho = snapshot.sliders[link].position;
    let b = leg.guide.anchor.coords + rho * u;
    let pose = snapshot.platform.pose;
    let (sin, cos) = pose.phi.sin_cos();
    let a = leg.attachment;
    let c = [
        pose.x + cos * a.x - sin * a.y,
        pose.y + sin * a.x + cos * a.y,
    ];
    ([b.x, b.y], c)
}

/// How `A` was (or is to be) obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Derivatives {
    /// Central differences of the right-hand side with one Richardson extrapolation.
    Differences,
    /// From the model's exact mechanical form (`M`, `C`, `K`;
    /// [`flexprr_dynamics::SceneModel::exact_mechanical_form`]).
    Analytic,
}

/// Linearises `model` about its state `y` at `t` for `inputs` and `outputs`: `A` from the
/// model's mechanical form where it is exact there, else by differences.
///
/// # Errors
/// The model fails near the operating point (kinematics, a singular pose), an input the
/// model cannot take (the KED model takes no loads), or a non-finite right-hand side.
pub fn linearize(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    inputs: &[Input],
    outputs: &[Output],
) -> Result<Linearization, LinearError> {
    linearize_with(model, t, y, inputs, outputs, Derivatives::Analytic)
}

/// `A = [0 I; -M^-1 K  -M^-1 C]` from the model's exact mechanical form into `a`, or
/// `false` (nothing written) when the model has none at `(t, y)`.
fn mechanical_a(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    a: &mut Mat<f64>,
) -> Result<bool, LinearError> {
    use faer::linalg::solvers::Solve;
    if !model.exact_mechanical_form(t, y) {
        return Ok(false);
    }
    let Some(form) = model.second_order_form() else {
        return Ok(false);
    };
    let n = form.coordinates();
    if 2 * n != y.len() {
        return Ok(false);
    }
    let (mut m, mut c, mut k) = (Mat::zeros(n, n), Mat::zeros(n, n), Mat::zeros(n, n));
    form.matrices(t, y, m.as_mut(), c.as_mut(), k.as_mut());
    let finite = |x: &Mat<f64>| (0..n).all(|j| x.col_as_slice(j).iter().all(|v| v.is_finite()));
    if !(finite(&m) && finite(&c) && finite(&k)) {
        return Err(LinearError::Channel(
            "the model's mass, damping or stiffness matrix is not finite at the operating point"
                .into(),
        ));
    }
    let lu = m.partial_piv_lu();
    let (mk, mc) = (lu.solve(&k), lu.solve(&c));
    for i in 0..n {
        a[(i, n + i)] = 1.0;
        for j in 0..n {
            a[(n + i, j)] = -mk[(i, j)];
            a[(n + i, n + j)] = -mc[(i, j)];
        }
    }
    let solved = (0..n).all(|j| {
        a.col_as_slice(j).iter().all(|v| v.is_finite())
            && a.col_as_slice(n + j).iter().all(|v| v.is_finite())
    });
    if !solved {
        return Err(LinearError::Channel(
            "the model's mass matrix is singular at the operating point".into(),
        ));
    }
    Ok(true)
}

/// [`linearize`] with the derivatives asked for: [`Derivatives::Differences`] everywhere
/// (the check of the analytic path, and of a model's claim that its form is exact), or
/// [`Derivatives::Analytic`] where the model's form is exact (what [`linearize`] does).
///
/// # Errors
/// As [`linearize`].
pub fn linearize_with(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    inputs: &[Input],
    outputs: &[Output],
    wanted: Derivatives,
) -> Result<Linearization, LinearError> {
    let n = model.dim();
    if y.len() != n {
        return Err(LinearError::Channel(format!(
            "the operating point has {} entries, the {} model's state {n}",
            y.len(),
            model.kind()
        )));
    }
    let coordinates = model.modes();
    let mut a = Mat::zeros(n, n);
    model.set_loads(&ExternalLoads::default()).ok();
    let analytic = wanted == Derivatives::Analytic && mechanical_a(model, t, y, &mut a)?;
    if !analytic {
        differentiate(
            y,
            0..n,
            n,
            &mut |probe, out| rhs(model, t, probe, out),
            &mut |j, column| {
                for (k, v) in column.iter().enumerate() {
                    a[(k, j)] = *v;
                }
            },
        )?;
    }
    let mut f0 = vec![0.0; n];
    rhs(model, t, y, &mut f0)?;
    let mut b = Mat::zeros(n, inputs.len());
    let mut loaded = vec![0.0; n];
    for (k, input) in inputs.iter().enumerate() {
        model.set_loads(&unit_load(input))?;
        let outcome = rhs(model, t, y, &mut loaded);
        model.set_loads(&ExternalLoads::default())?;
        outcome?;
        for i in 0..n {
            b[(i, k)] = loaded[i] - f0[i];
        }
    }
    let compliance = model.chord_compliance(t, y).map_err(LinearError::Model)?;
    let (a, b, state, total) = match &compliance {
        Some(cc) => {
            let (a, b) = relax_chords(&a, &b, coordinates, cc, inputs)?;
            let mut state = vec![0.0; n + 2 * DEVIATION];
            for (k, v) in y.iter().enumerate() {
                state[relaxed_index(k, coordinates)] = *v;
            }
            (a, b, state, coordinates + DEVIATION)
        }
        None => (a, b, y.to_vec(), coordinates),
    };
    let added = Added {
        own: coordinates,
        total,
        compliance: compliance.as_ref(),
    };
    let (c, d, output_values) = output_matrices(model, t, y, &added, &a, &b, outputs)?;
    Ok(Linearization {
        t,
        state,
        coordinates: total,
        a,
        inputs: inputs.to_vec(),
        b,
        outputs: outputs.to_vec(),
        c,
        d,
        output_values,
        elastic_chords: compliance.is_some(),
        derivatives: if analytic {
            Derivatives::Analytic
        } else {
            Derivatives::Differences
        },
    })
}

/// The index in the relaxed state (coordinates, deviation, their rates, the law's states)
/// of the model's state component `k` (`coordinates` coordinates, their rates, the law's).
fn relaxed_index(k: usize, coordinates: usize) -> usize {
    if k < coordinates {
        k
    } else if k < 2 * coordinates {
        k + DEVIATION
    } else {
        k + 2 * DEVIATION
    }
}

/// `A` and `B` of the model with its chords relaxed ([`flexprr_dynamics::ChordCompliance`]):
/// the model's generalized forces `F = M (A, B)` on its coordinates' acceleration rows, the
/// chords' springs and the point loads' share on the deviation, solved with the mass of
/// the coordinates and the deviation together.
fn relax_chords(
    a: &Mat<f64>,
    b: &Mat<f64>,
    coordinates: usize,
    cc: &flexprr_dynamics::ChordCompliance,
    inputs: &[Input],
) -> Result<(Mat<f64>, Mat<f64>), LinearError> {
    use faer::linalg::solvers::Solve;
    let (n, m, nz) = (a.nrows(), b.ncols(), coordinates);
    let total = nz + DEVIATION;
    let (n_new, map) = (n + 2 * DEVIATION, |k| relaxed_index(k, nz));
    let mut forces = Mat::<f64>::zeros(total, n_new);
    let mut load_forces = Mat::<f64>::zeros(total, m);
    for i in 0..nz {
        for col in 0..n {
            forces[(i, map(col))] = (0..nz).map(|k| cc.mass[(i, k)] * a[(nz + k, col)]).sum();
        }
        for col in 0..m {
            load_forces[(i, col)] = (0..nz).map(|k| cc.mass[(i, k)] * b[(nz + k, col)]).sum();
        }
    }
    for q in 0..DEVIATION {
        for r in 0..DEVIATION {
            forces[(nz + q, nz + r)] = -cc.stiffness[(q, r)];
        }
        for (col, input) in inputs.iter().enumerate() {
            if let Input::PointForce { link, xi } = *input {
                load_forces[(nz + q, col)] = xi * cc.joint_normal[link][q];
            }
        }
    }
    let mass = Mat::from_fn(total, total, |i, j| match (i < nz, j < nz) {
        (true, true) => cc.mass[(i, j)],
        (true, false) => cc.coupling[(i, j - nz)],
        (false, true) => cc.coupling[(j, i - nz)],
        (false, false) => cc.deviation_mass[(i - nz, j - nz)],
    });
    let llt = mass.llt(faer::Side::Lower).map_err(|_| {
        LinearError::Channel(
            "the mass matrix of the machine with elastic chords is not positive definite".into(),
        )
    })?;
    let accelerations = llt.solve(&forces);
    let load_accelerations = llt.solve(&load_forces);
    let mut relaxed = Mat::<f64>::zeros(n_new, n_new);
    let mut relaxed_b = Mat::<f64>::zeros(n_new, m);
    for i in 0..total {
        relaxed[(i, total + i)] = 1.0;
        for col in 0..n_new {
            relaxed[(total + i, col)] = accelerations[(i, col)];
        }
        for col in 0..m {
            relaxed_b[(total + i, col)] = load_accelerations[(i, col)];
        }
    }
    for row in 2 * nz..n {
        for col in 0..n {
            relaxed[(map(row), map(col))] = a[(row, col)];
        }
        for col in 0..m {
            relaxed_b[(map(row), col)] = b[(row, col)];
        }
    }
    Ok((relaxed, relaxed_b))
}

/// The coordinates a relaxation added to the model's, for the outputs' gradients.
struct Added<'a> {
    /// The model's own coordinates (the first ones).
    own: usize,
    /// All coordinates (the model's and the added ones).
    total: usize,
    compliance: Option<&'a flexprr_dynamics::ChordCompliance>,
}

impl Added<'_> {
    /// The gradient of `output` in the platform deviation (zero without it): the platform
    /// pose moves with it, and a link point at `xi` moves by `xi` times its joint's motion.
    fn gradient(&self, output: &Output) -> [f64; DEVIATION] {
        let Some(cc) = self.compliance else {
            return [0.0; DEVIATION];
        };
        match *output {
            Output::Platform(axis) => {
                let mut g = [0.0; DEVIATION];
                g[match axis {
                    Axis::X => 0,
                    Axis::Y => 1,
                    Axis::Phi => 2,
                }] = 1.0;
                g
            }
            Output::Acceleration { link, xi } => cc.joint_normal[link].map(|v| xi * v),
            _ => [0.0; DEVIATION],
        }
    }
}

/// `C`, `D` and the outputs' values.
type OutputRows = (Mat<f64>, Mat<f64>, Vec<f64>);

/// `C`, `D` and the outputs' values at the operating point.
fn output_matrices(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    added: &Added<'_>,
    a: &Mat<f64>,
    b: &Mat<f64>,
    outputs: &[Output],
) -> Result<OutputRows, LinearError> {
    let n = a.ncols();
    let (p, m) = (outputs.len(), b.ncols());
    let mut c = Mat::zeros(p, n);
    let mut d = Mat::zeros(p, m);
    let mut values = vec![0.0; p];
    if p == 0 {
        return Ok((c, d, values));
    }
    let snapshot = model.snapshot(t, y)?;
    let normals: Vec<[f64; 2]> = outputs
        .iter()
        .map(|o| match *o {
            Output::Acceleration { link, .. } => {
                let (b, c) = chord_of(model, &snapshot, link);
                let (dx, dy) = (c[0] - b[0], c[1] - b[1]);
                let length = dx.hypot(dy);
                [-dy / length, dx / length]
            }
            _ => [0.0; 2],
        })
        .collect();
    output_values(model, t, y, outputs, &normals, &mut values)?;
    // The gradients of every output in the model's coordinates, one difference per
    // coordinate for all outputs at once, then those in the added coordinates.
    let mut gradient = Mat::<f64>::zeros(p, added.total);
    differentiate(
        y,
        0..added.own,
        p,
        &mut |probe, out| output_values(model, t, probe, outputs, &normals, out),
        &mut |j, column| {
            for (row, v) in column.iter().enumerate() {
                gradient[(row, j)] = *v;
            }
        },
    )?;
    if added.compliance.is_some() {
        for (row, output) in outputs.iter().enumerate() {
            for (k, g) in added.gradient(output).into_iter().enumerate() {
                gradient[(row, added.own + k)] = g;
            }
        }
    }
    for (row, output) in outputs.iter().enumerate() {
        if let Output::Acceleration { .. } = output {
            // n . r'' = (d(n . r)/dq) q'' at rest: the acceleration rows of A x + B u.
            for j in 0..added.total {
                let g = gradient[(row, j)];
                for col in 0..n {
                    c[(row, col)] += g * a[(added.total + j, col)];
                }
                for col in 0..m {
                    d[(row, col)] += g * b[(added.total + j, col)];
                }
            }
            values[row] = 0.0;
        } else {
            for j in 0..added.total {
                c[(row, j)] = gradient[(row, j)];
            }
        }
    }
    Ok((c, d, values))
}
