//! One producer per output kind, each from the shared [`Samples`] and, where it needs
//! them, the integrated states.

use flexprr_dynamics::{
    AxialForceModel, AxialInput, CoupledSystem, DynamicsError, FrequencyHistory,
    JointReactionAxialForce, ModalSystem, SceneModel, end_forces, inverse_dynamics,
    rigid_kinetic_energy,
};
use flexprr_integrators::Solution;
use flexprr_scene::Scene;

use crate::column::{Column, Quantity as Q};
use crate::samples::Samples;
use crate::table::Table;

/// `count` empty columns, each with room for `rows` values.
fn columns(count: usize, rows: usize) -> Vec<Vec<f64>> {
    (0..count).map(|_| Vec::with_capacity(rows)).collect()
}

/// Slider and link kinematics (`kinematics.csv`).
pub(crate) fn kinematics(s: &Samples) -> Table {
    let mut table = Table::new("kinematics", &s.t);
    let pose = |f: fn(&flexprr_kinematics::PlatformMotion) -> f64| -> Vec<f64> {
        s.motions.iter().map(f).collect()
    };
    table.push(Column::of(Q::PlatformX), pose(|m| m.pose.x));
    table.push(Column::of(Q::PlatformY), pose(|m| m.pose.y));
    table.push(Column::of(Q::PlatformPhi), pose(|m| m.pose.phi));
    type LegValue = fn(&flexprr_kinematics::LegState) -> f64;
    let per_leg: [(Q, LegValue); 6] = [
        (Q::SliderPosition, |l| l.rho),
        (Q::SliderVelocity, |l| l.rho_dot),
        (Q::SliderAcceleration, |l| l.rho_ddot),
        (Q::LinkAngle, |l| l.beta),
        (Q::LinkAngularVelocity, |l| l.beta_dot),
        (Q::LinkAngularAcceleration, |l| l.beta_ddot),
    ];
    for i in 0..3 {
        for (q, value) in per_leg {
            let column = s.states.iter().map(|st| value(&st.legs[i])).collect();
            table.push(Column::link(q, i), column);
        }
    }
    table
}

/// Rigid driving forces, and with the links' elastic inertia when a KED solution is given
/// (`driving_forces.csv`, the paper's figures 10-11).
pub(crate) fn driving_forces(
    scene: &Scene,
    s: &mut Samples,
    flexible: Option<(&mut ModalSystem, &Solution)>,
) -> Result<(Table, usize), DynamicsError> {
    let machine = scene.machine.clone();
    let reactions = s.with_reactions(&machine)?.to_vec();
    let mut table = Table::new("driving_forces", &s.t);
    for i in 0..3 {
        let rigid = reactions.iter().map(|r| r.driving_force[i]).collect();
        table.push(Column::link(Q::DrivingForceRigid, i), rigid);
    }
    let mut solves = reactions.len();
    if let Some((system, solution)) = flexible {
        let mut flex = columns(3, s.len());
        for k in 0..s.len() {
            let acc = system.modal_accelerations(s.t[k], solution.y(k))?;
            let elastic = system.elastic_inertia(&acc);
            let f = inverse_dynamics(&machine, &s.states[k], Some(&elastic), s.t[k])?;
            solves += 1;
            for (column, force) in flex.iter_mut().zip(f.driving_force) {
                column.push(force);
            }
        }
        for (i, column) in flex.into_iter().enumerate() {
            let diff = column
                .iter()
                .zip(&reactions)
                .map(|(f, r)| f - r.driving_force[i])
                .collect();
            table.push(Column::link(Q::DrivingForceFlexible, i), column);
            table.push(Column::link(Q::DrivingForceDifference, i), diff);
        }
    }
    Ok((table, solves))
}

/// One component of the joint reactions of link `i`.
type ReactionPart = fn(&flexprr_dynamics::JointReactions, usize) -> f64;

/// Rigid joint reactions at B and C (`joint_reactions.csv`).
pub(crate) fn joint_reactions(scene: &Scene, s: &mut Samples) -> Result<Table, DynamicsError> {
    let mut table = Table::new("joint_reactions", &s.t);
    let reactions = s.with_reactions(&scene.machine)?;
    let parts: [(Q, ReactionPart); 4] = [
        (Q::ReactionBx, |r, i| r.slider_on_link[i].x),
        (Q::ReactionBy, |r, i| r.slider_on_link[i].y),
        (Q::ReactionCx, |r, i| r.platform_on_link[i].x),
        (Q::ReactionCy, |r, i| r.platform_on_link[i].y),
    ];
    let mut out = Vec::new();
    for i in 0..3 {
        for (q, value) in parts {
            out.push((
                Column::link(q, i),
                reactions.iter().map(|r| value(r, i)).collect(),
            ));
        }
    }
    for (column, values) in out {
        table.push(column, values);
    }
    Ok(table)
}

/// Axial force at both ends of each link (`axial_forces.csv`): the scene's axial model, or
/// the joint-reaction form when the scene switched the axial force off.
pub(crate) fn axial_forces(scene: &Scene, s: &mut Samples) -> Result<Table, DynamicsError> {
    let machine = scene.machine.clone();
    let reactions = s.with_reactions(&machine)?.to_vec();
    let fallback = JointReactionAxialForce;
    let model: &dyn AxialForceModel = if scene.axial_model.name() == "none" {
        &fallback
    } else {
        scene.axial_model.as_ref()
    };
    let mut table = Table::new("axial_forces", &s.t);
    for i in 0..3 {
        let (mut pb, mut pc) = (Vec::with_capacity(s.len()), Vec::with_capacity(s.len()));
        for (state, rigid) in s.states.iter().zip(&reactions) {
            let load = model.load(&AxialInput {
                leg: &state.legs[i],
                guide_direction: machine.geometry.legs[i].guide.direction.into_inner(),
                link: &machine.links[i],
                reactions: Some(rigid),
                index: i,
            });
            let (b, c) = end_forces(&load, machine.links[i].length());
            pb.push(b);
            pc.push(c);
        }
        table.push(Column::link(Q::AxialForceB, i), pb);
        table.push(Column::link(Q::AxialForceC, i), pc);
    }
    Ok(table)
}

/// Frequencies of every link and mode along the motion, with the end forces
/// (`frequencies.csv`).
pub(crate) fn frequencies(
    system: &mut ModalSystem,
    t: &[f64],
) -> Result<(Table, FrequencyHistory), DynamicsError> {
    let hist = FrequencyHistory::sample(system, t)?;
    let mut table = Table::new("frequencies", t);
    for i in 0..3 {
        for (j, omega_squared) in hist.omega_squared[i].iter().enumerate() {
            let hz = omega_squared
                .iter()
                .map(|w| w.max(0.0).sqrt() / std::f64::consts::TAU)
                .collect();
            table.push(Column::mode(Q::Frequency, i, j), hz);
        }
    }
    for i in 0..3 {
        let ends = &hist.end_forces[i];
        table.push(
            Column::link(Q::AxialForceB, i),
            ends.iter().map(|p| p.0).collect(),
        );
        table.push(
            Column::link(Q::AxialForceC, i),
            ends.iter().map(|p| p.1).collect(),
        );
    }
    Ok((table, hist))
}

/// Modal coordinates (`modes.csv`).
pub(crate) fn modes(model: &dyn SceneModel, solution: &Solution) -> Table {
    let mut table = Table::new("modes", &solution.t);
    for i in 0..3 {
        for (j, idx) in model.link_range(i).enumerate() {
            let values = (0..solution.len()).map(|k| solution.y(k)[idx]).collect();
            table.push(Column::mode(Q::ModalCoordinate, i, j), values);
        }
    }
    table
}

/// Deflections at the requested `xi`, and without axial force when that run was made
/// (`deflections.csv`, the paper's figures 6-8).
pub(crate) fn deflections(
    scene: &Scene,
    model: &dyn SceneModel,
    solution: &Solution,
    without_axial: Option<(&dyn SceneModel, &Solution)>,
) -> Table {
    let mut table = Table::new("deflections", &solution.t);
    let n = solution.len();
    for &xi in &scene.file.output.deflection_xi {
        for i in 0..3 {
            let w = (0..n)
                .map(|k| model.deflection(i, xi, solution.y(k)))
                .collect();
            table.push(Column::at(Q::Deflection, i, xi), w);
            if let Some((plain, states)) = without_axial {
                let w = (0..n.min(states.len()))
                    .map(|k| plain.deflection(i, xi, states.y(k)))
                    .collect();
                table.push(Column::at(Q::DeflectionWithoutAxialForce, i, xi), w);
            }
        }
    }
    table
}

/// The inertial and coupling modal forces (`modal_forces.csv`, the paper's figure 9).
pub(crate) fn modal_forces(scene: &Scene, s: &Samples) -> Table {
    let machine = &scene.machine;
    let mut table = Table::new("modal_forces", &s.t);
    for i in 0..3 {
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        let ints = &machine.links[i].integrals;
        for j in 0..machine.links[i].modes() {
            let (mut rho, mut beta, mut fg) = (Vec::new(), Vec::new(), Vec::new());
            for state in &s.states {
                let leg = &state.legs[i];
                rho.push(-leg.rho_ddot * u.dot(&leg.n) * ints.mass_psi[j]);
                beta.push(-ints.length * leg.beta_ddot * ints.mass_xi_psi[j]);
                fg.push(leg.rho_dot * leg.beta_dot * u.dot(&leg.e) * ints.mass_psi[j]);
            }
            table.push(Column::mode(Q::ModalForceRho, i, j), rho);
            table.push(Column::mode(Q::ModalForceBeta, i, j), beta);
            table.push(Column::mode(Q::ModalForceFg, i, j), fg);
        }
    }
    table
}

/// `v^T m v / 2` for a modal matrix `m`.
fn half_quadratic_form(m: &faer::Mat<f64>, v: &[f64]) -> f64 {
    let mut s = 0.0;
    for (a, va) in v.iter().enumerate() {
        for (b, vb) in v.iter().enumerate() {
            s += va * m[(a, b)] * vb;
        }
    }
    0.5 * s
}

/// Rigid kinetic energy and each link's strain and elastic kinetic energy
/// (`energies.csv`).
pub(crate) fn energies(
    scene: &Scene,
    model: &dyn SceneModel,
    s: &Samples,
    solution: &Solution,
) -> Table {
    let machine = &scene.machine;
    let n_out = solution.len();
    let mut table = Table::new("energies", &solution.t);
    let rigid = s.states[..n_out]
        .iter()
        .map(|st| rigid_kinetic_energy(machine, st))
        .collect();
    table.push(Column::of(Q::RigidKineticEnergy), rigid);
    let n = model.modes();
    for i in 0..3 {
        let ints = &machine.links[i].integrals;
        let r = model.link_range(i);
        let strain = (0..n_out)
            .map(|k| half_quadratic_form(&ints.stiffness, &solution.y(k)[r.clone()]))
            .collect();
        let kinetic = (0..n_out)
            .map(|k| {
                let y = solution.y(k);
                half_quadratic_form(&ints.mass, &y[n + r.start..n + r.end])
            })
            .collect();
        table.push(Column::link(Q::StrainEnergy, i), strain);
        table.push(Column::link(Q::ElasticKineticEnergy, i), kinetic);
    }
    table
}

/// The coupled model's platform deviation and forces (`platform_deviation.csv`,
/// `coupled_forces.csv`).
pub(crate) fn coupled(
    system: &mut CoupledSystem,
    solution: &Solution,
) -> Result<[Table; 2], DynamicsError> {
    let n_out = solution.len();
    let mut deviation = columns(6, n_out);
    let mut forces = columns(10, n_out);
    for k in 0..n_out {
        let (tk, y) = (solution.t[k], solution.y(k));
        let out = system.output(tk, y)?;
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
        let shortening = system.chord_shortening(&y[..system.modes()]);
        forces[9].push(shortening.iter().fold(0.0, |m: f64, d| m.max(*d)));
    }
    let mut pose = Table::new("platform_deviation", &solution.t);
    let names = [
        Q::DeviationX,
        Q::DeviationY,
        Q::DeviationPhi,
        Q::DeviationXWithStretch,
        Q::DeviationYWithStretch,
        Q::DeviationPhiWithStretch,
    ];
    for (q, column) in names.into_iter().zip(deviation) {
        pose.push(Column::of(q), column);
    }
    let mut table = Table::new("coupled_forces", &solution.t);
    let mut cols = forces.into_iter();
    for i in 0..3 {
        for q in [Q::AxialForceB, Q::AxialForceC, Q::CoupledDrivingForce] {
            table.push(Column::link(q, i), cols.next().unwrap_or_default());
        }
    }
    table.push(
        Column::of(Q::MaxChordShortening),
        cols.next().unwrap_or_default(),
    );
    Ok([pose, table])
}
