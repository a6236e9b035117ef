//! The speed search (`[search]` in a study file, `docs/studies.md`): bisection over one
//! numeric scene key (typically `trajectory.frequency`) for the smallest value at which the
//! mechanism collapses within a given number of revolutions or a given time.
//!
//! The search assumes a threshold: values below it do not collapse within the window, values
//! at or above it do. It first runs both ends of the bracket (`low` must not collapse, `high`
//! must), then halves the bracket until it is at most `tolerance` wide (bisection: the
//! bracket after `n` halvings is `(high - low) / 2^n`, Burden & Faires, *Numerical
//! Analysis*, section 2.1). The answer is the bracket: the largest value seen not to
//! collapse and the smallest seen to collapse. A probe that fails for another reason (a
//! diverged KED run, an integrator failure) ends the search with that failure: the threshold
//! is then not known, and the search says so instead of guessing.

use std::path::{Path, PathBuf};

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
}

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
}

/// One run of the search.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Probe {
    /// The key's value.
    pub value: f64,
    /// The end of its window (s).
    pub end_s: f64,
    /// Whether it collapsed within the window.
    pub collapses: bool,
    /// When (s), which link (1-based) and how far (m), if it collapsed.
    pub time_s: Option<f64>,
    /// Link (1-based).
    pub link: Option<usize>,
    /// Mid-point deflection at the collapse (m).
    pub deflection_m: Option<f64>,
    /// The failure message of a probe that neither finished nor collapsed.
    pub error: Option<String>,
}

/// What a search found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SearchOutcome {
    /// `"bracketed"` (the threshold lies in `(below, at_or_above]`), `"low-collapses"`
    /// (already at `low`), `"high-does-not-collapse"`, or `"failed"` (a probe failed for
    /// another reason; see its `error`).
    pub status: &'static str,
    /// Largest value seen not to collapse.
    pub below: Option<f64>,
    /// Smallest value seen to collapse: the collapse speed to within the tolerance.
    pub at_or_above: Option<f64>,
    /// The probes in the order they ran.
    pub probes: Vec<Probe>,
    /// `search.json`.
    pub file: PathBuf,
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
                    "expected finite low < high, got low = {} and high = {}",
                    c.low, c.high
                ),
            ));
        }
        if !(finite(c.tolerance) && c.tolerance > 0.0) {
            return Err((
                "search.tolerance",
                format!("expected a positive bracket width, got {}", c.tolerance),
            ));
        }
        if (c.high - c.low) / c.tolerance > 2f64.powi(30) {
            return Err((
                "search.tolerance",
                format!(
                    "{} is below 2^-30 of the bracket: the search would not end in a useful time",
                    c.tolerance
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
                        format!("expected a positive number, got {n}"),
                    ));
                }
                if c.low <= 0.0 {
                    return Err((
                        "search.low",
                        format!("a frequency must be positive, got {}", c.low),
                    ));
                }
                Window::Revolutions(n)
            }
            (None, Some(t)) => {
                if !(finite(t) && t > 0.0) {
                    return Err((
                        "search.time",
                        format!("expected a positive time (s), got {t}"),
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
        Ok(Self {
            key: c.key.clone(),
            low: c.low,
            high: c.high,
            tolerance: c.tolerance,
            window,
        })
    }

    /// The end of the window for `value` (s).
    pub fn end(&self, value: f64) -> f64 {
        match self.window {
            Window::Revolutions(n) => n / value,
            Window::Time(t) => t,
        }
    }
}

/// One probe: the base scene with the key set to `value`, `time.end` set to the window, run;
/// a collapse or a finished run, or the failure.
fn probe(study: &Study, search: &Search, value: f64) -> Probe {
    let end = search.end(value);
    let mut out = Probe {
        value,
        end_s: end,
        collapses: false,
        time_s: None,
        link: None,
        deflection_m: None,
        error: None,
    };
    let mut scene = study.base.clone();
    let set = set_key(&mut scene, &search.key, &toml::Value::Float(value))
        .and_then(|()| set_key(&mut scene, "time.end", &toml::Value::Float(end)));
    if let Err(e) = set {
        out.error = Some(e);
        return out;
    }
    let text = match toml::to_string(&scene) {
        Ok(t) => t,
        Err(e) => {
            out.error = Some(e.to_string());
            return out;
        }
    };
    let name = format!("{}_search", study.name);
    let file = format!("{} search {} = {value}", study.name, search.key);
    let scene = match flexprr_scene::Scene::from_text(&file, &name, &text) {
        Ok(s) => s,
        Err(e) => {
            out.error = Some(e.to_string());
            return out;
        }
    };
    match flexprr_run::run(&scene, &mut |_| {}) {
        Ok(_) => {}
        Err(failure) => match failure.error.collapse() {
            Some(c) => {
                out.collapses = true;
                out.time_s = Some(c.t);
                out.link = Some(c.link + 1);
                out.deflection_m = Some(c.deflection);
            }
            None => out.error = Some(failure.error.to_string()),
        },
    }
    out
}

/// Runs the search of `study` and writes `search.json` (the outcome and every probe) and
/// `results.csv` (one row per probe) into `out`; `on_probe` sees each probe as it ends.
///
/// # Errors
/// [`StudyError::Io`] when the files cannot be written.
pub fn run_search(
    study: &Study,
    search: &Search,
    out: &Path,
    on_probe: &dyn Fn(&Probe),
) -> Result<SearchOutcome, StudyError> {
    std::fs::create_dir_all(out).map_err(|source| StudyError::Io {
        path: out.display().to_string(),
        source,
    })?;
    let mut probes = Vec::new();
    let run = |value: f64, probes: &mut Vec<Probe>| {
        let p = probe(study, search, value);
        on_probe(&p);
        probes.push(p.clone());
        p
    };
    let (mut low, mut high) = (search.low, search.high);
    let status = 'search: {
        for (value, must_collapse) in [(high, true), (low, false)] {
            let p = run(value, &mut probes);
            if p.error.is_some() {
                break 'search "failed";
            }
            if p.collapses != must_collapse {
                break 'search if must_collapse {
                    "high-does-not-collapse"
                } else {
                    "low-collapses"
                };
            }
        }
        while high - low > search.tolerance {
            let mid = 0.5 * (low + high);
            let p = run(mid, &mut probes);
            if p.error.is_some() {
                break 'search "failed";
            }
            if p.collapses {
                high = mid;
            } else {
                low = mid;
            }
        }
        "bracketed"
    };
    let below = probes
        .iter()
        .filter(|p| p.error.is_none() && !p.collapses)
        .map(|p| p.value)
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))));
    let at_or_above = probes
        .iter()
        .filter(|p| p.collapses)
        .map(|p| p.value)
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.min(v))));
    let file = out.join("search.json");
    let outcome = SearchOutcome {
        status,
        below,
        at_or_above,
        probes,
        file: file.clone(),
    };
    let json = serde_json::json!({
        "study": study.name,
        "key": search.key,
        "low": search.low,
        "high": search.high,
        "tolerance": search.tolerance,
        "window": match search.window {
            Window::Revolutions(n) => serde_json::json!({ "revolutions": n }),
            Window::Time(t) => serde_json::json!({ "time_s": t }),
        },
        "status": outcome.status,
        "below": outcome.below,
        "at_or_above": outcome.at_or_above,
        "probes": outcome.probes,
    });
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| StudyError::Io { path, source }
    };
    let bytes = serde_json::to_vec_pretty(&json).unwrap_or_default();
    std::fs::write(&file, bytes).map_err(io(&file))?;
    let mut csv = format!(
        "probe,{},end_s,collapses,collapse_time_s,collapse_link,collapse_deflection_m,error\n",
        search.key
    );
    let num = |v: Option<f64>| v.map(crate::record::format_value).unwrap_or_default();
    for (k, p) in outcome.probes.iter().enumerate() {
        csv.push_str(&format!(
            "{k},{},{},{},{},{},{},\"{}\"\n",
            crate::record::format_value(p.value),
            crate::record::format_value(p.end_s),
            if p.collapses { "yes" } else { "no" },
            num(p.time_s),
            p.link.map(|l| l.to_string()).unwrap_or_default(),
            num(p.deflection_m),
            p.error.as_deref().unwrap_or("").replace('"', "'"),
        ));
    }
    let results = out.join("results.csv");
    std::fs::write(&results, csv).map_err(io(&results))?;
    Ok(outcome)
}
