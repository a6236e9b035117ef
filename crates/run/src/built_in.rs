//! The built-in outputs as [`OutputProducer`]s, in the order a run asks them: the outputs of
//! the commanded rigid motion, the KED frequencies, the control outputs, then the outputs of
//! the integrated model (its own tables first, the linearisations along the motion last).

use std::sync::Arc;

use flexprr_scene::{OutputKind, Scene};

use crate::column::Quantity as Q;
use crate::error::RunError;
use crate::outputs;
use crate::plot::Figure;
use crate::plot::run_figures as fig;
use crate::producer::{Needs, OutputContext, OutputProducer, SharedProducer};
use crate::table::RunResult;
use crate::variant::{SceneVariant, Uncontrolled, WithoutAxialForce};
use crate::viewer;

type Produce = fn(&mut OutputContext<'_>, &mut RunResult) -> Result<(), RunError>;
use crate::plot::run_figures::Figures;

/// A built-in output: its name, when a scene wants it, what it needs, its files, and the
/// functions that make its tables and figures.
#[derive(Debug)]
struct BuiltIn {
    name: &'static str,
    wanted: fn(&Scene) -> bool,
    needs: Needs,
    files: &'static [&'static str],
    patterns: &'static [(&'static str, &'static str)],
    produce: Produce,
    figures: Figures,
}

impl OutputProducer for BuiltIn {
    fn name(&self) -> &'static str {
        self.name
    }
    fn wanted(&self, scene: &Scene) -> bool {
        (self.wanted)(scene)
    }
    fn needs(&self) -> Needs {
        self.needs
    }
    fn files(&self) -> &'static [&'static str] {
        self.files
    }
    fn file_patterns(&self) -> &'static [(&'static str, &'static str)] {
        self.patterns
    }
    fn produce(&self, ctx: &mut OutputContext<'_>, result: &mut RunResult) -> Result<(), RunError> {
        (self.produce)(ctx, result)
    }
    fn figures(&self, scene: &Scene, result: &RunResult) -> Vec<(String, Figure)> {
        (self.figures)(scene, result)
    }
}

const RIGID: Needs = Needs {
    samples: true,
    integration: false,
    variants: &[],
};
const INTEGRATED: Needs = Needs {
    samples: false,
    integration: true,
    variants: &[],
};
const BOTH: Needs = Needs {
    samples: true,
    integration: true,
    variants: &[],
};

/// An output the scene requests by its [`OutputKind`] name.
macro_rules! requested {
    ($kind:ident) => {
        |scene: &Scene| scene.outputs.contains(&OutputKind::$kind)
    };
}

/// The built-in producers, in the order a run asks them.
pub(crate) fn producers() -> Vec<SharedProducer> {
    [rigid_producers(), model_producers(), combined_producers()]
        .into_iter()
        .flatten()
        .map(|b| Arc::new(b) as SharedProducer)
        .collect()
}

/// The outputs of the rigid motion alone (inverse kinematics and dynamics at the
/// output times) and of the scene's KED modes along it: kinematics, driving and axial forces,
/// joint reactions, the machine drawing, the frequencies.
fn rigid_producers() -> Vec<BuiltIn> {
    vec![
        BuiltIn {
            name: "kinematics",
            wanted: requested!(Kinematics),
            needs: RIGID,
            files: &["kinematics.csv", "kinematics.svg"],
            patterns: &[],
            produce: |c, r| table(r, outputs::kinematics(samples(c)?)),
            figures: fig::KINEMATICS,
        },
        BuiltIn {
            name: "driving_forces",
            wanted: requested!(DrivingForces),
            needs: RIGID,
            files: &["driving_forces.csv", "driving_forces.svg"],
            patterns: &[],
            produce: driving_forces,
            figures: fig::DRIVING_FORCES,
        },
        BuiltIn {
            name: "joint_reactions",
            wanted: requested!(JointReactions),
            needs: RIGID,
            files: &["joint_reactions.csv"],
            patterns: &[],
            produce: |c, r| {
                let s = c.samples.as_mut().ok_or_else(no_samples)?;
                table(r, outputs::joint_reactions(c.scene, s)?)
            },
            figures: fig::NONE,
        },
        BuiltIn {
            name: "axial_forces",
            wanted: requested!(AxialForces),
            needs: RIGID,
            files: &["axial_forces.csv", "axial_forces.svg"],
            patterns: &[],
            produce: |c, r| {
                let s = c.samples.as_mut().ok_or_else(no_samples)?;
                table(r, outputs::axial_forces(c.scene, s)?)
            },
            figures: fig::AXIAL_FORCES,
        },
        BuiltIn {
            name: "machine",
            wanted: requested!(Machine),
            needs: RIGID,
            files: &["machine.svg"],
            patterns: &[],
            produce: |c, r| {
                r.documents
                    .push(viewer::machine_file(c.scene, samples(c)?)?);
                Ok(())
            },
            figures: fig::NONE,
        },
        BuiltIn {
            name: "frequencies",
            wanted: requested!(Frequencies),
            needs: Needs::default(),
            files: &["frequencies.csv", "table1.md", "table1.csv"],
            patterns: &[("axial_force_frequency_mode", ".svg")],
            produce: |c, r| {
                let (table, hist) = outputs::frequencies(c.ked, c.times)?;
                r.tables.push(table);
                r.frequencies = Some(hist);
                Ok(())
            },
            figures: fig::FREQUENCIES,
        },
    ]
}

/// The outputs of the integrated model: the control outputs (from the shared samples
/// when the scene has a control law), the model's own tables, the modes, the deflections
/// (with the variant runs) and the patches.
fn model_producers() -> Vec<BuiltIn> {
    vec![
        BuiltIn {
            name: "control",
            wanted: |scene| {
                crate::control::needs_samples(scene)
                    || RIGID_REQUESTS.iter().any(|k| scene.outputs.contains(k))
            },
            needs: RIGID,
            files: &[
                "tracking.csv",
                "tracking.svg",
                "actuators.csv",
                "actuators.svg",
            ],
            patterns: &[],
            produce: control,
            figures: fig::CONTROL,
        },
        BuiltIn {
            name: "model_tables",
            wanted: |_| true,
            needs: INTEGRATED,
            files: &[
                "platform_deviation.csv",
                "platform_deviation.svg",
                "coupled_forces.csv",
                "nonlinear_forces.csv",
            ],
            patterns: &[],
            produce: |c, r| {
                let i = integrated(c)?;
                r.tables.extend(i.model.tables(&i.solution)?);
                Ok(())
            },
            figures: fig::PLATFORM_DEVIATION,
        },
        BuiltIn {
            name: "modes",
            wanted: requested!(Modes),
            needs: INTEGRATED,
            files: &["modes.csv", "modes.svg"],
            patterns: &[],
            produce: |c, r| {
                let i = integrated(c)?;
                table(r, outputs::modes(i.model.as_ref(), &i.solution))
            },
            figures: fig::MODES,
        },
        BuiltIn {
            name: "deflections",
            wanted: requested!(Deflections),
            needs: Needs {
                variants: &["without_axial_force", "uncontrolled"],
                ..INTEGRATED
            },
            files: &["deflections.csv"],
            patterns: &[("deflections_xi", ".svg")],
            produce: deflections,
            figures: fig::DEFLECTIONS,
        },
        BuiltIn {
            name: "piezo",
            wanted: |scene| !scene.patches.is_empty(),
            needs: Needs {
                variants: &["uncontrolled"],
                ..INTEGRATED
            },
            files: &["piezo.csv", "piezo.svg"],
            patterns: &[],
            produce: piezo,
            figures: fig::PIEZO,
        },
    ]
}

/// The outputs that read both the rigid motion and the integrated model: modal forces,
/// energies, the viewer and snapshots, the whole machine's frequencies along the motion.
fn combined_producers() -> Vec<BuiltIn> {
    vec![
        BuiltIn {
            name: "modal_forces",
            wanted: requested!(ModalForces),
            needs: BOTH,
            files: &["modal_forces.csv", "modal_forces.svg"],
            patterns: &[],
            produce: |c, r| table(r, outputs::modal_forces(c.scene, samples(c)?)),
            figures: fig::MODAL_FORCES,
        },
        BuiltIn {
            name: "energies",
            wanted: requested!(Energies),
            needs: BOTH,
            files: &["energies.csv", "energies.svg"],
            patterns: &[],
            produce: |c, r| {
                let s = c.samples.as_ref().ok_or_else(no_samples)?;
                let i = c.integrated.as_deref_mut().ok_or_else(not_integrated)?;
                table(r, outputs::energies(i.model.as_mut(), s, &i.solution)?)
            },
            figures: fig::ENERGIES,
        },
        BuiltIn {
            name: "viewer",
            wanted: |scene| {
                scene.outputs.contains(&OutputKind::Viewer)
                    || scene.outputs.contains(&OutputKind::Snapshots)
            },
            needs: BOTH,
            files: &["viewer.html", "snapshots.svg"],
            patterns: &[],
            produce: viewer_output,
            figures: fig::NONE,
        },
        BuiltIn {
            name: "machine_frequencies",
            wanted: requested!(MachineFrequencies),
            needs: INTEGRATED,
            files: &["machine_frequencies.csv", "machine_frequencies.svg"],
            patterns: &[],
            produce: machine_frequencies,
            figures: fig::MACHINE_FREQUENCIES,
        },
    ]
}

/// The requests that make a run compute the shared samples (and so its control report).
const RIGID_REQUESTS: [OutputKind; 9] = [
    OutputKind::Kinematics,
    OutputKind::DrivingForces,
    OutputKind::JointReactions,
    OutputKind::AxialForces,
    OutputKind::ModalForces,
    OutputKind::Energies,
    OutputKind::Viewer,
    OutputKind::Snapshots,
    OutputKind::Machine,
];

/// Adds `table` to `r`.
fn table(r: &mut RunResult, table: crate::table::Table) -> Result<(), RunError> {
    r.tables.push(table);
    Ok(())
}

fn no_samples() -> RunError {
    RunError::Output {
        output: "samples".into(),
        reason: "the shared samples were not computed".into(),
    }
}

fn not_integrated() -> RunError {
    RunError::Output {
        output: "model".into(),
        reason: "the model was not integrated".into(),
    }
}

fn samples<'a>(c: &'a OutputContext<'_>) -> Result<&'a crate::samples::Samples, RunError> {
    c.samples.as_ref().ok_or_else(no_samples)
}

fn integrated<'a>(
    c: &'a mut OutputContext<'_>,
) -> Result<&'a mut crate::run::Integrated, RunError> {
    c.integrated.as_deref_mut().ok_or_else(not_integrated)
}

fn driving_forces(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let s = c.samples.as_mut().ok_or_else(no_samples)?;
    let model_forces = match c.integrated.as_deref_mut() {
        Some(i) => Some(i.snapshots()?),
        None => None,
    };
    let (table, solves) = outputs::driving_forces(c.scene, s, model_forces)?;
    r.stats.inverse_dynamics_solves += solves;
    r.tables.push(table);
    Ok(())
}

fn control(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let s = c.samples.as_mut().ok_or_else(no_samples)?;
    let snapshots = match c.integrated.as_deref_mut() {
        Some(i) if crate::control::needs_snapshots(c.scene) => Some(i.snapshots()?),
        _ => None,
    };
    Ok(crate::control::produce(c.scene, s, snapshots, r)?)
}

fn piezo(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let scene = c.scene;
    let i = integrated(c)?;
    let free = i.variants.iter().find(|(n, _)| *n == Uncontrolled.name());
    let free = free.map(|(_, v)| v);
    Ok(crate::piezo::produce(
        scene,
        i.model.as_mut(),
        &i.solution,
        free,
        r,
    )?)
}

fn deflections(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let scene = c.scene;
    let i = integrated(c)?;
    let solved = |name: &str| {
        i.variants
            .iter()
            .find(|(n, _)| *n == name)
            .and_then(|(_, v)| v.solved())
    };
    let variants = [
        (
            Q::DeflectionWithoutAxialForce,
            solved(WithoutAxialForce.name()),
        ),
        (
            crate::piezo::DEFLECTION_UNCONTROLLED,
            solved(Uncontrolled.name()),
        ),
    ];
    r.tables.push(outputs::deflections(
        scene,
        i.model.as_ref(),
        &i.solution,
        &variants,
    )?);
    Ok(())
}

fn viewer_output(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let (scene, s) = (c.scene, c.samples.as_ref().ok_or_else(no_samples)?);
    let i = c.integrated.as_deref_mut().ok_or_else(not_integrated)?;
    let snapshots = i.snapshots()?.to_vec();
    let data = viewer::viewer_data(
        scene,
        s,
        i.model.as_ref(),
        &i.solution,
        &snapshots,
        c.ked,
        r.frequencies.as_ref(),
    )?;
    r.documents.extend(viewer::viewer_files(scene, &data)?);
    r.viewer = Some(data);
    Ok(())
}

fn machine_frequencies(c: &mut OutputContext<'_>, r: &mut RunResult) -> Result<(), RunError> {
    let i = c.integrated.as_deref_mut().ok_or_else(not_integrated)?;
    // Last: the linearisations evaluate the model away from its solution.
    let out = crate::machine_frequencies::machine_frequencies(
        i.model.as_mut(),
        &i.solution,
        c.ked,
        c.progress,
    );
    r.tables.extend(out.table);
    if let Some(note) = out.note {
        r.add_report(note);
    }
    match out.failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
