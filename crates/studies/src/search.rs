//! The speed search (`[search]` in a study file, `docs/studies.md`): bisection over one
//! numeric scene key (typically `trajectory.frequency`) for the smallest value at which the
//! machine reaches its speed limit within a given number of revolutions or a given time.
//!
//! The limit is a [`Criterion`]: the collapse of the mechanism (coupled and nonlinear
//! models: a run stopped with the collapse outcome) or the buckling of a link (the KED
//! estimate: a link's lowest bending frequency under the rigid motion's axial forces
//! reaches zero, paper eq. (12) with `omega^2 <= 0`; frequencies only, nothing integrated).
//! With `[[axis]]` tables, one search runs per case of the axes (e.g. one per
//! `model.coupling`), so the KED buckling speed and the collapse speeds of the coupled and
//! nonlinear models come out side by side in one study.
//!
//! The search assumes a threshold: values below it do not reach the limit within the
//! window, values at or above it do. It first runs both ends of the bracket (`low` must not
//! collapse, `high` must), then narrows the bracket until it is at most `tolerance` wide.
//! With `probes_per_round = 1` (the default) this is bisection (the bracket after `n`
//! halvings is `(high - low) / 2^n`, Burden & Faires, *Numerical Analysis*, section 2.1);
//! with `k`, each round probes `k` interior values at once and keeps one of the `k + 1`
//! parts (k-section: `(high - low) / (k + 1)^n` after `n` rounds), see [`section_search`].
//! The schedule depends on the study only, never on the thread count, so every `--threads`
//! gives the same probes and the same answer. The answer is the bracket: the largest value
//! seen not to collapse below the smallest seen to collapse, checked against every probe
//! ([`Verification`]): where the outcome is not monotone in the key, the search says so
//! and reports the interval that holds every change it saw. A probe that fails for another
//! reason (a diverged KED run, an integrator failure) ends the search with that failure:
//! the threshold is then not known, and the search says so instead of guessing.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::StudyError;
use crate::study::{Study, set_key};

/// `[search]` as written.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SearchConfig {
    /// Dotted scene key searched over (a number), e.g. `trajectory.frequency`.
    pub key: String,
    /// A value that does not collapse within the window.
    pub low: f64,
    /// A value that does.
    pub high: f64,
    /// Stop when the bracket is at most this wide (same unit as the key).
    pub tolerance: f64,
    /// The window in revolutions of the circle: `time.end = revolutions / value`
    /// (only with `key = "trajectory.frequency"`).
    #[serde(default)]
    pub revolutions: Option<f64>,
    /// The window in seconds: `time.end = time`.
    #[serde(default)]
    pub time: Option<f64>,
    /// `"collapse"` or `"buckling"`; by default each case's own limit: buckling for a KED
    /// model, collapse for a coupled or nonlinear one.
    #[serde(default)]
    pub criterion: Option<Criterion>,
    /// Interior probes per round (k-section: each round cuts the bracket into `k + 1`
    /// parts); 1, the default, is bisection. The probes of a round run at once on the
    /// threads there are, so `3` or `7` use more cores on one search; the probes, and so
    /// the answer, are the same for any `--threads`.
    #[serde(default)]
    pub probes_per_round: Option<usize>,
}

/// What counts as reaching the speed limit in a probe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// The run stops with the collapse outcome within the window (coupled and nonlinear
    /// models: a mid-point deflection past `model.collapse_deflection`, or a type-II pose).
    Collapse,
    /// A link's lowest bending frequency under the rigid motion's axial forces reaches zero
    /// within the window (the KED buckling estimate; frequencies only, KED or coupled scenes).
    Buckling,
}

impl Criterion {
    /// The word used in files and messages.
    pub fn name(self) -> &'static str {
        match self {
            Criterion::Collapse => "collapse",
            Criterion::Buckling => "buckling",
        }
    }

    /// The criterion a case gets when the search names none: buckling for a KED model
    /// (it cannot collapse: its platform follows the rigid motion), collapse otherwise.
    pub fn default_for(coupling: &str) -> Self {
        if coupling == "ked" {
            Criterion::Buckling
        } else {
            Criterion::Collapse
        }
    }
}
/// The most interior probes per round a search may ask for.
pub const MAX_PROBES_PER_ROUND: usize = 63;

/// The window of a search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Window {
    /// This many revolutions of the circle (the span depends on the frequency searched).
    Revolutions(f64),
    /// This many seconds.
    Time(f64),
}

/// A checked `[search]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Search {
    /// Dotted scene key.
    pub key: String,
    /// Lower end of the bracket.
    pub low: f64,
    /// Upper end of the bracket.
    pub high: f64,
    /// Bracket width at which the search stops.
    pub tolerance: f64,
    /// Collapse within this window.
    pub window: Window,
    /// The criterion named in the file, if any (else each case's default).
    pub criterion: Option<Criterion>,
    /// Interior probes per round `k` (1: bisection).
    pub probes_per_round: usize,
}

/// One run of the search.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Probe {
    /// The key's value.
    pub value: f64,
    /// The end of its window (s).
    pub end_s: f64,
    /// Whether it reached the limit (collapsed, or buckled) within the window; `None` (JSON
    /// `null`, `failed` in `results.csv`) when the probe failed for another reason, given
    /// in `error`.
    pub reached: Option<bool>,
    /// When (s): the collapse, or the start of the first buckling interval.
    pub time_s: Option<f64>,
    /// Link (1-based) that collapsed or buckled first.
    pub link: Option<usize>,
    /// Mid-point deflection at the collapse (m); none for buckling.
    pub deflection_m: Option<f64>,
    /// The failure message of a probe that neither finished nor collapsed.
    pub error: Option<String>,
}

/// What one search (one case of the axes) found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SearchOutcome {
    /// The case: each axis key with its value as written in the table (empty without axes).
    pub case: CaseLabels,
    /// The criterion this search used.
    pub criterion: Criterion,
    /// `"bracketed"` (the threshold lies in `(below, at_or_above]`), `"low-reaches"`
    /// (already at `low`), `"high-does-not-reach"`, or `"failed"` (a probe failed for
    /// another reason; see its `error`).
    pub status: &'static str,
    /// Largest value seen not to reach the limit.
    pub below: Option<f64>,
    /// Smallest value seen to reach it: the speed limit to within the tolerance.
    pub at_or_above: Option<f64>,
    /// Rounds of interior probes after the two ends (each round probes
    /// [`Search::probes_per_round`] values at once; see [`section_search`]).
    pub rounds: usize,
    /// The probes in the order they ran.
    pub probes: Vec<Probe>,
    /// Every decided probe checked against the answer ([`Verification`]).
    pub verification: Verification,
}

/// The probes of a search checked against its answer: sorted by value, the outcome should
/// change once, from not reaching the limit to reaching it, inside the bracket. Where it
/// changes more than once the outcome is not monotone in the key: the search says so (status
/// `"non-monotone"`), widens its answer to the interval that holds every change seen, and
/// names the probes that show it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Verification {
    /// Whether the decided probes change outcome at most once, upwards.
    pub monotone: bool,
    /// Every change of outcome between neighbouring decided probes: `(below, above,
    /// reached above)`, in value order.
    pub transitions: Vec<Transition>,
    /// The first onset narrowed by the search when the outcome is not monotone: the lowest
    /// change from not reaching to reaching, `(below, at_or_above)`.
    pub first_onset: Option<(f64, f64)>,
    /// The probes on the wrong side of the first onset: reaching below it or not reaching
    /// above it.
    pub contradicting: Vec<f64>,
}

/// A change of outcome between two neighbouring decided probes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Transition {
    /// The lower probe's value.
    pub below: f64,
    /// The upper probe's value.
    pub above: f64,
    /// Whether the upper one reached the limit (`true`: the limit starts here; `false`:
    /// it stops reaching it, a contradiction of a threshold).
    pub reached_above: bool,
}

impl Verification {
    /// The check of `probes`: their transitions in value order and the probes on the wrong
    /// side of `(below, at_or_above]`, the bracket the search narrowed.
    pub fn of(probes: &[Probe], bracket: Option<(f64, f64)>) -> Self {
        let mut decided: Vec<(f64, bool)> = probes
            .iter()
            .filter_map(|p| p.reached.map(|r| (p.value, r)))
            .collect();
        decided.sort_by(|a, b| a.0.total_cmp(&b.0));
        decided.dedup_by(|a, b| a.0.total_cmp(&b.0).is_eq() && a.1 == b.1);
        let transitions: Vec<Transition> = decided
            .windows(2)
            .filter(|w| w[0].1 != w[1].1)
            .map(|w| Transition {
                below: w[0].0,
                above: w[1].0,
                reached_above: w[1].1,
            })
            .collect();
        let monotone = transitions.len() <= 1 && transitions.iter().all(|t| t.reached_above);
        let contradicting = bracket.map_or_else(Vec::new, |(below, above)| {
            decided
                .iter()
                .filter(|(v, r)| (*r && *v <= below) || (!*r && *v >= above))
                .map(|(v, _)| *v)
                .collect()
        });
        Self {
            monotone: monotone && contradicting.is_empty(),
            transitions,
            first_onset: None,
            contradicting,
        }
    }
}

impl SearchOutcome {
    /// The case as `key = value, ...`, or `base scene` without axes.
    pub fn case_label(&self) -> String {
        if self.case.is_empty() {
            "base scene".to_string()
        } else {
            self.case
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    }
}

impl Search {
    /// Checks `[search]`.
    ///
    /// # Errors
    /// A `(key, message)` pair for the first bad value.
    pub fn from_config(c: &SearchConfig) -> Result<Self, (&'static str, String)> {
        let finite = |v: f64| v.is_finite();
        if !(finite(c.low) && finite(c.high) && c.low < c.high) {
            return Err((
                "search.high",
                format!(
                    "expected finite low < high, got low = {:?} and high = {:?}",
                    c.low, c.high
                ),
            ));
        }
        if !(finite(c.tolerance) && c.tolerance > 0.0) {
            return Err((
                "search.tolerance",
                format!("expected a positive bracket width, got {:?}", c.tolerance),
            ));
        }
        if (c.high - c.low) / c.tolerance > 2f64.powi(30) {
            return Err((
                "search.tolerance",
                format!(
                    "{:?} is below 2^-30 of the bracket: the search would not end in a useful time",
                    c.tolerance
                ),
            ));
        }
        let resolution = 64.0 * f64::EPSILON * c.low.abs().max(c.high.abs());
        if c.tolerance <= resolution {
            return Err((
                "search.tolerance",
                format!(
                    "{:?} is below the resolution of the numbers near {:?} ({resolution:.3e}): the bracket could not shrink to it",
                    c.tolerance, c.high
                ),
            ));
        }
        let window = match (c.revolutions, c.time) {
            (Some(n), None) => {
                if c.key != "trajectory.frequency" {
                    return Err((
                        "search.revolutions",
                        format!(
                            "a window in revolutions needs key = \"trajectory.frequency\" (the key is \"{}\"): give search.time instead",
                            c.key
                        ),
                    ));
                }
                if !(finite(n) && n > 0.0) {
                    return Err((
                        "search.revolutions",
                        format!("expected a positive number, got {n:?}"),
                    ));
                }
                if c.low <= 0.0 {
                    return Err((
                        "search.low",
                        format!("a frequency must be positive, got {:?}", c.low),
                    ));
                }
                Window::Revolutions(n)
            }
            (None, Some(t)) => {
                if !(finite(t) && t > 0.0) {
                    return Err((
                        "search.time",
                        format!("expected a positive time (s), got {t:?}"),
                    ));
                }
                Window::Time(t)
            }
            _ => {
                return Err((
                    "search",
                    "give exactly one of search.revolutions and search.time".into(),
                ));
            }
        };
        let probes_per_round = c.probes_per_round.unwrap_or(1);
        if !(1..=MAX_PROBES_PER_ROUND).contains(&probes_per_round) {
            return Err((
                "search.probes_per_round",
                format!(
                    "expected 1 (bisection) to {MAX_PROBES_PER_ROUND} probes per round, got \
                     {probes_per_round}"
                ),
            ));
        }
        Ok(Self {
            key: c.key.clone(),
            low: c.low,
            high: c.high,
            tolerance: c.tolerance,
            window,
            criterion: c.criterion,
            probes_per_round,
        })
    }

    /// The criterion of a case whose scene table is `scene`: the one named in the file, or
    /// the model's own limit. Refuses pairs that cannot work: a KED model never collapses
    /// (its platform follows the rigid motion), and the nonlinear model has no KED
    /// frequencies to buckle.
    ///
    /// # Errors
    /// A message for the `search.criterion` key.
    pub fn criterion_for(&self, scene: &toml::Table) -> Result<Criterion, String> {
        let coupling = scene
            .get("model")
            .and_then(|m| m.get("coupling"))
            .and_then(toml::Value::as_str)
            .unwrap_or("ked");
        let criterion = self
            .criterion
            .unwrap_or_else(|| Criterion::default_for(coupling));
        match (criterion, coupling) {
            (Criterion::Collapse, "ked") => Err(
                "a KED model (model.coupling = \"ked\") cannot collapse: its platform follows the rigid motion; use criterion = \"buckling\" or a coupled model".to_string(),
            ),
            (Criterion::Buckling, "nonlinear") => Err(
                "the buckling criterion needs the KED frequencies, which the nonlinear model does not give; use criterion = \"collapse\" or model.coupling = \"ked\" or \"coupled\"".to_string(),
            ),
            _ => Ok(criterion),
        }
    }

    /// The most probes one search runs when every probe decides: the two ends, then
    /// `k` per round until the bracket is at most the tolerance wide.
    pub fn planned_probes(&self) -> usize {
        let k = self.probes_per_round;
        let rounds = ((self.high - self.low) / self.tolerance).ln() / ((k + 1) as f64).ln();
        2 + k * rounds.ceil().max(0.0) as usize
    }

    /// The end of the window for `value` (s).
    pub fn end(&self, value: f64) -> f64 {
        match self.window {
            Window::Revolutions(n) => n / value,
            Window::Time(t) => t,
        }
    }
}

/// The scene table of a probe: the case's scene with the key set to `value`, `time.end`
/// set to the window, and the outputs the criterion needs, only those: the frequencies for
/// buckling (nothing is integrated), the deflections for a collapse (the model is
/// integrated, whatever the base scene requests); no plots.
///
/// # Errors
/// The message of [`set_key`] when a key cannot be set.
pub(crate) fn probe_table(
    search: &Search,
    scene: &toml::Table,
    criterion: Criterion,
    value: f64,
) -> Result<toml::Table, String> {
    let mut scene = scene.clone();
    let requests = match criterion {
        Criterion::Buckling => "frequencies",
        Criterion::Collapse => "deflections",
    };
    let requests = toml::Value::Array(vec![toml::Value::String(requests.into())]);
    set_key(&mut scene, &search.key, &toml::Value::Float(value))?;
    set_key(
        &mut scene,
        "time.end",
        &toml::Value::Float(search.end(value)),
    )?;
    set_key(&mut scene, "output.requests", &requests)?;
    set_key(&mut scene, "output.plots", &toml::Value::Boolean(false))?;
    set_key(
        &mut scene,
        "output.compare_without_axial_force",
        &toml::Value::Boolean(false),
    )?;
    Ok(scene)
}

/// One probe: the probe scene ([`probe_table`]) run; the limit reached or not, or the
/// failure.
fn probe(
    study: &Study,
    search: &Search,
    scene: &toml::Table,
    criterion: Criterion,
    value: f64,
) -> Probe {
    let end = search.end(value);
    let mut out = Probe {
        value,
        end_s: end,
        reached: None,
        time_s: None,
        link: None,
        deflection_m: None,
        error: None,
    };
    let text = probe_table(search, scene, criterion, value)
        .and_then(|table| toml::to_string(&table).map_err(|e| e.to_string()));
    let text = match text {
        Ok(t) => t,
        Err(e) => {
            out.error = Some(e);
            return out;
        }
    };
    let name = format!("{}_search", study.name);
    let file = format!("{} search {} = {value}", study.name, search.key);
    let scene =
        match flexprr_scene::Scene::from_text_with(&study.plugins.scenes, &file, &name, &text) {
            Ok(s) => s,
            Err(e) => {
                out.error = Some(e.to_string());
                return out;
            }
        };
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        flexprr_run::run_registered(&scene, &study.plugins.outputs, &mut |_| {})
    }));
    let Ok(outcome) = outcome else {
        out.error = Some("the run panicked (a bug: please report it)".into());
        return out;
    };
    match (outcome, criterion) {
        (Ok(result), Criterion::Buckling) => {
            let first = result.frequencies.as_ref().and_then(|h| {
                h.buckling
                    .iter()
                    .filter(|b| b.t_start <= end)
                    .min_by(|a, b| a.t_start.total_cmp(&b.t_start))
            });
            match (first, &result.frequencies) {
                (Some(b), _) => {
                    out.reached = Some(true);
                    out.time_s = Some(b.t_start);
                    out.link = Some(b.link + 1);
                }
                (None, Some(_)) => out.reached = Some(false),
                (None, None) => out.error = Some("the run gave no frequencies".into()),
            }
        }
        (Ok(result), Criterion::Collapse) => {
            if result.stats.integrated {
                out.reached = Some(false);
            } else {
                out.error = Some("the probe was not integrated, so it cannot collapse".into());
            }
        }
        (Err(failure), criterion) => match (failure.error.collapse(), criterion) {
            (Some(c), Criterion::Collapse) => {
                out.reached = Some(true);
                out.time_s = Some(c.t);
                out.link = Some(c.link + 1);
                out.deflection_m = Some(c.deflection);
            }
            _ => out.error = Some(failure.error.to_string()),
        },
    }
    out
}

/// The `k` interior points of `(low, high)` that cut it into `k + 1` equal parts, ascending;
/// points that rounding puts on an end or on each other are left out (a bracket near the
/// resolution of `f64`), so the list may be shorter, even empty.
pub fn section_points(low: f64, high: f64, k: usize) -> Vec<f64> {
    let parts = (k + 1) as f64;
    let mut points: Vec<f64> = Vec::with_capacity(k);
    for i in 1..=k {
        let x = low + (high - low) * (i as f64 / parts);
        if x > low && x < high && points.last().is_none_or(|&last| x > last) {
            points.push(x);
        }
    }
    points
}

/// One search by k-section (the bisection of Burden & Faires, section 2.1, with `k` probes
/// per round: each round cuts the bracket into `k + 1` equal parts and keeps the one where
/// the limit starts, so `n` rounds shrink it by `(k + 1)^n`; `k = 1` is bisection), with
/// `k` = [`Search::probes_per_round`].
///
/// `probe(value)` runs one probe (the probes of a round run in parallel on the current
/// rayon pool: the thread count changes when they run, never which values are probed);
/// `on_probe` sees each probe as it ends, with the outcome as it stood before its round.
///
/// The rules are bisection's, whatever `k`:
/// - the ends first: `high` must reach the limit, then `low` must not (run together when
///   `k >= 2`, read in that order); otherwise the status is `"high-does-not-reach"`,
///   `"low-reaches"` or `"failed"`;
/// - the bracket `(low, high]` keeps `low` not reaching and `high` reaching, and rounds
///   continue while it is wider than `tolerance`;
/// - in a round, the smallest value that reaches the limit becomes `high` and the one below
///   it `low` (or the largest value becomes `low` when none reaches): the search narrows
///   the first onset;
/// - a probe that fails for another reason ends the search as `"failed"` (the threshold is
///   then not known), except the lower end when the upper one already did not reach the
///   limit (bisection would not have run it).
///
/// At the end every decided probe is checked against the answer ([`Verification`]): if the
/// outcome changes more than once along the key (a probe above the bracket that does not
/// reach the limit, or one below it that does), the status is `"non-monotone"` and the
/// answer is the interval that holds every change seen, with the first onset kept in the
/// verification. The rounds take `ceil(log(w0 / tolerance) / log(k + 1))` for a bracket of
/// width `w0`.
pub fn section_search(
    search: &Search,
    case: CaseLabels,
    criterion: Criterion,
    probe: &(dyn Fn(f64) -> Probe + Sync),
    on_probe: &(dyn Fn(&SearchOutcome, &Probe) + Sync),
) -> SearchOutcome {
    let k = search.probes_per_round.max(1);
    let mut outcome = SearchOutcome {
        case,
        criterion,
        status: "failed",
        below: None,
        at_or_above: None,
        rounds: 0,
        probes: Vec::new(),
        verification: Verification::default(),
    };
    let probes = Prober { probe, on_probe };
    let (mut low, mut high) = (search.low, search.high);
    outcome.status = match probes.ends(k, low, high, &mut outcome) {
        Some(status) => status,
        None => probes.narrow(search, k, (&mut low, &mut high), &mut outcome),
    };
    if outcome.status == "bracketed" {
        answer_bracketed(&mut outcome, low, high);
    } else {
        answer_unbracketed(&mut outcome);
    }
    outcome
}

/// The probe of a search and what sees each probe end.
struct Prober<'a> {
    probe: &'a (dyn Fn(f64) -> Probe + Sync),
    on_probe: &'a (dyn Fn(&SearchOutcome, &Probe) + Sync),
}

impl Prober<'_> {
    /// One round: runs `values` at once (in parallel when more than one) and appends the
    /// probes to `outcome` in the order of `values`; whether each reached the limit (`None`:
    /// it failed for another reason).
    fn round(&self, values: &[f64], outcome: &mut SearchOutcome) -> Vec<Option<bool>> {
        use rayon::prelude::*;
        let before: &SearchOutcome = outcome;
        let run = |&v: &f64| {
            let p = (self.probe)(v);
            (self.on_probe)(before, &p);
            p
        };
        let probes: Vec<Probe> = if values.len() == 1 {
            values.iter().map(run).collect()
        } else {
            values.par_iter().map(run).collect()
        };
        let reached = probes.iter().map(|p| p.reached).collect();
        outcome.probes.extend(probes);
        reached
    }

    /// The ends: `high` must reach the limit, then `low` must not (one round when `k >= 2`,
    /// `low` only after `high` reached it otherwise). The final status when they do not
    /// bracket the threshold, `None` when they do.
    fn ends(
        &self,
        k: usize,
        low: f64,
        high: f64,
        outcome: &mut SearchOutcome,
    ) -> Option<&'static str> {
        let ends: Vec<Option<bool>> = if k >= 2 {
            self.round(&[high, low], outcome)
        } else {
            let first = self.round(&[high], outcome);
            if first[0] == Some(true) {
                [first, self.round(&[low], outcome)].concat()
            } else {
                first
            }
        };
        for (reached, must_reach) in ends.into_iter().zip([true, false]) {
            let Some(reached) = reached else {
                return Some("failed");
            };
            if reached != must_reach {
                return Some(if must_reach {
                    "high-does-not-reach"
                } else {
                    "low-reaches"
                });
            }
        }
        None
    }

    /// Rounds of `k` probes inside the bracket `(low, high]` while it is wider than the
    /// tolerance, keeping the first onset: `"bracketed"`, or `"failed"` when a probe fails.
    fn narrow(
        &self,
        search: &Search,
        k: usize,
        (low, high): (&mut f64, &mut f64),
        outcome: &mut SearchOutcome,
    ) -> &'static str {
        while *high - *low > search.tolerance {
            let points = section_points(*low, *high, k);
            if points.is_empty() {
                break;
            }
            let reached = self.round(&points, outcome);
            outcome.rounds += 1;
            if reached.contains(&None) {
                return "failed";
            }
            match reached.iter().position(|r| *r == Some(true)) {
                Some(j) => {
                    *high = points[j];
                    if j > 0 {
                        *low = points[j - 1];
                    }
                }
                None => *low = points[points.len() - 1],
            }
        }
        "bracketed"
    }
}

/// The answer of a bracketed search: `(low, high]`, checked against every decided probe; a
/// non-monotone outcome widens it to the interval that holds every change seen, keeping the
/// first onset in the verification.
fn answer_bracketed(outcome: &mut SearchOutcome, low: f64, high: f64) {
    (outcome.below, outcome.at_or_above) = (Some(low), Some(high));
    let verification = Verification::of(&outcome.probes, Some((low, high)));
    if !verification.monotone {
        // The answer is the interval that holds every change of outcome seen.
        outcome.status = "non-monotone";
        outcome.below = verification
            .transitions
            .iter()
            .map(|t| t.below)
            .reduce(f64::min);
        outcome.at_or_above = verification
            .transitions
            .iter()
            .map(|t| t.above)
            .reduce(f64::max);
        outcome.verification = Verification {
            first_onset: Some((low, high)),
            ..verification
        };
    } else {
        outcome.verification = verification;
    }
}

/// What a search that did not bracket the threshold knows: the largest value that did not
/// reach the limit and the smallest that did.
fn answer_unbracketed(outcome: &mut SearchOutcome) {
    outcome.below = outcome
        .probes
        .iter()
        .filter(|p| p.reached == Some(false))
        .map(|p| p.value)
        .reduce(f64::max);
    outcome.at_or_above = outcome
        .probes
        .iter()
        .filter(|p| p.reached == Some(true))
        .map(|p| p.value)
        .reduce(f64::min);
    outcome.verification = Verification::of(&outcome.probes, None);
}

/// A search's case: each axis key with its value as written in the table.
pub type CaseLabels = Vec<(String, String)>;

/// The cases a search runs: each case of the axes with its labelled values and scene table,
/// or the base scene alone without axes.
///
/// # Errors
/// A message naming the case when an axis value cannot be set.
pub fn search_cases(study: &Study) -> Result<Vec<(CaseLabels, toml::Table)>, String> {
    if study.axes.is_empty() {
        return Ok(vec![(Vec::new(), study.base.clone())]);
    }
    study
        .cases
        .iter()
        .map(|case| {
            let table = study.case_table(case)?;
            let labels = study
                .axes
                .iter()
                .zip(study.case_parameters(case))
                .map(|(axis, value)| (axis.key.clone(), value))
                .collect();
            Ok((labels, table))
        })
        .collect()
}

/// Runs every search of `study` (one per case of its axes, or one on the base scene), the
/// searches and the probes of each round in parallel on `threads` workers
/// ([`section_search`]; the probes do not depend on `threads`). `on_probe` sees each probe
/// as it ends, with its search. Nothing is written: see [`write_search_files`].
///
/// # Errors
/// [`StudyError::Input`] when a case's scene cannot be formed; [`StudyError::Io`] when the
/// workers cannot start.
pub fn run_search(
    study: &Study,
    search: &Search,
    threads: usize,
    on_probe: &(dyn Fn(&SearchOutcome, &Probe) + Sync),
) -> Result<Vec<SearchOutcome>, StudyError> {
    use rayon::prelude::*;
    let input = |key: &str, message: String| StudyError::Input {
        file: study.file.clone(),
        location: None,
        key: key.to_string(),
        message,
    };
    let cases = search_cases(study).map_err(|m| input("axis", m))?;
    let mut jobs = Vec::with_capacity(cases.len());
    for (labels, table) in cases {
        let criterion = search
            .criterion_for(&table)
            .map_err(|m| input("search.criterion", m))?;
        jobs.push((labels, table, criterion));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| StudyError::Io {
            path: study.file.clone(),
            source: std::io::Error::other(format!("cannot start worker threads: {e}")),
        })?;
    // The searches run in parallel, and the probes of each round too; the thread count
    // changes only when probes run, never which ones (each search's schedule is its own).
    Ok(pool.install(|| {
        jobs.into_par_iter()
            .map(|(labels, table, criterion)| {
                section_search(
                    search,
                    labels,
                    criterion,
                    &|value| probe(study, search, &table, criterion, value),
                    on_probe,
                )
            })
            .collect()
    }))
}

/// Writes `search.json`, `search.md` (the speeds side by side) and `results.csv` (one row
/// per probe) of the searches' outcomes into `dir`.
///
/// # Errors
/// [`StudyError::Io`] when a file cannot be written.
pub fn write_search_files(
    study: &Study,
    search: &Search,
    outcomes: &[SearchOutcome],
    dir: &Path,
) -> Result<(), StudyError> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| StudyError::Io { path, source }
    };
    let json = search_json(study, search, outcomes);
    let file = dir.join("search.json");
    let bytes = serde_json::to_vec_pretty(&json).unwrap_or_default();
    std::fs::write(&file, bytes).map_err(io(&file))?;
    let markdown = dir.join("search.md");
    std::fs::write(&markdown, search_markdown(study, search, outcomes)).map_err(io(&markdown))?;
    let results = dir.join("results.csv");
    std::fs::write(&results, search_csv(study, search, outcomes)?).map_err(io(&results))?;
    Ok(())
}

/// `search.json`: the settings and every search with its probes. With a single search its
/// `status`, `below`, `at_or_above` and `probes` are also given at the top level.
fn search_json(study: &Study, search: &Search, outcomes: &[SearchOutcome]) -> serde_json::Value {
    let one = |o: &SearchOutcome| {
        serde_json::json!({
            "case": o.case.iter().map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone()))).collect::<serde_json::Map<_, _>>(),
            "criterion": o.criterion.name(),
            "status": o.status,
            "below": o.below,
            "at_or_above": o.at_or_above,
            "rounds": o.rounds,
            "verification": o.verification,
            "probes": o.probes,
        })
    };
    let mut json = serde_json::json!({
        "study": study.name,
        "key": search.key,
        "low": search.low,
        "high": search.high,
        "tolerance": search.tolerance,
        "probes_per_round": search.probes_per_round,
        "window": match search.window {
            Window::Revolutions(n) => serde_json::json!({ "revolutions": n }),
            Window::Time(t) => serde_json::json!({ "time_s": t }),
        },
        "searches": outcomes.iter().map(one).collect::<Vec<_>>(),
    });
    if let ([single], Some(map)) = (outcomes, json.as_object_mut()) {
        for key in [
            "criterion",
            "status",
            "below",
            "at_or_above",
            "rounds",
            "verification",
            "probes",
        ] {
            map.insert(key.to_string(), one(single)[key].clone());
        }
    }
    json
}

/// `search.md`: one row per search, the speeds side by side.
fn search_markdown(study: &Study, search: &Search, outcomes: &[SearchOutcome]) -> String {
    let num = |v: Option<f64>| v.map_or("-".to_string(), crate::record::format_value);
    let window = match search.window {
        Window::Revolutions(n) => format!("{n} revolutions"),
        Window::Time(t) => format!("{t} s"),
    };
    let mut md = format!(
        "# {}: speed limit in `{}`\n\nSearch over {} to {} (tolerance {}), window {window}: \
         the two ends, then rounds of {} probes at once (bisection with one). The limit is \
         reached at or above the upper end and not at the lower end.\n\n\
         | case | criterion | status | not reached at | reached at | when (s) | link | probes | rounds |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|\n",
        study.name, search.key, search.low, search.high, search.tolerance, search.probes_per_round
    );
    for o in outcomes {
        let first = o.at_or_above.and_then(|v| {
            o.probes
                .iter()
                .find(|p| p.reached == Some(true) && p.value.total_cmp(&v).is_eq())
        });
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            o.case_label(),
            o.criterion.name(),
            o.status,
            num(o.below),
            num(o.at_or_above),
            num(first.and_then(|p| p.time_s)),
            first
                .and_then(|p| p.link)
                .map_or("-".to_string(), |l| l.to_string()),
            o.probes.len(),
            o.rounds
        ));
    }
    let failed: Vec<String> = outcomes
        .iter()
        .filter(|o| o.status == "failed")
        .filter_map(|o| {
            let probe = o.probes.iter().find(|p| p.error.is_some())?;
            Some(format!(
                "- {}: the probe at {} = {} failed: {}\n",
                o.case_label(),
                search.key,
                crate::record::format_value(probe.value),
                probe.error.as_deref().unwrap_or_default()
            ))
        })
        .collect();
    if !failed.is_empty() {
        md.push_str("\nFailed searches (no bracket is claimed):\n\n");
        md.push_str(&failed.concat());
    }
    let contradicted: Vec<String> = outcomes
        .iter()
        .filter(|o| o.status == "non-monotone")
        .map(|o| {
            format!(
                "- {}: {}\n",
                o.case_label(),
                non_monotone_note(&search.key, o)
            )
        })
        .collect();
    if !contradicted.is_empty() {
        md.push_str(
            "\nSearches whose outcome is not monotone in the key (the answer is the interval \
             that holds every change of outcome seen):\n\n",
        );
        md.push_str(&contradicted.concat());
    }
    let ignored: Vec<String> = outcomes
        .iter()
        .filter(|o| o.status != "failed")
        .flat_map(|o| {
            o.probes.iter().filter(|p| p.error.is_some()).map(|p| {
                format!(
                    "- {}: the probe at {} = {} failed: {}\n",
                    o.case_label(),
                    search.key,
                    crate::record::format_value(p.value),
                    p.error.as_deref().unwrap_or_default()
                )
            })
        })
        .collect();
    if !ignored.is_empty() {
        md.push_str(
            "\nProbes that failed without deciding the outcome (the lower end, run together \
             with an upper end that did not reach the limit):\n\n",
        );
        md.push_str(&ignored.concat());
    }
    md
}

/// What a non-monotone search saw, in words: the changes of outcome, the probes that
/// contradict a single threshold, and the interval reported.
pub fn non_monotone_note(key: &str, o: &SearchOutcome) -> String {
    let v = crate::record::format_value;
    let changes = o
        .verification
        .transitions
        .iter()
        .map(|t| {
            format!(
                "{} between {} and {}",
                if t.reached_above {
                    "reached"
                } else {
                    "no longer reached"
                },
                v(t.below),
                v(t.above)
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let against = o
        .verification
        .contradicting
        .iter()
        .map(|x| v(*x))
        .collect::<Vec<_>>()
        .join(", ");
    let onset = o
        .verification
        .first_onset
        .map(|(a, b)| format!("; the first onset is in ({}, {}]", v(a), v(b)))
        .unwrap_or_default();
    format!(
        "the {} is not monotone in {key}: {changes} (probes at {against} contradict a single \
         threshold){onset}; the limit lies somewhere in ({}, {}]",
        o.criterion.name(),
        o.below.map_or("-".to_string(), v),
        o.at_or_above.map_or("-".to_string(), v)
    )
}

/// `results.csv`: one row per probe, with its search's case and criterion (written by the
/// `csv` crate, so case values with commas, such as inline tables, are quoted).
///
/// # Errors
/// [`StudyError::Directory`] if the CSV writer fails.
fn search_csv(
    study: &Study,
    search: &Search,
    outcomes: &[SearchOutcome],
) -> Result<Vec<u8>, StudyError> {
    let err = |e: &dyn std::fmt::Display| StudyError::Directory {
        dir: "results.csv".into(),
        message: e.to_string(),
    };
    let num = |v: Option<f64>| v.map(crate::record::format_value).unwrap_or_default();
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["search".to_string()];
    header.extend(study.axes.iter().map(|a| a.key.clone()));
    header.extend(
        [
            "criterion",
            "probe",
            search.key.as_str(),
            "end_s",
            "reached",
            "time_s",
            "link",
            "collapse_deflection_m",
            "error",
        ]
        .map(String::from),
    );
    w.write_record(&header).map_err(|e| err(&e))?;
    for (s, o) in outcomes.iter().enumerate() {
        for (k, p) in o.probes.iter().enumerate() {
            let mut row = vec![s.to_string()];
            row.extend(o.case.iter().map(|(_, v)| v.clone()));
            row.extend([
                o.criterion.name().to_string(),
                k.to_string(),
                crate::record::format_value(p.value),
                crate::record::format_value(p.end_s),
                match p.reached {
                    Some(true) => "yes",
                    Some(false) => "no",
                    None => "failed",
                }
                .to_string(),
                num(p.time_s),
                p.link.map(|l| l.to_string()).unwrap_or_default(),
                num(p.deflection_m),
                p.error.clone().unwrap_or_default(),
            ]);
            w.write_record(&row).map_err(|e| err(&e))?;
        }
    }
    w.into_inner().map_err(|e| err(&e))
}
