//! The piezoelectric patches in a run (docs/piezo.md): the `piezo` table (each patch's
//! sensor, commanded and applied voltages, saturation and actuator power), the comparison
//! with the same scene without its vibration control law (the reduction of the mid-point
//! deflection, the `_uncontrolled` deflection columns), the `vibration_control` section of
//! `summary.json`, the warnings when a patch saturates, and `piezo.svg`.
//!
//! Everything reads the integrated model through [`flexprr_dynamics::PatchReadout::patch_states`] and
//! [`SceneModel::deflection`]; nothing here asks which model ran.

mod figures;
mod report;

use flexprr_dynamics::{DynamicsError, NamedQuantity, PatchState, SceneModel};
use flexprr_integrators::Solution;
use flexprr_scene::{OutputKind, Scene};

pub(crate) use figures::figures;
pub use report::{LinkReduction, PatchSummary, PiezoReport};

use crate::column::{Column, Quantity as Q};
use crate::table::{RunResult, Table};
use crate::variant::VariantRun;

/// Transverse deflection w at xi of the same scene without its vibration control (m):
/// `w_<i>_xi<xi>_uncontrolled_m`.
pub const DEFLECTION_UNCONTROLLED: Q =
    Q::Named(NamedQuantity::new("w", "m", "w", "m").with_suffix("uncontrolled"));
/// A patch's sensor voltage `V_s` (V); link and the patch's index on it.
pub const PATCH_SENSOR_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_sensor", "V", "V_s", "V"));
/// A patch's voltage command from the vibration control law (V).
pub const PATCH_COMMAND_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_command", "V", "V_c", "V"));
/// A patch's applied voltage: the command clipped at its limit (V).
pub const PATCH_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_applied", "V", "V", "V"));
/// Whether a patch's command was clipped at its limit (1) or not (0).
pub const PATCH_SATURATED: Q = Q::Named(NamedQuantity::new("patch_saturated", "flag", "sat", "1"));
/// Mechanical power a patch's actuator delivers to its link (W; negative when it removes
/// energy).
pub const PATCH_POWER: Q = Q::Named(NamedQuantity::new("P_patch", "W", "P", "W"));

/// Where along the links the reduction is measured: the mid-point.
pub const REDUCTION_XI: f64 = 0.5;

/// The patch outputs of an integrated run into `result`: the `piezo` table when requested,
/// the [`PiezoReport`] (and its warnings) whenever the scene has patches.
///
/// # Errors
/// The model could not give its patches' states or a deflection at an output time.
pub(crate) fn produce(
    scene: &Scene,
    model: &mut dyn SceneModel,
    solution: &Solution,
    uncontrolled: Option<&VariantRun>,
    result: &mut RunResult,
) -> Result<(), DynamicsError> {
    if scene.patches.is_empty() || solution.is_empty() {
        return Ok(());
    }
    let states = (0..solution.len())
        .map(|k| model.patch_states(solution.t[k], solution.y(k)))
        .collect::<Result<Vec<_>, _>>()?;
    if states
        .first()
        .is_none_or(|s| s.len() != scene.patches.len())
    {
        return Err(DynamicsError::Inconsistent(format!(
            "the {} model reports no state for the scene's {} patches",
            model.kind(),
            scene.patches.len()
        )));
    }
    if scene.outputs.contains(&OutputKind::Piezo) {
        result.tables.push(table(scene, &solution.t, &states));
    }
    let mut report = PiezoReport::of(scene, &solution.t, &states);
    match uncontrolled {
        Some(VariantRun::Solved(free, free_solution)) => {
            report.uncontrolled_run = true;
            report.reduction = Some(reductions(model, solution, free.as_ref(), free_solution)?);
        }
        Some(VariantRun::Failed(why)) => {
            report.uncontrolled_run = true;
            report.uncontrolled_failure = Some(why.clone());
        }
        None => {}
    }
    result.add_report(report);
    Ok(())
}

/// Patch `p`'s index among the patches on its link (0-based): the second index of its
/// columns.
pub(crate) fn index_on_link(scene: &Scene, p: usize) -> usize {
    let link = scene.patches[p].link;
    scene.patches[..p].iter().filter(|q| q.link == link).count()
}

/// `piezo.csv`: per patch (link, index on the link) the sensor voltage, the command, the
/// applied voltage, the saturation flag and the actuator power.
fn table(scene: &Scene, t: &[f64], states: &[Vec<PatchState>]) -> Table {
    let mut table = Table::new("piezo", t);
    type Part = fn(&PatchState) -> f64;
    let parts: [(Q, Part); 5] = [
        (PATCH_SENSOR_VOLTAGE, |s| s.sensor),
        (PATCH_COMMAND_VOLTAGE, |s| s.command),
        (PATCH_VOLTAGE, |s| s.voltage),
        (PATCH_SATURATED, |s| f64::from(u8::from(s.saturated))),
        (PATCH_POWER, |s| s.power),
    ];
    for (p, patch) in scene.patches.iter().enumerate() {
        let index = index_on_link(scene, p);
        for (q, value) in parts {
            let column = states.iter().map(|s| value(&s[p])).collect();
            table.push(Column::mode(q, patch.link, index), column);
        }
    }
    table
}

/// The mid-point deflection of every link with and without control, over the output
/// times both runs reached.
fn reductions(
    model: &dyn SceneModel,
    solution: &Solution,
    free: &dyn SceneModel,
    free_solution: &Solution,
) -> Result<Vec<LinkReduction>, DynamicsError> {
    let n = solution.len().min(free_solution.len());
    let series = |m: &dyn SceneModel, s: &Solution, i: usize| {
        (0..n)
            .map(|k| m.deflection(s.t[k], i, REDUCTION_XI, s.y(k)))
            .collect::<Result<Vec<_>, _>>()
    };
    (0..3)
        .map(|i| {
            Ok(LinkReduction::of(
                i,
                &series(model, solution, i)?,
                &series(free, free_solution, i)?,
            ))
        })
        .collect()
}
