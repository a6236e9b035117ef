//! The outputs of the geometrically nonlinear model ([`NonlinearSystem`]): its coordinates
//! are node positions and angles, not modal amplitudes, so deflections, platform motion,
//! forces and energies come from the model's own output at each sample time, not from the
//! modal tables of the other models.

use flexprr_dynamics::{DynamicsError, NonlinearSystem};
use flexprr_integrators::Solution;
use flexprr_scene::{OutputKind, Scene};

use crate::column::{Column, Quantity as Q};
use crate::table::Table;

/// What the nonlinear model adds to a run: its tables and the largest mid-point deflection
/// over the samples (m).
pub(crate) struct NonlinearTables {
    /// `platform_deviation`, `nonlinear_forces`, and `deflections` and `energies` when
    /// requested.
    pub tables: Vec<Table>,
    /// Largest `|w(1/2)|` over links and samples (m).
    pub max_midpoint_deflection: f64,
}

/// The nonlinear model's tables at the solution's sample times:
///
/// * `platform_deviation.csv`: platform pose minus its nominal pose (`dx`, `dy`, `dphi`);
/// * `nonlinear_forces.csv`: axial forces at both ends and the driving force of each link,
///   and the chords' type-II measure;
/// * `deflections.csv` (requested): `w` at each `output.deflection_xi` from the chord;
/// * `energies.csv` (requested): kinetic energy of the links and platform, strain energy of
///   the links.
///
/// # Errors
/// A kinematic failure at a sample time (the samples are states the integration accepted,
/// so this means a trajectory leaving the workspace).
pub(crate) fn tables(
    scene: &Scene,
    system: &mut NonlinearSystem,
    solution: &Solution,
) -> Result<NonlinearTables, DynamicsError> {
    let n_out = solution.len();
    let xis = &scene.file.output.deflection_xi;
    let want_deflections = scene.outputs.contains(&OutputKind::Deflections);
    let want_energies = scene.outputs.contains(&OutputKind::Energies);
    let mut deviation: [Vec<f64>; 3] = Default::default();
    let mut forces: Vec<Vec<f64>> = (0..10).map(|_| Vec::with_capacity(n_out)).collect();
    let mut deflections: Vec<Vec<f64>> = (0..3 * xis.len())
        .map(|_| Vec::with_capacity(n_out))
        .collect();
    let (mut kinetic, mut strain) = (Vec::new(), Vec::new());
    let mut max_mid = 0.0_f64;
    for k in 0..n_out {
        let (t, y) = (solution.t[k], solution.y(k));
        let out = system.output(t, y)?;
        for (q, d) in out.pose_deviation().into_iter().enumerate() {
            deviation[q].push(d);
        }
        for i in 0..3 {
            forces[3 * i].push(out.axial_force_b[i]);
            forces[3 * i + 1].push(out.axial_force_c[i]);
            forces[3 * i + 2].push(out.driving_force[i]);
            max_mid = max_mid.max(out.midpoint_deflection[i].abs());
        }
        forces[9].push(out.type_ii_measure);
        if want_deflections {
            for (p, &xi) in xis.iter().enumerate() {
                for i in 0..3 {
                    deflections[3 * p + i].push(system.deflection_at(t, i, xi, y)?);
                }
            }
        }
        if want_energies {
            kinetic.push(out.kinetic_energy);
            strain.push(out.strain_energy);
        }
    }
    let mut pose = Table::new("platform_deviation", &solution.t);
    let [dx, dy, dphi] = deviation;
    pose.push(Column::of(Q::DeviationX), dx);
    pose.push(Column::of(Q::DeviationY), dy);
    pose.push(Column::of(Q::DeviationPhi), dphi);
    let mut force_table = Table::new("nonlinear_forces", &solution.t);
    let mut cols = forces.into_iter();
    for i in 0..3 {
        for q in [Q::AxialForceB, Q::AxialForceC, Q::CoupledDrivingForce] {
            force_table.push(Column::link(q, i), cols.next().unwrap_or_default());
        }
    }
    force_table.push(
        Column::of(Q::TypeIIMeasure),
        cols.next().unwrap_or_default(),
    );
    let mut tables = vec![pose, force_table];
    if want_deflections {
        let mut table = Table::new("deflections", &solution.t);
        let mut cols = deflections.into_iter();
        for &xi in xis {
            for i in 0..3 {
                table.push(
                    Column::at(Q::Deflection, i, xi),
                    cols.next().unwrap_or_default(),
                );
            }
        }
        tables.push(table);
    }
    if want_energies {
        let mut table = Table::new("energies", &solution.t);
        table.push(Column::of(Q::KineticEnergy), kinetic);
        table.push(Column::of(Q::StrainEnergy), strain);
        tables.push(table);
    }
    Ok(NonlinearTables {
        tables,
        max_midpoint_deflection: max_mid,
    })
}
