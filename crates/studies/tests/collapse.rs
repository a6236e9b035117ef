//! The study quantity `collapse` and the speed search, checked against direct runs of the
//! same scenes (the run layer's collapse outcome, not the study code) and against the
//! search's own law: the bracket shrinks by k + 1 per round of k probes and ends no wider
//! than the tolerance.

use std::path::{Path, PathBuf};

use flexprr_run::run;
use flexprr_scene::Scene;
use flexprr_studies::search::Criterion;
use flexprr_studies::study::{Study, StudyOptions, read_case_records, run_study};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

/// The coupled paper scene, deflections only, coarse output, over `end` seconds.
const COUPLED: &str = r#"
base = "coupled_f20.toml"
[set.output]
requests = ["deflections"]
plots = false
[set.integrator]
rtol = 1e-7
atol = 1e-11
[set.time]
output_step = 1e-3
"#;

/// A direct run of the coupled scene at `f` Hz over `end` s: the collapse time, if any.
fn direct(f: f64, end: f64) -> Option<f64> {
    let text = std::fs::read_to_string(configs().join("coupled_f20.toml"))
        .unwrap()
        .replace("frequency = 20.0", &format!("frequency = {f:?}"))
        .replace("end = 0.2", &format!("end = {end:?}"))
        .replace("output_step = 1e-4", "output_step = 1e-3")
        .replace("rtol = 1e-8", "rtol = 1e-7")
        .replace("atol = 1e-12", "atol = 1e-11");
    let scene = Scene::from_text("direct.toml", "direct", &text).unwrap();
    match run(&scene, &mut |_| {}) {
        Ok(_) => None,
        Err(failure) => Some(
            failure
                .error
                .collapse()
                .unwrap_or_else(|| panic!("{f} Hz: {}", failure.error))
                .t,
        ),
    }
}

#[test]
fn the_collapse_quantity_reports_what_a_direct_run_does() {
    let text = format!(
        "quantities = [{{ kind = \"collapse\" }}, {{ kind = \"peak_deflection\", link = 1 }}]\n{COUPLED}\n\
         [[axis]]\nkey = \"trajectory.frequency\"\nvalues = [20.0, 30.0]\n"
    )
    .replace("[set.time]\n", "[set.time]\nend = 0.05\n");
    let study = Study::from_text("collapse.toml", "collapse", &text, &configs()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_study(&study, dir.path(), &StudyOptions::default(), &|_, _| {}).unwrap();
    let records = read_case_records(dir.path()).unwrap();
    let columns = study.columns();
    let value = |id: usize, name: &str| {
        let k = columns.iter().position(|c| c == name).unwrap() - 2;
        records[&id].quantities[k].clone()
    };
    // 20 Hz: no collapse (a direct run finishes).
    assert_eq!(direct(20.0, 0.05), None);
    assert_eq!(records[&0].status.name(), "ok");
    assert_eq!(value(0, "collapses"), "no");
    assert_eq!(value(0, "collapse_time_s"), "");
    // 30 Hz: the case is ok, with the direct run's collapse time; its peak deflection (of the
    // run up to the collapse) is just below the 20 mm limit.
    let t = direct(30.0, 0.05).expect("30 Hz collapses");
    assert_eq!(records[&1].status.name(), "ok", "{:?}", records[&1].error);
    assert_eq!(value(1, "collapses"), "yes");
    let recorded: f64 = value(1, "collapse_time_s").parse().unwrap();
    assert!((recorded - t).abs() <= 1e-9 * t, "{recorded} vs {t}");
    assert_eq!(value(1, "collapse_link"), "1");
    let w: f64 = value(1, "collapse_deflection_m").parse().unwrap();
    // The crossing of the 20 mm limit, located on the accepted step's dense output.
    assert!((w.abs() - 0.02).abs() < 1e-6 * 0.02, "{w}");
    let peak: f64 = value(1, "w_peak_1_m").parse().unwrap();
    assert!(peak < 0.02 && peak > 0.015, "{peak}");

    // Without the quantity, a collapse is a failed case of kind "collapse".
    let text = text.replace("{ kind = \"collapse\" }, ", "");
    let study = Study::from_text("collapse.toml", "plain", &text, &configs()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_study(&study, dir.path(), &StudyOptions::default(), &|_, _| {}).unwrap();
    let records = read_case_records(dir.path()).unwrap();
    assert_eq!(records[&0].status.name(), "ok");
    assert_eq!(records[&1].status.name(), "failed");
    let failure = records[&1].failure.as_ref().unwrap();
    assert_eq!(failure.kind.name(), "collapse");
    assert!((failure.time.unwrap() - t).abs() <= 1e-9 * t);
}

#[test]
fn the_speed_search_brackets_the_threshold_found_by_direct_runs() {
    // Collapse within 40 ms: fast at 30 Hz (29.8 ms), never at 20 Hz.
    let (low, high, tolerance, window) = (20.0, 32.0, 0.2, 0.04);
    let text = format!(
        "{COUPLED}\n[search]\nkey = \"trajectory.frequency\"\nlow = {low:?}\nhigh = {high:?}\n\
         tolerance = {tolerance}\ntime = {window}\n"
    );
    let study = Study::from_text("search.toml", "search", &text, &configs()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let options = StudyOptions {
        threads: Some(2),
        ..StudyOptions::default()
    };
    let summary = run_study(&study, dir.path(), &options, &|_, _| {}).unwrap();
    let [outcome] = &summary.searches[..] else {
        panic!("one search: {:?}", summary.searches)
    };
    assert_eq!(outcome.status, "bracketed");
    let (below, above) = (outcome.below.unwrap(), outcome.at_or_above.unwrap());
    assert!(
        below < above && above - below <= tolerance,
        "{below} {above}"
    );
    // Bisection (the default, whatever the threads): the two ends, then
    // ceil(log2(12 / 0.2)) = 6 halvings.
    assert_eq!(outcome.rounds, 6);
    assert_eq!(outcome.probes.len(), 2 + 6);
    assert!(outcome.verification.monotone);
    // Independent check: direct runs on either side of the bracket agree with it, and so
    // does every probe (each probe's outcome is a direct run's).
    assert_eq!(direct(below, window), None, "{below} Hz");
    assert!(direct(above, window).is_some(), "{above} Hz");
    for p in &outcome.probes {
        assert_eq!(
            p.reached,
            Some(direct(p.value, window).is_some()),
            "{}",
            p.value
        );
        assert_eq!(p.reached, Some(p.value >= above), "{} vs {above}", p.value);
    }
    // The files: search.json with the bracket, results.csv with a row per probe.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("search.json")).unwrap())
            .unwrap();
    assert_eq!(json["status"], "bracketed");
    assert_eq!(json["at_or_above"].as_f64(), Some(above));
    assert_eq!(json["criterion"], "collapse");
    let csv = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + outcome.probes.len());
}

#[test]
fn search_settings_are_checked_where_they_are_written() {
    let bad = [
        (
            "low = 30.0\nhigh = 20.0\ntolerance = 0.1\ntime = 0.1",
            "search.high",
        ),
        (
            "low = 20.0\nhigh = 30.0\ntolerance = 0.0\ntime = 0.1",
            "search.tolerance",
        ),
        ("low = 20.0\nhigh = 30.0\ntolerance = 0.1", "search"),
        (
            "low = 20.0\nhigh = 30.0\ntolerance = 0.1\ntime = 0.1\nrevolutions = 3.0",
            "search",
        ),
    ];
    for (body, key) in bad {
        let text = format!("{COUPLED}\n[search]\nkey = \"trajectory.frequency\"\n{body}\n");
        let err = Study::from_text("s.toml", "s", &text, &configs()).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains(&format!("{key}:")) || message.contains(key),
            "{message}"
        );
    }
    // Revolutions need the frequency key.
    let text = format!(
        "{COUPLED}\n[search]\nkey = \"trajectory.radius\"\nlow = 0.01\nhigh = 0.05\ntolerance = 0.001\nrevolutions = 5.0\n"
    );
    let message = Study::from_text("s.toml", "s", &text, &configs())
        .unwrap_err()
        .to_string();
    assert!(message.contains("search.revolutions"), "{message}");
}

/// The KED buckling speed from frequencies only: whether link `link` (1-based) buckles within
/// `end` s at `f` Hz, by a direct frequencies-only run of the coupled scene's machine.
fn direct_buckles(f: f64, end: f64) -> bool {
    let text = std::fs::read_to_string(configs().join("coupled_f20.toml"))
        .unwrap()
        .replace("frequency = 20.0", &format!("frequency = {f:?}"))
        .replace("end = 0.2", &format!("end = {end:?}"))
        .replace("coupling = \"coupled\"", "coupling = \"ked\"")
        .replace(
            "requests = [\"axial_forces\", \"driving_forces\", \"frequencies\", \"modes\", \"deflections\"]",
            "requests = [\"frequencies\"]",
        );
    let scene = Scene::from_text("direct.toml", "direct", &text).unwrap();
    assert!(!scene.needs_integration(), "a frequencies-only scene");
    let result = run(&scene, &mut |_| {}).unwrap();
    !result.frequencies.unwrap().buckling.is_empty()
}

/// The collapse bracket of the external ANCF model (`validation/data/collapse_speeds.json`,
/// independent data): the largest frequency whose largest mid-point deflection stays below
/// 20 mm within 0.5 s, and the smallest that passes it.
fn external_bracket() -> (f64, f64) {
    let json: serde_json::Value = serde_json::from_str(include_str!(
        "../../../validation/data/collapse_speeds.json"
    ))
    .unwrap();
    let runs = json["runs"].as_array().unwrap();
    let (mut below, mut above) = (f64::NEG_INFINITY, f64::INFINITY);
    for r in runs {
        assert_eq!(r["end_s"].as_f64(), Some(0.5), "a 0.5 s run");
        let f = r["frequency_Hz"].as_f64().unwrap();
        if r["t_deflection_10pct_s"].is_null() {
            below = below.max(f);
        } else {
            above = above.min(f);
        }
    }
    assert!(
        below < above,
        "the external runs bracket one threshold: {below} {above}"
    );
    (below, above)
}

/// The speed limits side by side (`configs/study_speed_limit.toml` without its slow
/// nonlinear case): one search per model. The KED buckling speed is checked by direct
/// frequencies-only runs on either side, and the coupled collapse speed against the
/// external ANCF model's bracket: every threshold in the coupled bracket lies within
/// 0.5 Hz of every threshold in the external one (issue 18's target).
#[test]
fn the_speed_limits_of_the_models_side_by_side() {
    let text = std::fs::read_to_string(configs().join("study_speed_limit.toml"))
        .unwrap()
        .lines()
        .filter(|l| !l.contains("coupling = \"nonlinear\""))
        .collect::<Vec<_>>()
        .join("\n");
    let study = Study::from_text("speed_limit.toml", "speed_limit", &text, &configs()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let summary = run_study(&study, dir.path(), &StudyOptions::default(), &|_, _| {}).unwrap();
    let [ked, coupled] = &summary.searches[..] else {
        panic!("two searches: {:?}", summary.searches)
    };
    assert_eq!(ked.criterion, Criterion::Buckling);
    assert_eq!(coupled.criterion, Criterion::Collapse);
    for s in [ked, coupled] {
        assert_eq!(s.status, "bracketed", "{}", s.case_label());
        let (below, above) = (s.below.unwrap(), s.at_or_above.unwrap());
        assert!(above > below && above - below <= 0.1, "{below} {above}");
    }
    // KED: direct runs on either side of the bracket.
    let (kb, ka) = (ked.below.unwrap(), ked.at_or_above.unwrap());
    assert!(!direct_buckles(kb, 0.5), "{kb} Hz");
    assert!(direct_buckles(ka, 0.5), "{ka} Hz");
    // Coupled: against the external model.
    let (eb, ea) = external_bracket();
    let (cb, ca) = (coupled.below.unwrap(), coupled.at_or_above.unwrap());
    assert!(
        ca - eb <= 0.5 && ea - cb <= 0.5,
        "coupled ({cb}, {ca}] Hz against external ({eb}, {ea}] Hz"
    );
    // The collapse comes well below the KED estimate.
    assert!(ca < kb - 5.0, "coupled {ca} Hz, KED {kb} Hz");
    // search.md sets them side by side, one row per model.
    let md = std::fs::read_to_string(dir.path().join("search.md")).unwrap();
    assert!(
        md.contains("| buckling | bracketed |") && md.contains("| collapse | bracketed |"),
        "{md}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("search.json")).unwrap())
            .unwrap();
    assert_eq!(json["searches"].as_array().map(Vec::len), Some(2));
}

/// Searches that cannot work are refused where they are written: a KED case asked to
/// collapse, and an axis over the searched key.
#[test]
fn search_criteria_are_checked_against_each_case() {
    let text = format!(
        "{COUPLED}\n[[axis]]\nkey = \"model.coupling\"\nvalues = [\"ked\", \"coupled\"]\n\
         [search]\nkey = \"trajectory.frequency\"\nlow = 20.0\nhigh = 30.0\ntolerance = 0.5\n\
         time = 0.05\ncriterion = \"collapse\"\n"
    );
    let message = Study::from_text("s.toml", "s", &text, &configs())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("search.criterion")
            && message.contains("model.coupling = ked")
            && message.contains("cannot collapse"),
        "{message}"
    );
    assert_eq!(message.lines().count(), 1, "{message}");
    let text = format!(
        "{COUPLED}\n[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [20.0, 25.0]\n\
         [search]\nkey = \"trajectory.frequency\"\nlow = 20.0\nhigh = 30.0\ntolerance = 0.5\ntime = 0.05\n"
    );
    let message = Study::from_text("s.toml", "s", &text, &configs())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("axis.0.key") && message.contains("varies"),
        "{message}"
    );
}
