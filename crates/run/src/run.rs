//! Running a scene: only the requested outputs are computed ("leave out what a scene does
//! not need"): a frequencies-only scene never integrates the ODE, a kinematics-only scene
//! never solves the inverse dynamics.

use std::time::Instant as Clock;

use flexprr_dynamics::{
    AxialInput, AxialModel, CoupledOptions, CoupledSystem, CouplingModel, FrequencyHistory,
    ModalSystem, end_forces, inverse_dynamics, rigid_kinetic_energy,
};
use flexprr_integrators::{OdeSystem, Solution, Stats};

use flexprr_scene::ScenarioError;
use flexprr_scene::{OutputKind, Scene};

/// A time-series table: first column `t_s`, then named columns with units in their names.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// File stem (`kinematics`, `deflections`, ...).
    pub name: String,
    /// Column names, `t_s` first.
    pub columns: Vec<String>,
    /// Column data, `data[column][row]`.
    pub data: Vec<Vec<f64>>,
}

impl Table {
    /// A table with only the time column.
    pub fn new(name: &str, t: &[f64]) -> Self {
        Self {
            name: name.to_string(),
            columns: vec!["t_s".into()],
            data: vec![t.to_vec()],
        }
    }
    /// Appends a column.
    pub fn push(&mut self, name: impl Into<String>, values: Vec<f64>) {
        self.columns.push(name.into());
        self.data.push(values);
    }
    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c == name)
            .map(|i| self.data[i].as_slice())
    }
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
}

/// What a run did (tests use it to prove that only the needed work was done).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunStats {
    /// Whether the modal ODE was integrated.
    pub integrated: bool,
    /// Right-hand-side evaluations of the modal system(s).
    pub rhs_evaluations: usize,
    /// Rigid inverse-dynamics solves (inside the ODE and for outputs).
    pub inverse_dynamics_solves: usize,
    /// Integrator statistics of the main integration.
    pub integrator: Option<Stats>,
    /// Wall-clock time of the whole run (s).
    pub wall_time_s: f64,
}

/// Everything a run produced.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The requested time series.
    pub tables: Vec<Table>,
    /// Frequencies along the motion, when requested.
    pub frequencies: Option<FrequencyHistory>,
    /// Work statistics.
    pub stats: RunStats,
}

impl RunResult {
    /// The table called `name`.
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }
}

/// Wraps a system to report progress as a fraction of the time span.
struct Progress<'a, S> {
    inner: &'a mut S,
    t0: f64,
    span: f64,
    calls: usize,
    report: &'a mut dyn FnMut(f64),
}

impl<S: OdeSystem> OdeSystem for Progress<'_, S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.calls += 1;
        if self.calls % 4096 == 0 {
            (self.report)(((t - self.t0) / self.span).clamp(0.0, 1.0));
        }
        self.inner.rhs(t, y, dy);
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: faer::MatMut<'_, f64>) {
        self.inner.jacobian(t, y, jac);
    }
    fn has_analytic_jacobian(&self) -> bool {
        self.inner.has_analytic_jacobian()
    }
}

/// Integrates `system` over the scene's output times with the scene's method.
///
/// # Errors
/// [`ScenarioError::Run`] with the integrator's or the system's reason and the time.
pub fn integrate(
    scene: &Scene,
    system: &mut ModalSystem,
    report: &mut dyn FnMut(f64),
) -> Result<Solution, ScenarioError> {
    let y0 = system.initial_state();
    let result = solve_with(scene, system, &y0, report);
    let solution = result.map_err(|e| match system.take_failure() {
        Some(cause) => ScenarioError::Run(format!("{cause} (integrator: {e})")),
        None => ScenarioError::Run(format!("{} integrator: {e}", scene.method.name())),
    })?;
    // The linear (small-deflection) model grows without bound while a link buckles: a run
    // whose deflection passes half the link length reports that instead of returning
    // deflections of kilometres.
    let fraction = crate::guard::RUNAWAY_DEFLECTION_FRACTION;
    match crate::guard::deflection_excess(scene, system, &solution, fraction) {
        Some(excess) => Err(ScenarioError::Run(format!(
            "diverged: {excess}; the small-deflection model has left its range (a link buckles, or the tolerance is too loose); request \"frequencies\" to see the buckling intervals"
        ))),
        None => Ok(solution),
    }
}

/// Solves any system over the scene's output times with the scene's method and options.
fn solve_with<S: OdeSystem>(
    scene: &Scene,
    system: &mut S,
    y0: &[f64],
    report: &mut dyn FnMut(f64),
) -> Result<Solution, flexprr_integrators::IntegratorError> {
    let t = &scene.output_times;
    let (t0, span) = (t[0], t[t.len() - 1] - t[0]);
    let mut wrapped = Progress {
        inner: system,
        t0,
        span,
        calls: 0,
        report,
    };
    scene
        .method
        .solve(scene.options.clone(), &mut wrapped, y0, t)
}

/// Integrates the coupled model (platform moved by the links' foreshortening) of a scene.
///
/// # Errors
/// [`ScenarioError::Run`] with the integrator's or the system's reason and the time.
pub fn integrate_coupled(
    scene: &Scene,
    report: &mut dyn FnMut(f64),
) -> Result<(Solution, CoupledSystem), ScenarioError> {
    let options = CoupledOptions {
        axial_stiffness: Some([scene.axial_stiffness; 3]),
        ..CoupledOptions::full()
    };
    let mut system = CoupledSystem::new(
        scene.machine.clone(),
        scene.trajectory.clone(),
        scene.damping.clone(),
        options,
    )
    .map_err(|e| ScenarioError::Run(e.to_string()))?;
    let y0 = system.initial_state();
    let solution =
        solve_with(scene, &mut system, &y0, report).map_err(|e| match system.take_failure() {
            Some(cause) => ScenarioError::Run(format!("{cause} (integrator: {e})")),
            None => ScenarioError::Run(format!(
                "{} integrator on the coupled model: {e}",
                scene.method.name()
            )),
        })?;
    Ok((solution, system))
}

fn new_system(scene: &Scene, axial_off: bool) -> Result<ModalSystem, ScenarioError> {
    let mut formulation = scene.formulation;
    if axial_off {
        formulation.axial = AxialModel::None;
    }
    ModalSystem::new(
        scene.machine.clone(),
        scene.trajectory.clone(),
        formulation,
        scene.damping.clone(),
    )
    .map_err(|e| ScenarioError::Run(e.to_string()))
}

/// Runs a scene, computing only what it requests. `report` receives the progress of the
/// integration (fraction of the time span).
///
/// # Errors
/// [`ScenarioError::Run`] when the integration or an output computation fails.
pub fn run(scene: &Scene, report: &mut dyn FnMut(f64)) -> Result<RunResult, ScenarioError> {
    let clock = Clock::now();
    let t = scene.output_times.clone();
    let n_out = t.len();
    let wants = |k: OutputKind| scene.outputs.contains(&k);
    let mut stats = RunStats::default();
    let mut tables = Vec::new();
    let mut system = new_system(scene, false)?;
    let machine = scene.machine.clone();
    let modes: [usize; 3] = std::array::from_fn(|i| machine.links[i].modes());
    let run_err = |e: flexprr_dynamics::DynamicsError| ScenarioError::Run(e.to_string());

    // The coupled model replaces the KED integration (and gives the actual axial and
    // driving forces and the platform's deviation).
    let coupled = if scene.coupling == CouplingModel::Coupled
        && (scene.needs_integration()
            || wants(OutputKind::AxialForces)
            || wants(OutputKind::DrivingForces))
    {
        let (sol, csys) = integrate_coupled(scene, report)?;
        stats.integrated = true;
        stats.integrator = Some(sol.stats.clone());
        stats.rhs_evaluations += csys.counters().rhs_evaluations;
        Some((sol, csys))
    } else {
        None
    };
    // The KED modal ODE, only when an output needs it.
    let solution = if coupled.is_none() && scene.needs_integration() {
        stats.integrated = true;
        let sol = integrate(scene, &mut system, report)?;
        stats.integrator = Some(sol.stats.clone());
        Some(sol)
    } else {
        None
    };
    let mut coupled_states: Option<Solution> = None;
    let without_axial = if solution.is_some() && scene.file.output.compare_without_axial_force {
        let mut plain = new_system(scene, true)?;
        let sol = integrate(scene, &mut plain, &mut |_| {})?;
        stats.rhs_evaluations += plain.counters().rhs_evaluations;
        stats.inverse_dynamics_solves += plain.counters().inverse_dynamics_solves;
        Some((sol, plain))
    } else {
        None
    };

    if wants(OutputKind::Kinematics) {
        let mut table = Table::new("kinematics", &t);
        let mut cols = columns(3 + 18, n_out);
        for &tk in &t {
            let motion = scene.trajectory.motion(tk);
            let state = machine
                .geometry
                .inverse_kinematics_unchecked(&motion)
                .map_err(|source| {
                    run_err(flexprr_dynamics::DynamicsError::Kinematics { t: tk, source })
                })?;
            cols[0].push(motion.pose.x);
            cols[1].push(motion.pose.y);
            cols[2].push(motion.pose.phi);
            for (i, leg) in state.legs.iter().enumerate() {
                let vals = [
                    leg.rho,
                    leg.rho_dot,
                    leg.rho_ddot,
                    leg.beta,
                    leg.beta_dot,
                    leg.beta_ddot,
                ];
                for (q, v) in vals.into_iter().enumerate() {
                    cols[3 + 6 * i + q].push(v);
                }
            }
        }
        let mut cols = cols.into_iter();
        for name in ["x_m", "y_m", "phi_rad"] {
            table.push(name, cols.next().unwrap_or_default());
        }
        for i in 1..=3 {
            for name in [
                "rho_{}_m",
                "rho_dot_{}_m_s",
                "rho_ddot_{}_m_s2",
                "beta_{}_rad",
                "beta_dot_{}_rad_s",
                "beta_ddot_{}_rad_s2",
            ] {
                table.push(
                    name.replace("{}", &i.to_string()),
                    cols.next().unwrap_or_default(),
                );
            }
        }
        tables.push(table);
    }

    // Outputs that need the rigid inverse dynamics at every output time.
    if wants(OutputKind::DrivingForces)
        || wants(OutputKind::JointReactions)
        || wants(OutputKind::AxialForces)
    {
        let axial_model = match scene.formulation.axial {
            AxialModel::None => AxialModel::JointReaction,
            other => other,
        }
        .model();
        let mut driving = columns(3, n_out);
        let mut driving_flex = columns(3, n_out);
        let mut reactions_cols = columns(12, n_out);
        let mut axial_cols = columns(6, n_out);
        for (k, &tk) in t.iter().enumerate() {
            let motion = scene.trajectory.motion(tk);
            let state = machine
                .geometry
                .inverse_kinematics_unchecked(&motion)
                .map_err(|source| {
                    run_err(flexprr_dynamics::DynamicsError::Kinematics { t: tk, source })
                })?;
            stats.inverse_dynamics_solves += 1;
            let rigid = inverse_dynamics(&machine, &state, None, tk).map_err(run_err)?;
            for i in 0..3 {
                driving[i].push(rigid.driving_force[i]);
                let (fb, fc) = (rigid.slider_on_link[i], rigid.platform_on_link[i]);
                for (q, v) in [fb.x, fb.y, fc.x, fc.y].into_iter().enumerate() {
                    reactions_cols[4 * i + q].push(v);
                }
                let load = axial_model.load(&AxialInput {
                    leg: &state.legs[i],
                    guide_direction: machine.geometry.legs[i].guide.direction.into_inner(),
                    link: &machine.links[i],
                    reactions: Some(&rigid),
                    index: i,
                });
                let (pb, pc) = end_forces(&load, machine.links[i].length());
                axial_cols[2 * i].push(pb);
                axial_cols[2 * i + 1].push(pc);
            }
            if let Some(sol) = &solution {
                let y = sol.y(k);
                let acc = system.modal_accelerations(tk, y).map_err(run_err)?;
                let elastic = system.elastic_inertia(&acc);
                stats.inverse_dynamics_solves += 1;
                let flex =
                    inverse_dynamics(&machine, &state, Some(&elastic), tk).map_err(run_err)?;
                for (column, force) in driving_flex.iter_mut().zip(flex.driving_force) {
                    column.push(force);
                }
            }
        }
        if wants(OutputKind::DrivingForces) {
            let mut table = Table::new("driving_forces", &t);
            for (i, column) in driving.iter().enumerate() {
                table.push(format!("F_a_{}_rigid_N", i + 1), column.clone());
            }
            if solution.is_some() {
                for i in 0..3 {
                    let diff: Vec<f64> = driving_flex[i]
                        .iter()
                        .zip(&driving[i])
                        .map(|(f, r)| f - r)
                        .collect();
                    table.push(format!("F_a_{}_flexible_N", i + 1), driving_flex[i].clone());
                    table.push(format!("F_a_{}_difference_N", i + 1), diff);
                }
            }
            tables.push(table);
        }
        if wants(OutputKind::JointReactions) {
            let mut table = Table::new("joint_reactions", &t);
            let mut cols = reactions_cols.into_iter();
            for i in 1..=3 {
                for name in ["F_B_{}_x_N", "F_B_{}_y_N", "F_C_{}_x_N", "F_C_{}_y_N"] {
                    table.push(
                        name.replace("{}", &i.to_string()),
                        cols.next().unwrap_or_default(),
                    );
                }
            }
            tables.push(table);
        }
        if wants(OutputKind::AxialForces) {
            let mut table = Table::new("axial_forces", &t);
            let mut cols = axial_cols.into_iter();
            for i in 1..=3 {
                table.push(format!("P_B_{i}_N"), cols.next().unwrap_or_default());
                table.push(format!("P_C_{i}_N"), cols.next().unwrap_or_default());
            }
            tables.push(table);
        }
    }

    let frequencies = if wants(OutputKind::Frequencies) {
        let before = system.counters().inverse_dynamics_solves;
        let hist = FrequencyHistory::sample(&mut system, &t).map_err(run_err)?;
        stats.inverse_dynamics_solves += system.counters().inverse_dynamics_solves - before;
        let mut table = Table::new("frequencies", &t);
        for (i, &r) in modes.iter().enumerate() {
            for j in 0..r {
                table.push(
                    format!("f_{}_{}_Hz", i + 1, j + 1),
                    hist.omega_squared[i][j]
                        .iter()
                        .map(|w| dynamics_hz(*w))
                        .collect(),
                );
            }
        }
        for i in 0..3 {
            table.push(
                format!("P_B_{}_N", i + 1),
                hist.end_forces[i].iter().map(|p| p.0).collect(),
            );
            table.push(
                format!("P_C_{}_N", i + 1),
                hist.end_forces[i].iter().map(|p| p.1).collect(),
            );
        }
        tables.push(table);
        Some(hist)
    } else {
        None
    };

    if let Some((sol, mut csys)) = coupled {
        let mut deviation = columns(6, n_out);
        let mut forces = columns(10, n_out);
        for (k, &tk) in t.iter().enumerate() {
            let out = csys.output(tk, sol.y(k)).map_err(run_err)?;
            let (plain, stretched) = (out.pose_deviation(), out.pose_deviation_with_stretch());
            for q in 0..3 {
                deviation[q].push(plain[q]);
                deviation[3 + q].push(stretched[q]);
            }
            for i in 0..3 {
                forces[3 * i].push(out.axial_force_b[i]);
                forces[3 * i + 1].push(out.axial_force_c[i]);
                forces[3 * i + 2].push(out.driving_force[i]);
            }
            forces[9].push(
                csys.chord_shortening(&sol.y(k)[..csys.modes()])
                    .iter()
                    .fold(0.0, |m: f64, d| m.max(*d)),
            );
        }
        let mut table = Table::new("platform_deviation", &t);
        for (name, col) in [
            "dx_m",
            "dy_m",
            "dphi_rad",
            "dx_with_stretch_m",
            "dy_with_stretch_m",
            "dphi_with_stretch_rad",
        ]
        .into_iter()
        .zip(deviation)
        {
            table.push(name, col);
        }
        tables.push(table);
        let mut table = Table::new("coupled_forces", &t);
        let mut cols = forces.into_iter();
        for i in 1..=3 {
            for name in ["P_B_{}_N", "P_C_{}_N", "F_a_{}_N"] {
                table.push(
                    name.replace("{}", &i.to_string()),
                    cols.next().unwrap_or_default(),
                );
            }
        }
        table.push("max_chord_shortening_m", cols.next().unwrap_or_default());
        tables.push(table);
        coupled_states = Some(sol);
    }

    if let Some(sol) = solution.as_ref().or(coupled_states.as_ref()) {
        let range = |i: usize| system.link_range(i);
        if wants(OutputKind::Modes) {
            let mut table = Table::new("modes", &t);
            for i in 0..3 {
                for (j, idx) in range(i).enumerate() {
                    table.push(
                        format!("eta_{}_{}_m", i + 1, j + 1),
                        (0..n_out).map(|k| sol.y(k)[idx]).collect(),
                    );
                }
            }
            tables.push(table);
        }
        if wants(OutputKind::Deflections) {
            let mut table = Table::new("deflections", &t);
            for &xi in &scene.file.output.deflection_xi {
                for i in 0..3 {
                    let link = &machine.links[i];
                    let r = range(i);
                    table.push(
                        format!("w_{}_xi{xi}_m", i + 1),
                        (0..n_out)
                            .map(|k| link.deflection(&sol.y(k)[r.clone()], xi))
                            .collect(),
                    );
                    if let Some((plain, psys)) = &without_axial {
                        let r = psys.link_range(i);
                        table.push(
                            format!("w_{}_xi{xi}_no_axial_m", i + 1),
                            (0..n_out)
                                .map(|k| link.deflection(&plain.y(k)[r.clone()], xi))
                                .collect(),
                        );
                    }
                }
            }
            tables.push(table);
        }
        if wants(OutputKind::ModalForces) {
            let mut table = Table::new("modal_forces", &t);
            let mut cols: Vec<Vec<f64>> = columns(3 * (modes[0] + modes[1] + modes[2]), n_out);
            for &tk in &t {
                let state = machine
                    .geometry
                    .inverse_kinematics_unchecked(&scene.trajectory.motion(tk))
                    .map_err(|source| {
                        run_err(flexprr_dynamics::DynamicsError::Kinematics { t: tk, source })
                    })?;
                let mut c = 0;
                for (i, &r) in modes.iter().enumerate() {
                    let leg = &state.legs[i];
                    let u = machine.geometry.legs[i].guide.direction.into_inner();
                    let ints = &machine.links[i].integrals;
                    for j in 0..r {
                        cols[c].push(-leg.rho_ddot * u.dot(&leg.n) * ints.mass_psi[j]);
                        cols[c + 1].push(-ints.length * leg.beta_ddot * ints.mass_xi_psi[j]);
                        cols[c + 2]
                            .push(leg.rho_dot * leg.beta_dot * u.dot(&leg.e) * ints.mass_psi[j]);
                        c += 3;
                    }
                }
            }
            let mut cols = cols.into_iter();
            for i in 1..=3 {
                for j in 1..=modes[i - 1] {
                    table.push(format!("F_rho_{i}_{j}_N"), cols.next().unwrap_or_default());
                    table.push(format!("F_beta_{i}_{j}_N"), cols.next().unwrap_or_default());
                    table.push(format!("F_fg_{i}_{j}_N"), cols.next().unwrap_or_default());
                }
            }
            tables.push(table);
        }
        if wants(OutputKind::Energies) {
            let mut table = Table::new("energies", &t);
            let n = system.modes();
            let mut rigid = Vec::with_capacity(n_out);
            for &tk in &t {
                let state = machine
                    .geometry
                    .inverse_kinematics_unchecked(&scene.trajectory.motion(tk))
                    .map_err(|source| {
                        run_err(flexprr_dynamics::DynamicsError::Kinematics { t: tk, source })
                    })?;
                rigid.push(rigid_kinetic_energy(&machine, &state));
            }
            table.push("rigid_kinetic_J", rigid);
            for i in 0..3 {
                let ints = &machine.links[i].integrals;
                let r = range(i);
                let quad = |m: &faer::Mat<f64>, v: &[f64]| -> f64 {
                    let mut s = 0.0;
                    for a in 0..v.len() {
                        for b in 0..v.len() {
                            s += v[a] * m[(a, b)] * v[b];
                        }
                    }
                    0.5 * s
                };
                table.push(
                    format!("strain_{}_J", i + 1),
                    (0..n_out)
                        .map(|k| quad(&ints.stiffness, &sol.y(k)[r.clone()]))
                        .collect(),
                );
                table.push(
                    format!("elastic_kinetic_{}_J", i + 1),
                    (0..n_out)
                        .map(|k| {
                            let y = sol.y(k);
                            let v: Vec<f64> = r.clone().map(|idx| y[n + idx]).collect();
                            quad(&ints.mass, &v)
                        })
                        .collect(),
                );
            }
            tables.push(table);
        }
    }
    stats.rhs_evaluations += system.counters().rhs_evaluations;
    stats.inverse_dynamics_solves += system.counters().inverse_dynamics_solves;
    stats.wall_time_s = clock.elapsed().as_secs_f64();
    Ok(RunResult {
        tables,
        frequencies,
        stats,
    })
}

/// `count` empty columns, each with room for `rows` values.
fn columns(count: usize, rows: usize) -> Vec<Vec<f64>> {
    (0..count).map(|_| Vec::with_capacity(rows)).collect()
}

fn dynamics_hz(omega_squared: f64) -> f64 {
    omega_squared.max(0.0).sqrt() / std::f64::consts::TAU
}
