//! What a run writes, as plug-ins: each output is an [`OutputProducer`] that names itself,
//! states what it needs (the shared samples, the integrated model, a variant run), the files
//! and figures it writes, the scalar quantities it offers to studies, and makes its tables,
//! documents and reports. The run asks every producer of an [`OutputRegistry`] that the scene
//! wants ([`crate::run_registered`]); the built-in outputs are producers registered the same
//! way ([`OutputRegistry::built_in`]), and [`crate::RUN_PRODUCTS`] is their list of files.
//!
//! A program adds its own output with [`OutputRegistry::register`], which also declares its
//! name in the scene's [`Registry`] so that a scene requests it in `output.custom`:
//!
//! ```
//! use std::sync::Arc;
//! use flexprr_run::{OutputContext, OutputProducer, OutputRegistry, RunError, RunResult, Table};
//! use flexprr_run::producer::{Needs, StudyQuantity};
//!
//! /// The platform's distance from the origin (`reach.csv`).
//! #[derive(Debug)]
//! struct Reach;
//!
//! impl OutputProducer for Reach {
//!     fn name(&self) -> &'static str {
//!         "reach"
//!     }
//!     fn needs(&self) -> Needs {
//!         Needs { samples: true, ..Needs::default() }
//!     }
//!     fn files(&self) -> &'static [&'static str] {
//!         &["reach.csv"]
//!     }
//!     fn quantities(&self) -> &'static [StudyQuantity] {
//!         &[StudyQuantity { name: "reach_max_m", unit: "m", label: "largest reach" }]
//!     }
//!     fn produce(&self, ctx: &mut OutputContext<'_>, result: &mut RunResult) -> Result<(), RunError> {
//!         let r = ctx.motions().iter().map(|m| m.pose.x.hypot(m.pose.y)).collect();
//!         let mut table = Table::new("reach", ctx.times());
//!         table.push(flexprr_run::Column::of(flexprr_run::Quantity::Named(
//!             flexprr_dynamics::NamedQuantity::new("reach", "m", "r", "m"),
//!         )), r);
//!         result.tables.push(table);
//!         Ok(())
//!     }
//!     fn quantity(&self, result: &RunResult, name: &str) -> Option<Result<f64, String>> {
//!         let r = result.table("reach")?.column("reach_m")?;
//!         (name == "reach_max_m").then(|| Ok(r.iter().copied().fold(0.0, f64::max)))
//!     }
//! }
//!
//! let mut scenes = flexprr_scene::Registry::default();
//! let mut outputs = OutputRegistry::built_in();
//! outputs.register(&mut scenes, Arc::new(Reach));
//! assert!(outputs.products().is_product("reach.csv"));
//! assert_eq!(scenes.output_names(), ["reach"]);
//! ```

use std::borrow::Cow;
use std::sync::Arc;

use flexprr_dynamics::{JointReactions, MachineSnapshot, ModalSystem, SceneModel};
use flexprr_integrators::Solution;
use flexprr_kinematics::{MachineState, PlatformMotion};
use flexprr_outdir::{Legacy, Products};
use flexprr_scene::{Registry, Scene};

use crate::error::RunError;
use crate::plot::Figure;
use crate::run::Integrated;
use crate::samples::Samples;
use crate::table::RunResult;
use crate::variant::VariantRun;

/// What a producer needs from the run before it is asked.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Needs {
    /// The shared samples: the commanded motion and its inverse kinematics at the output
    /// times ([`OutputContext::motions`], [`OutputContext::states`], the rigid reactions).
    pub samples: bool,
    /// The integrated model and its solution: the producer is skipped when the run did not
    /// integrate (a run whose requested outputs need no integration).
    pub integration: bool,
    /// The variant runs (by [`crate::SceneVariant::name`]) it reads when the scene makes them.
    pub variants: &'static [&'static str],
}

/// A scalar a producer offers to studies, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StudyQuantity {
    /// The name a study asks for, which is also its column in `results.csv`.
    pub name: &'static str,
    /// SI unit (empty for ratios and flags).
    pub unit: &'static str,
    /// Words for an axis label.
    pub label: &'static str,
}

/// One output of a run (see the module documentation).
pub trait OutputProducer: Send + Sync + std::fmt::Debug {
    /// Its name: the request in a scene (`output.requests` for the built-in ones,
    /// `output.custom` for a program's own).
    fn name(&self) -> &'static str;

    /// Whether a run of `scene` makes it: by default, when the scene requests it.
    fn wanted(&self, scene: &Scene) -> bool {
        scene.requests(self.name())
    }

    /// What it needs from the run (nothing by default).
    fn needs(&self) -> Needs {
        Needs::default()
    }

    /// The files it may write (tables as `<name>.csv`, figures, documents).
    fn files(&self) -> &'static [&'static str] {
        &[]
    }

    /// `(prefix, suffix)` patterns of the files it may write, e.g. `("deflections_xi", ".svg")`.
    fn file_patterns(&self) -> &'static [(&'static str, &'static str)] {
        &[]
    }

    /// The scalar quantities it offers to studies.
    fn quantities(&self) -> &'static [StudyQuantity] {
        &[]
    }

    /// Makes its tables, documents and reports into `result`.
    ///
    /// # Errors
    /// Why it could not: the run fails with it, keeping what was made.
    fn produce(&self, ctx: &mut OutputContext<'_>, result: &mut RunResult) -> Result<(), RunError>;

    /// Its figures `(file, figure)` from what `result` holds (written unless the scene turns
    /// plots off; a figure without data is left out). None by default.
    fn figures(&self, _scene: &Scene, _result: &RunResult) -> Vec<(String, Figure)> {
        Vec::new()
    }

    /// The quantity called `name` of a run that made this output: `None` when it offers no
    /// such quantity, an error when the run cannot give it.
    fn quantity(&self, _result: &RunResult, _name: &str) -> Option<Result<f64, String>> {
        None
    }
}

/// A shared producer: a result keeps the producers that made it.
pub type SharedProducer = Arc<dyn OutputProducer>;

/// The producers a run asks, in order: the built-in ones, then those registered.
#[derive(Debug, Clone)]
pub struct OutputRegistry {
    producers: Vec<SharedProducer>,
}

impl Default for OutputRegistry {
    fn default() -> Self {
        Self::built_in()
    }
}

impl OutputRegistry {
    /// The built-in outputs (`docs/scenes.md`, "Outputs and their CSV columns").
    pub fn built_in() -> Self {
        Self {
            producers: crate::built_in::producers(),
        }
    }

    /// Adds `producer` after the others and declares its name in the scene registry
    /// `scenes` (so that a scene loaded with it may request it in `output.custom`).
    pub fn register(&mut self, scenes: &mut Registry, producer: SharedProducer) {
        scenes.register_output(producer.name(), producer.needs().integration);
        self.producers.retain(|p| p.name() != producer.name());
        self.producers.push(producer);
    }

    /// The producers, in the order a run asks them.
    pub fn producers(&self) -> &[SharedProducer] {
        &self.producers
    }

    /// The producer called `name`.
    pub fn get(&self, name: &str) -> Option<&SharedProducer> {
        self.producers.iter().find(|p| p.name() == name)
    }

    /// Every quantity the producers offer to studies, with the producer's name.
    pub fn quantities(&self) -> Vec<(&'static str, StudyQuantity)> {
        self.producers
            .iter()
            .flat_map(|p| p.quantities().iter().map(|q| (p.name(), *q)))
            .collect()
    }

    /// The files a run with these producers may write: `summary.json` and every producer's
    /// files and patterns (what [`flexprr_outdir`] refuses to write over in a directory
    /// flexprr did not write, and recognises an earlier run's directory by).
    pub fn products(&self) -> Products {
        let mut products = Products {
            kind: "run",
            names: Cow::Owned(vec!["summary.json"]),
            patterns: Cow::Owned(Vec::new()),
            legacy: Some(Legacy::JsonKey {
                file: "summary.json",
                key: "flexprr_version",
            }),
        };
        for p in &self.producers {
            add_files(&mut products, p.as_ref());
        }
        products
    }
}

/// Adds the files and patterns of `producer` to `products` (once each).
pub(crate) fn add_files(products: &mut Products, producer: &dyn OutputProducer) {
    for name in producer.files() {
        if !products.names.contains(name) {
            products.names.to_mut().push(name);
        }
    }
    for pattern in producer.file_patterns() {
        if !products.patterns.contains(pattern) {
            products.patterns.to_mut().push(*pattern);
        }
    }
}

/// What a producer reads: the scene, the output times reached, the shared samples, the
/// integrated model with its solution, snapshots and variant runs, and the progress.
pub struct OutputContext<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) times: &'a [f64],
    pub(crate) samples: Option<Samples>,
    pub(crate) ked: &'a mut ModalSystem,
    pub(crate) integrated: Option<&'a mut Integrated>,
    pub(crate) progress: &'a mut dyn FnMut(f64),
}

impl OutputContext<'_> {
    /// The scene.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// The output times reached (all of them, or up to a failure).
    pub fn times(&self) -> &[f64] {
        self.times
    }

    /// The commanded platform motion at the output times (empty unless the producer
    /// [`Needs::samples`]).
    pub fn motions(&self) -> &[PlatformMotion] {
        self.samples.as_ref().map_or(&[], |s| &s.motions)
    }

    /// The inverse kinematics at the output times (empty unless [`Needs::samples`]).
    pub fn states(&self) -> &[MachineState] {
        self.samples.as_ref().map_or(&[], |s| &s.states)
    }

    /// The rigid joint reactions at the output times (computed once; empty unless
    /// [`Needs::samples`]).
    ///
    /// # Errors
    /// A singular pose, with its time.
    pub fn reactions(&mut self) -> Result<&[JointReactions], RunError> {
        match self.samples.as_mut() {
            Some(s) => Ok(s.with_reactions(&self.scene.machine)?),
            None => Ok(&[]),
        }
    }

    /// The integrated model, when the run integrated.
    pub fn model(&self) -> Option<&dyn SceneModel> {
        self.integrated.as_ref().map(|i| i.model.as_ref())
    }

    /// The integrated solution, when the run integrated.
    pub fn solution(&self) -> Option<&Solution> {
        self.integrated.as_ref().map(|i| &i.solution)
    }

    /// The model's snapshots at the solution's times (computed once), when the run
    /// integrated.
    ///
    /// # Errors
    /// The model could not give a snapshot.
    pub fn snapshots(&mut self) -> Result<Option<&[MachineSnapshot]>, RunError> {
        match self.integrated.as_deref_mut() {
            Some(i) => Ok(Some(i.snapshots()?)),
            None => Ok(None),
        }
    }

    /// The variant run called `name`, when the scene made it.
    pub fn variant(&self, name: &str) -> Option<&VariantRun> {
        let i = self.integrated.as_deref()?;
        i.variants.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    /// Reports the producer's progress (fraction of its work).
    pub fn progress(&mut self, fraction: f64) {
        (self.progress)(fraction);
    }
}
