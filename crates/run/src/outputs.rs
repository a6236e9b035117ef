//! One producer per output kind, each from the shared [`Samples`] and, where it needs
//! them, the integrated states.

use flexprr_dynamics::{
    AxialForceModel, AxialInput, DynamicsError, FrequencyHistory, JointReactionAxialForce,
    MachineSnapshot, ModalSystem, SceneModel, end_forces, rigid_kinetic_energy,
};
use flexprr_integrators::Solution;
use flexprr_scene::Scene;

use crate::column::{Column, Quantity as Q};
use crate::samples::Samples;
use crate::table::Table;

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

/// Rigid driving forces, and the integrated model's own when its snapshots are given
/// (`driving_forces.csv`; the KED model's are the paper's figures 10-11, with the links'
/// elastic inertia).
pub(crate) fn driving_forces(
    scene: &Scene,
    s: &mut Samples,
    model: Option<&[MachineSnapshot]>,
) -> Result<(Table, usize), DynamicsError> {
    let machine = scene.machine.clone();
    let reactions = s.with_reactions(&machine)?.to_vec();
    let mut table = Table::new("driving_forces", &s.t);
    for i in 0..3 {
        let rigid = reactions.iter().map(|r| r.driving_force[i]).collect();
        table.push(Column::link(Q::DrivingForceRigid, i), rigid);
    }
    if let Some(snapshots) = model {
        let n = snapshots.len().min(reactions.len());
        for i in 0..3 {
            let flexible: Vec<f64> = snapshots[..n].iter().map(|p| p.driving_force[i]).collect();
            let diff = flexible
                .iter()
                .zip(&reactions)
                .map(|(f, r)| f - r.driving_force[i])
                .collect();
            table.push(Column::link(Q::DrivingForceFlexible, i), flexible);
            table.push(Column::link(Q::DrivingForceDifference, i), diff);
        }
    }
    Ok((table, reactions.len()))
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

/// A model and its states over the output times.
pub(crate) type Solved<'a> = (&'a dyn SceneModel, &'a Solution);

/// Deflections at the requested `xi` (`deflections.csv`), and for each variant run that was
/// made, its deflections as the column quantity it is paired with: without axial force
/// (the paper's figures 6-8), without vibration control (docs/piezo.md).
///
/// # Errors
/// A deflection the model cannot compute at an output time (a kinematic failure).
pub(crate) fn deflections(
    scene: &Scene,
    model: &dyn SceneModel,
    solution: &Solution,
    variants: &[(Q, Option<Solved<'_>>)],
) -> Result<Table, DynamicsError> {
    let mut table = Table::new("deflections", &solution.t);
    let deflection = |model: &dyn SceneModel, states: &Solution, i: usize, xi: f64| {
        (0..solution.len().min(states.len()))
            .map(|k| model.deflection(states.t[k], i, xi, states.y(k)))
            .collect::<Result<Vec<_>, _>>()
    };
    for &xi in &scene.file.output.deflection_xi {
        for i in 0..3 {
            table.push(
                Column::at(Q::Deflection, i, xi),
                deflection(model, solution, i, xi)?,
            );
            for (quantity, run) in variants {
                if let Some((other, states)) = run {
                    table.push(
                        Column::at(*quantity, i, xi),
                        deflection(*other, states, i, xi)?,
                    );
                }
            }
        }
    }
    Ok(table)
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

/// The kinetic energy of the commanded rigid motion, and the model's own energies
/// ([`SceneModel::energies`]): the whole machine's kinetic energy where the model has it,
/// each link's strain energy and, for modal models, each link's elastic kinetic energy
/// (`energies.csv`).
///
/// # Errors
/// The model failed to give its energies at an output time.
pub(crate) fn energies(
    model: &mut dyn SceneModel,
    s: &Samples,
    solution: &Solution,
) -> Result<Table, DynamicsError> {
    let n_out = solution.len().min(s.len());
    let mut table = Table::new("energies", &solution.t[..n_out]);
    let machine = model.machine();
    let rigid = s.states[..n_out]
        .iter()
        .map(|st| rigid_kinetic_energy(machine, st))
        .collect();
    table.push(Column::of(Q::RigidKineticEnergy), rigid);
    let energies = (0..n_out)
        .map(|k| model.energies(solution.t[k], solution.y(k)))
        .collect::<Result<Vec<_>, _>>()?;
    if energies.iter().all(|e| e.kinetic.is_some()) {
        let kinetic = energies.iter().map(|e| e.kinetic.unwrap_or(0.0)).collect();
        table.push(Column::of(Q::KineticEnergy), kinetic);
    }
    let elastic = energies.iter().all(|e| e.elastic_kinetic.is_some());
    for i in 0..3 {
        table.push(
            Column::link(Q::StrainEnergy, i),
            energies.iter().map(|e| e.strain[i]).collect(),
        );
        if elastic {
            table.push(
                Column::link(Q::ElasticKineticEnergy, i),
                energies
                    .iter()
                    .map(|e| e.elastic_kinetic.map_or(0.0, |k| k[i]))
                    .collect(),
            );
        }
    }
    Ok(table)
}
