//! The deflection limit (`[plan] deflection_limit`): the planned motion slowed uniformly until
//! the scene's flexible model keeps every link's deflection within the limit at every time of
//! its run (the move and its settling window).
//!
//! The rigid limits are met by the time-optimal plan; the links' deflection is not a function
//! of the path state but of the whole motion's history, so it is met outside the planner: the
//! plan is slowed by a factor `k` ([`flexprr_planning::Planner::stretched`]: path speeds
//! `/k`, path accelerations `/k^2`, the shaper kept) and the flexible model is run again. The
//! quasi-static part of the deflection goes with the acceleration, so a first guess is
//! `k = sqrt(peak / limit)`; the factor is bracketed between a probe that breaks the limit and
//! one that meets it, and the bracket is halved (in `log k`) to [`STRETCH_TOLERANCE`]. The
//! deflection is not monotone in `k` in general (a residual vibration can grow where a slower
//! move excites a mode harder), so the answer is the smallest factor found that meets the
//! limit with a breaking one within the tolerance below it, and every probe is reported.

use flexprr_planning::{Plan, Planner};
use flexprr_run::RunResult;

use crate::error::PlanError;
use crate::pipeline::{PlanOutcome, build_scene};
use crate::vibration::{run, vibration_of, with_deflections};

/// Relative width of the final bracket on the slow-down factor.
pub const STRETCH_TOLERANCE: f64 = 0.01;

/// The largest slow-down factor tried before the limit is declared out of reach.
pub const MAX_STRETCH: f64 = 64.0;

/// One run of the flexible model on the plan slowed by `stretch`.
#[derive(Debug, Clone, PartialEq)]
pub struct Probe {
    /// The factor on every time of the time-optimal plan.
    pub stretch: f64,
    /// The move's duration or the period (s).
    pub duration: f64,
    /// Largest `|w|` of any link over the run (m), or why the run or the slowed plan failed.
    pub peak: Result<f64, String>,
}

impl Probe {
    /// Whether the probe meets `limit`.
    fn meets(&self, limit: f64) -> bool {
        matches!(self.peak, Ok(w) if w <= limit)
    }
}

/// What the deflection limit did to the plan.
#[derive(Debug, Clone)]
pub struct DeflectionSearch {
    /// The limit (m).
    pub limit: f64,
    /// The factor applied (1: the time-optimal plan already meets the limit).
    pub stretch: f64,
    /// The peak deflection of the plan as delivered (m).
    pub peak: f64,
    /// The time-optimal (and shaped) plan before slowing.
    pub fastest: Plan,
    /// Every run of the search, in the order made.
    pub probes: Vec<Probe>,
}

impl DeflectionSearch {
    /// Whether the limit slowed the plan.
    pub fn binds(&self) -> bool {
        self.stretch > 1.0
    }
}

/// Largest `|w|` of any link over a run: the sampled deflections and the largest deflection
/// over the integrator's accepted steps (between the samples), whichever is larger.
pub fn peak_deflection(result: &RunResult) -> f64 {
    let sampled = vibration_of(result, None, 0.0)
        .deflection
        .iter()
        .fold(0.0f64, |a, w| a.max(*w));
    result
        .stats
        .max_deflection_m
        .map_or(sampled, |between| sampled.max(between))
}

/// The pieces of the pipeline the search re-times: the planner of the planned path (its
/// dense check) and the planned scene of a plan.
pub(crate) struct Retiming<'a> {
    /// The planner on the planned (oriented) path.
    pub planner: &'a Planner<'a>,
    /// Re-times the outcome to a plan: its data, planned scene and span.
    pub apply: &'a dyn Fn(&mut PlanOutcome, Plan) -> Result<(), PlanError>,
}

/// Slows `outcome`'s plan until the scene's flexible model meets `limit` (module
/// documentation). `peak` is the flexible check's peak on the time-optimal plan.
///
/// # Errors
/// [`PlanError::DeflectionLimit`] when no factor up to [`MAX_STRETCH`] meets the limit (with
/// the probes); a planned scene the builder refuses.
pub(crate) fn meet_limit(
    outcome: &mut PlanOutcome,
    limit: f64,
    peak: f64,
    retiming: &Retiming<'_>,
    progress: &mut dyn FnMut(&str),
) -> Result<DeflectionSearch, PlanError> {
    let fastest = outcome.plan.clone();
    let mut probes = vec![Probe {
        stretch: 1.0,
        duration: fastest.duration,
        peak: Ok(peak),
    }];
    if peak <= limit {
        return Ok(DeflectionSearch {
            limit,
            stretch: 1.0,
            peak,
            fastest,
            probes,
        });
    }
    let probe = |k: f64, progress: &mut dyn FnMut(&str)| -> Result<Probe, PlanError> {
        progress(&format!(
            "deflection limit: the motion slowed {k:.4} times on the flexible model"
        ));
        let plan = match retiming.planner.stretched(&fastest, k) {
            Ok(plan) => plan,
            Err(e) => {
                return Ok(Probe {
                    stretch: k,
                    duration: f64::NAN,
                    peak: Err(e.to_string()),
                });
            }
        };
        let duration = plan.duration;
        let mut trial = outcome.clone();
        (retiming.apply)(&mut trial, plan)?;
        let built = build_scene(
            &outcome.scene,
            &with_deflections(&trial.planned_file, false),
        )?;
        let peak = run(&built, "the slowed motion")
            .map(|r| peak_deflection(&r))
            .map_err(|e| e.to_string());
        Ok(Probe {
            stretch: k,
            duration,
            peak,
        })
    };
    // Bracket: `lo` breaks the limit, `hi` meets it.
    let mut lo = 1.0;
    let mut last = peak;
    let hi = loop {
        let guess = (lo * (last / limit).sqrt() * 1.02).max(lo * 1.2);
        let k = guess.min(MAX_STRETCH);
        let p = probe(k, progress)?;
        let meets = p.meets(limit);
        last = match &p.peak {
            Ok(w) => *w,
            Err(_) => 4.0 * last,
        };
        probes.push(p);
        if meets {
            break k;
        }
        if k >= MAX_STRETCH {
            return Err(PlanError::DeflectionLimit {
                scene: outcome.scene.clone(),
                limit,
                detail: format!(
                    "even {MAX_STRETCH} times slower than the time-optimal motion the links deflect {}: probes {}",
                    probes.last().map_or(String::new(), |p| peak_text(&p.peak)),
                    probe_list(&probes)
                ),
            });
        }
        lo = k;
    };
    let mut hi = hi;
    while hi / lo - 1.0 > STRETCH_TOLERANCE {
        let mid = (lo * hi).sqrt();
        let p = probe(mid, progress)?;
        if p.meets(limit) {
            hi = mid;
        } else {
            lo = mid;
        }
        probes.push(p);
    }
    let mut plan =
        retiming
            .planner
            .stretched(&fastest, hi)
            .map_err(|source| PlanError::Planning {
                scene: outcome.scene.clone(),
                stage: "the motion slowed for the deflection limit",
                source: Box::new(source),
            })?;
    for stretch in &mut plan.binding {
        stretch.constraint = "deflection_limit".into();
    }
    (retiming.apply)(outcome, plan)?;
    // The probe at `hi` met the limit, so its peak is a number.
    let peak = probes
        .iter()
        .rev()
        .find(|p| p.stretch.to_bits() == hi.to_bits())
        .and_then(|p| p.peak.clone().ok())
        .unwrap_or(limit);
    Ok(DeflectionSearch {
        limit,
        stretch: hi,
        peak,
        fastest,
        probes,
    })
}

fn peak_text(peak: &Result<f64, String>) -> String {
    match peak {
        Ok(w) => format!("{w:.4e} m"),
        Err(why) => format!("(failed: {why})"),
    }
}

fn probe_list(probes: &[Probe]) -> String {
    probes
        .iter()
        .map(|p| format!("{:.3}x: {}", p.stretch, peak_text(&p.peak)))
        .collect::<Vec<_>>()
        .join(", ")
}
