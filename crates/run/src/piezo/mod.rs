//! The piezoelectric patches in a run (docs/piezo.md): the `piezo` table (each patch's
//! sensor, commanded and applied voltages, saturation and actuator power), the comparison
//! with the same scene without its vibration control law (the reduction of the mid-point
//! deflection, the `_uncontrolled` deflection columns), the `vibration_control` section of
//! `summary.json`, the warnings when a patch saturates, and `piezo.svg`.
//!
//! Everything reads the integrated model through [`flexprr_dynamics::PatchReadout::patch_states`] and
//! [`SceneModel::deflection`]; nothing here asks which model ran.

mod report;

use flexprr_dynamics::{DynamicsError, PatchState, SceneModel};
use flexprr_integrators::Solution;
use flexprr_scene::{OutputKind, Scene};

pub use report::{LinkReduction, PatchSummary, PiezoReport};

use crate::column::{Column, Quantity as Q};
use crate::table::{RunResult, Table};
use crate::variant::VariantRun;

pub use flexprr_figures::columns::{
    DEFLECTION_UNCONTROLLED, PATCH_COMMAND_VOLTAGE, PATCH_POWER, PATCH_SATURATED,
    PATCH_SENSOR_VOLTAGE, PATCH_VOLTAGE,
};

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
        return Err(flexprr_dynamics::PatchError::NoPatchStates {
            model: model.kind().to_string(),
            patches: scene.patches.len(),
        }
        .into());
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

pub(crate) use flexprr_figures::columns::index_on_link;

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
