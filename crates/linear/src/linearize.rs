//! The linearisation of any scene model about a state: `x' = A x + B u`, `y = C x + D u`
//! with `x` the deviation of the model's state from the operating point, or, when the
//! model's control law is sampled, the exact discrete-time model `x[k+1] = A x[k] + B u[k]`,
//! `y[k] = C x[k] + D u[k]` of the sampled loop ([`crate::discrete`]).
//!
//! * `A` from the model's mechanical form `M`, `C`, `K` where the model says they are the
//!   exact derivatives there ([`flexprr_dynamics::LinearHints::exact_mechanical_form`]: the
//!   nonlinear model at rest without actuators or patches), `A = [0 I; -M^-1 K  -M^-1 C]`;
//! * elsewhere `A = df/dy` by central differences with one Richardson extrapolation (error of fourth
//!   order in the step; exact for the models' quadratic terms, Dahlquist & Bjorck,
//!   *Numerical Methods in Scientific Computing*, 2008, 3.3.4);
//! * `B`: central differences of the right-hand side in each input (forces, setpoints,
//!   patch voltages); exact for the loads, in which the right-hand side is affine
//!   ([`flexprr_dynamics::LoadInput::set_loads`]);
//! * `C`: outputs that are functions of the state (slider positions and velocities, the
//!   platform pose and its rates, tracking errors, deflections, slopes, patch sensors, the
//!   law's command and the motor torque) by the same differences, and `D` by differences in
//!   the inputs; the acceleration of a link point is `n . dr/dq q''` with `q''` the
//!   acceleration rows of `A x + B u`, which gives its `C` and `D` rows.
//!
//! Non-smooth terms: the actuators' Coulomb friction is held at its value at the operating
//! point by default ([`Coulomb::LeftOut`]: the slope of its smoothed form at rest is the
//! smoothing's, not a damper), and the output says so ([`Linearization::notes`]); a
//! saturated actuator or patch at the operating point is reported (its loop is open there).

use faer::Mat;
use flexprr_dynamics::channel::{self, Input, Output};
use flexprr_dynamics::{ExternalLoads, SceneModel};

use crate::LinearError;
use crate::relax::{Relaxation, relax_chords};

/// How the actuators' Coulomb friction enters a linearisation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Coulomb {
    /// Held at its value at the operating point (the default): at zero slider speed the
    /// smoothed `tanh` law's slope `tau_C / omega_s` is an artefact of the smoothing (a
    /// stiff damper of about 1e5 N s/m for the shipped motor scenes); a real stuck slider
    /// is neither free nor damped. Away from rest the slope is negligible anyway.
    #[default]
    LeftOut,
    /// Its smoothed slope kept (the model as it is integrated).
    Smoothed,
}

/// How a linearisation is made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Settings {
    /// How `A` is obtained.
    pub derivatives: Derivatives,
    /// The actuators' Coulomb friction.
    pub coulomb: Coulomb,
}

/// A name of a state component: for readers and as an identifier (python-control's and
/// MATLAB's signal names).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateName {
    /// What it is (`rate of modal coordinate of link 1, mode 2`).
    pub name: String,
    /// An identifier (`eta_1_2_rate`).
    pub signal: String,
}

/// A linear model of a scene model about an operating point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// The time of the operating point (s).
    pub t: f64,
    /// The operating point: the model's state (with the relaxed chords' coordinates, 0), then
    /// a sampled law's states.
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
    /// (a model that offers it, at rest: [`flexprr_dynamics::LinearHints::chord_compliance`]).
    /// Then the coordinates are the model's followed by the platform's deviation `(dx, dy,
    /// dphi)` from the pose the rigid chords impose (and the links' axial coordinates), and
    /// the state is those coordinates, their rates, then the control law's states.
    pub elastic_chords: bool,
    /// How `A` was obtained.
    pub derivatives: Derivatives,
    /// The sample period of a discrete-time model (s): the period of the model's sampled
    /// control law; 0 for a continuous-time model.
    pub dt: f64,
    /// Number of states of a sampled control law at the end of the state (0 for a
    /// continuous model, whose law's states are part of the model's state).
    pub law_states: usize,
    /// The name of each state component.
    pub states: Vec<StateName>,
    /// What the model leaves out or finds at the operating point (Coulomb friction held,
    /// saturated actuators), one line each.
    pub notes: Vec<String>,
    /// Coordinates the relaxation of the chords added (after the model's own).
    pub(crate) added: usize,
}

impl Linearization {
    /// A linear model from its matrices (continuous for `dt = 0`, else discrete at `dt`),
    /// without channels' names or an operating point: for tests and for models built
    /// elsewhere. The states are named `x_1 ..`.
    pub fn from_matrices(a: Mat<f64>, b: Mat<f64>, c: Mat<f64>, d: Mat<f64>, dt: f64) -> Self {
        let n = a.nrows();
        let p = c.nrows();
        Self {
            t: 0.0,
            state: vec![0.0; n],
            coordinates: n / 2,
            a,
            inputs: Vec::new(),
            b,
            outputs: Vec::new(),
            c,
            d,
            output_values: vec![0.0; p],
            elastic_chords: false,
            derivatives: Derivatives::Differences,
            dt,
            law_states: 0,
            states: (0..n)
                .map(|k| StateName {
                    name: format!("state {}", k + 1),
                    signal: format!("x_{}", k + 1),
                })
                .collect(),
            notes: Vec::new(),
            added: 0,
        }
    }

    /// Whether the model is in discrete time.
    pub fn is_discrete(&self) -> bool {
        self.dt > 0.0
    }

    /// The model's own state component of linear state component `k`, or `None` for a
    /// coordinate or rate the relaxed chords add, or a sampled law's state.
    pub fn model_component(&self, k: usize) -> Option<usize> {
        let total = self.coordinates;
        let own = total - self.added;
        let model_states = self.a.nrows() - self.law_states;
        if k >= model_states {
            None
        } else if k < own {
            Some(k)
        } else if k < total {
            None
        } else if k < total + own {
            Some(k - self.added)
        } else if k < 2 * total {
            None
        } else {
            Some(k - 2 * self.added)
        }
    }

    /// A reader's name of linear state component `k` that the model does not have (the
    /// relaxed chords' coordinates, a sampled law's states), or `None` for the model's own
    /// components.
    pub fn added_component_name(&self, k: usize) -> Option<String> {
        if self.model_component(k).is_some() {
            return None;
        }
        self.states.get(k).map(|s| s.name.clone())
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

/// A function of the model under loads written into a slice, or the model's failure.
pub(crate) type LoadsFunction<'a> =
    dyn FnMut(&mut dyn SceneModel, &ExternalLoads, &mut [f64]) -> Result<(), LinearError> + 'a;

/// A function of the state written into a slice, or the model's failure.
pub(crate) type StateFunction<'a> = dyn FnMut(&[f64], &mut [f64]) -> Result<(), LinearError> + 'a;

/// `(g(y + h e_j) - g(y - h e_j)) / 2h` extrapolated from `h` and `h / 2`, for every `j` of
/// `columns`, written column by column by `put(j, derivative)`.
pub(crate) fn differentiate(
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
pub(crate) fn rhs(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    dy: &mut [f64],
) -> Result<(), LinearError> {
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

/// How `A` was (or is to be) obtained.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Derivatives {
    /// Central differences of the right-hand side with one Richardson extrapolation.
    Differences,
    /// From the model's exact mechanical form (`M`, `C`, `K`;
    /// [`flexprr_dynamics::LinearHints::exact_mechanical_form`]) where it is exact, else by
    /// differences (the default).
    #[default]
    Analytic,
}

/// Linearises `model` about its state `y` at `t` for `inputs` and `outputs` with the
/// default [`Settings`]: `A` from the model's mechanical form where it is exact there, else
/// by differences; Coulomb friction held; a sampled control law discretised exactly.
///
/// # Errors
/// The model fails near the operating point (kinematics, a singular pose), an input or
/// output the model cannot give (a reference without a control law, a patch the scene does
/// not have), a non-finite right-hand side, a model too large for a dense linear analysis
/// ([`crate::cost`]).
pub fn linearize(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    inputs: &[Input],
    outputs: &[Output],
) -> Result<Linearization, LinearError> {
    linearize_with_settings(model, t, y, inputs, outputs, &Settings::default())
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
    let settings = Settings {
        derivatives: wanted,
        ..Settings::default()
    };
    linearize_with_settings(model, t, y, inputs, outputs, &settings)
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

/// An input of the plant as the linearisation applies it: a user's input, or the command
/// of a sampled law (its loop opened).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum PlantInput {
    /// One of the linear model's inputs.
    User(Input),
    /// The force command of slider `i`, replacing the sampled law's.
    SliderCommand(usize),
    /// The voltage command of patch `p`, replacing the sampled vibration law's.
    PatchCommand(usize),
}

impl PlantInput {
    /// The difference step: 1 N for forces (exact: the right-hand side is affine in them),
    /// 10 um and 0.1 mm/s for setpoints, 10 mV for voltages.
    fn step(self) -> f64 {
        match self {
            PlantInput::User(input) => match input {
                Input::SliderForce(_) | Input::PointForce { .. } => 1.0,
                Input::Reference(_) => 1e-5,
                Input::ReferenceRate(_) => 1e-4,
                Input::PatchVoltage(_) => 1e-2,
                Input::ActuatorCommand(_) => 1.0,
            },
            PlantInput::SliderCommand(_) => 1.0,
            PlantInput::PatchCommand(_) => 1e-2,
        }
    }

    /// `loads` with this input moved by `value`.
    fn apply(self, loads: &ExternalLoads, value: f64, patches: usize) -> ExternalLoads {
        let mut out = loads.clone();
        match self {
            PlantInput::User(input) => input.add_to(&mut out, value, patches),
            PlantInput::SliderCommand(i) => {
                out.slider_command[i] = Some(loads.slider_command[i].unwrap_or(0.0) + value);
            }
            PlantInput::PatchCommand(p) => {
                if let Some(v) = out.patch_command.as_mut().and_then(|c| c.get_mut(p)) {
                    *v += value;
                }
            }
        }
        out
    }

    /// Where a point force acts (its share on the relaxed chords' coordinates).
    fn point(self) -> Option<(usize, f64)> {
        match self {
            PlantInput::User(Input::PointForce { link, xi }) => Some((link, xi)),
            _ => None,
        }
    }
}

/// `(g(loads + h) - g(loads - h)) / 2h` for the plant input `input` of `g` evaluated with
/// the model's loads set.
pub(crate) fn input_derivative(
    model: &mut dyn SceneModel,
    base: &ExternalLoads,
    input: PlantInput,
    width: usize,
    g: &mut LoadsFunction<'_>,
) -> Result<Vec<f64>, LinearError> {
    let h = input.step();
    let patches = model.patch_count();
    let (mut plus, mut minus) = (vec![0.0; width], vec![0.0; width]);
    for (value, target) in [(h, &mut plus), (-h, &mut minus)] {
        let loads = input.apply(base, value, patches);
        model.set_loads(&loads).map_err(LinearError::Model)?;
        let outcome = g(model, &loads, target);
        set_loads(model, base)?;
        outcome?;
    }
    Ok((0..width)
        .map(|k| (plus[k] - minus[k]) / (2.0 * h))
        .collect())
}

/// [`linearize`] with explicit [`Settings`].
///
/// # Errors
/// As [`linearize`].
pub fn linearize_with_settings(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    inputs: &[Input],
    outputs: &[Output],
    settings: &Settings,
) -> Result<Linearization, LinearError> {
    let n = model.dim();
    if y.len() != n {
        return Err(LinearError::Channel(format!(
            "the operating point has {} entries, the {} model's state {n}",
            y.len(),
            model.kind()
        )));
    }
    crate::cost::check(n, outputs.len())?;
    for input in inputs {
        channel::check_input(model, input).map_err(|e| LinearError::Channel(e.0))?;
    }
    set_loads(model, &ExternalLoads::default())?;
    for output in outputs {
        channel::check_output(model, t, y, output).map_err(|e| LinearError::Channel(e.0))?;
    }
    let mut notes = model
        .actuation()
        .map_or_else(Vec::new, |a| a.controller.linear_notes());
    let laws = model.sampled_laws(t);
    let period = crate::discrete::common_period(&laws)?;
    // The loads that hold the operating point: friction held, sampled loops opened at
    // their commands there.
    let mut base = ExternalLoads::default();
    if model.slider_law() {
        let snapshot = model.snapshot(t, y)?;
        let velocity = snapshot.sliders.map(|s| s.velocity);
        if let Some(actuation) = model.actuation() {
            let non_smooth: Vec<usize> = (0..3)
                .filter(|&i| actuation.actuators[i].friction_is_non_smooth_at(velocity[i]))
                .collect();
            if settings.coulomb == Coulomb::LeftOut {
                base.friction_velocity = Some(velocity);
                if !non_smooth.is_empty() {
                    notes.push(format!(
                        "Coulomb friction left out at slider{} {} (at rest its smoothed slope \
                         is the smoothing's, not a damper); --coulomb smoothed keeps it",
                        if non_smooth.len() > 1 { "s" } else { "" },
                        join(&non_smooth)
                    ));
                }
            } else if !non_smooth.is_empty() {
                notes.push(format!(
                    "Coulomb friction kept with its smoothed slope at slider{} {} (a stiff \
                     damper at rest: the smoothing's, not the machine's)",
                    if non_smooth.len() > 1 { "s" } else { "" },
                    join(&non_smooth)
                ));
            }
        }
        if period == 0.0 {
            if let Some(actuators) = snapshot.actuators {
                for (i, a) in actuators.iter().enumerate() {
                    if a.output.saturated {
                        notes.push(saturation_note(i, a.command, model));
                    }
                }
                // A loop broken at its actuator: the actuator holds the law's command of
                // the operating point, the input moves it.
                for input in inputs {
                    if let Input::ActuatorCommand(i) = *input {
                        base.slider_command[i] = Some(actuators[i].command);
                    }
                }
            }
        }
    }
    let mut law = None;
    if period > 0.0 {
        set_loads(model, &base)?;
        let sample = model.law_sample(t, y, &laws.slider_states)?;
        if laws.slider_period > 0.0 {
            base.slider_command = sample.slider_command.map(Some);
            if let Some(actuation) = model.actuation() {
                for i in 0..3 {
                    let command = sample.slider_command[i];
                    if actuation.actuators[i].apply(command, 0.0).saturated {
                        notes.push(saturation_note(i, command, model));
                    }
                }
            }
        }
        if laws.patch_period > 0.0 {
            base.patch_command = Some(sample.patch_command.clone());
        }
        law = Some(sample);
    }
    if let Ok(patches) = model.patch_states(t, y) {
        for (p, state) in patches.iter().enumerate() {
            if state.saturated && period == 0.0 {
                notes.push(format!(
                    "patch {} saturated at the operating point (command {:.4} V beyond its \
                     limit): its loop is open in this model",
                    p + 1,
                    state.command
                ));
            }
        }
    }
    set_loads(model, &base)?;
    let coordinates = model.modes();
    let mut a = Mat::zeros(n, n);
    let analytic = settings.derivatives == Derivatives::Analytic
        && base == ExternalLoads::default()
        && mechanical_a(model, t, y, &mut a)?;
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
    let mut plant_inputs: Vec<PlantInput> = Vec::new();
    if laws.slider_period > 0.0 {
        plant_inputs.extend((0..3).map(PlantInput::SliderCommand));
    }
    if laws.patch_period > 0.0 {
        plant_inputs.extend((0..model.patch_count()).map(PlantInput::PatchCommand));
    }
    let commands = plant_inputs.len();
    // The commands of a sampled law that a loop broken at its actuator takes from an input
    // instead.
    let opened: Vec<bool> = plant_inputs
        .iter()
        .map(|p| match p {
            PlantInput::SliderCommand(i) => inputs.contains(&Input::ActuatorCommand(*i)),
            _ => false,
        })
        .collect();
    plant_inputs.extend(inputs.iter().map(|i| PlantInput::User(*i)));
    let mut b = Mat::zeros(n, plant_inputs.len());
    for (k, input) in plant_inputs.iter().enumerate() {
        let column = input_derivative(model, &base, *input, n, &mut |m, _, out| rhs(m, t, y, out))?;
        for (i, v) in column.into_iter().enumerate() {
            b[(i, k)] = v;
        }
    }
    let compliance = model.chord_compliance(t, y).map_err(LinearError::Model)?;
    let points: Vec<Option<(usize, f64)>> = plant_inputs.iter().map(|i| i.point()).collect();
    let relaxation = Relaxation::new(compliance.as_ref(), coordinates, n);
    let (a, b) = match &compliance {
        Some(cc) => relax_chords(&a, &b, coordinates, cc, &points)?,
        None => (a, b),
    };
    let outputs_of = crate::outputs::plant_outputs(
        model,
        t,
        y,
        &base,
        &relaxation,
        &a,
        &b,
        &plant_inputs,
        commands,
        outputs,
        laws.slider_period > 0.0,
    )?;
    let mut outputs_of = outputs_of;
    for (k, open) in opened.iter().enumerate() {
        if !open {
            continue;
        }
        // The applied command of a broken loop is an input (its D columns); only the law's
        // own command stays composed with the law.
        for (row, output) in outputs.iter().enumerate() {
            if !matches!(output, Output::SliderCommand(i) if plant_inputs[k] == PlantInput::SliderCommand(*i))
            {
                outputs_of.g_u[(row, k)] = 0.0;
            }
        }
    }
    let mut states = crate::names::state_names(model, &relaxation);
    let mut state = relaxation.state(y);
    let (a, b, c, d, law_states) = match law {
        None => (a, b, outputs_of.c, outputs_of.d, 0),
        Some(sample) => {
            let closed = crate::discrete::close_sampled_loop(
                model,
                t,
                y,
                &base,
                &relaxation,
                &laws,
                &sample,
                period,
                &a,
                &b,
                commands,
                &plant_inputs[commands..],
                &outputs_of,
                &opened,
            )?;
            let z = laws.slider_states.len();
            state.extend_from_slice(&laws.slider_states);
            let law_name = model
                .actuation()
                .map_or_else(|| "control".to_string(), |a| a.controller.name());
            states.extend((0..z).map(|k| StateName {
                name: format!("state {} of the sampled {law_name} law", k + 1),
                signal: format!("law_{}", k + 1),
            }));
            (closed.a, closed.b, closed.c, closed.d, z)
        }
    };
    if period > 0.0 {
        notes.insert(
            0,
            format!(
                "discrete time at the law's period T = {} s (zero-order hold; the command of \
                 a sample acts from that sample on): poles z, frequencies from s = ln(z) / T, \
                 those above the Nyquist frequency {} Hz fold below it",
                period,
                (0.5 / period * 1e6).round() / 1e6
            ),
        );
    }
    set_loads(model, &ExternalLoads::default())?;
    Ok(Linearization {
        t,
        state,
        coordinates: relaxation.total,
        a,
        inputs: inputs.to_vec(),
        b,
        outputs: outputs.to_vec(),
        c,
        d,
        output_values: outputs_of.values,
        elastic_chords: compliance.is_some(),
        derivatives: if analytic {
            Derivatives::Analytic
        } else {
            Derivatives::Differences
        },
        dt: period,
        law_states,
        states,
        notes,
        added: relaxation.total - relaxation.own,
    })
}

/// Sets `loads` on `model`; a model that takes none (the KED model) is left alone when
/// they are the default.
pub(crate) fn set_loads(
    model: &mut dyn SceneModel,
    loads: &ExternalLoads,
) -> Result<(), LinearError> {
    match model.set_loads(loads) {
        Err(_) if *loads == ExternalLoads::default() => Ok(()),
        other => other.map_err(LinearError::Model),
    }
}

/// `1, 2 and 3` (1-based).
fn join(items: &[usize]) -> String {
    let words: Vec<String> = items.iter().map(|i| (i + 1).to_string()).collect();
    match words.len() {
        0 => String::new(),
        1 => words[0].clone(),
        k => format!("{} and {}", words[..k - 1].join(", "), words[k - 1]),
    }
}

/// The note of a saturated actuator.
fn saturation_note(i: usize, command: f64, model: &dyn SceneModel) -> String {
    let limit = model
        .actuation()
        .map_or(f64::INFINITY, |a| a.actuators[i].force_limit());
    format!(
        "slider {}'s actuator is saturated at the operating point (command {:.4e} N, limit \
         {:.4e} N): its loop is open in this model",
        i + 1,
        command,
        limit
    )
}
