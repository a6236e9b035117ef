//! Case records: every record carries a status and, when not ok, a failure with kind, time
//! and message; a resume or a merge checks each record against its case and refuses one that
//! was edited, holds a non-finite value or the wrong number of values, naming its file.

use std::path::{Path, PathBuf};

use flexprr_integrators::IntegratorError;
use flexprr_studies::study::{
    CaseStatus, FailureKind, Shard, Study, StudyError, StudyOptions, classify_run_failure,
    merge_studies, read_case_records, run_study,
};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

/// Frequencies only: three speeds and a negative thickness (an invalid case each).
fn small_study() -> Study {
    let text = r#"
base = "paper_f20.toml"
quantities = [
    { kind = "frequency_range", link = 1, mode = 1 },
    { kind = "buckling", link = 1 },
]
[set.output]
requests = ["frequencies"]
compare_without_axial_force = false
plots = false
[set.time]
end = 0.05
output_step = 1e-3
[[axis]]
key = "trajectory.frequency"
values = [5.0, 20.0, 35.0]
[[axis]]
key = "links.section.thickness"
values = [0.002, -0.001]
"#;
    Study::from_text("records.toml", "records", text, &configs()).unwrap()
}

fn resume() -> StudyOptions {
    StudyOptions {
        threads: Some(2),
        resume: true,
        ..StudyOptions::default()
    }
}

fn record_path(dir: &Path, id: usize) -> PathBuf {
    dir.join(format!("cases/{id:06}.json"))
}

/// Edits record `id` of `dir` as JSON.
fn edit(dir: &Path, id: usize, change: impl FnOnce(&mut serde_json::Value)) {
    let path = record_path(dir, id);
    let mut record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    change(&mut record);
    std::fs::write(&path, serde_json::to_string_pretty(&record).unwrap()).unwrap();
}

/// Runs the study into a fresh directory and returns it with its table.
fn finished(tmp: &Path, name: &str) -> (PathBuf, String) {
    let dir = tmp.join(name);
    run_study(&small_study(), &dir, &resume(), &|_, _| {}).unwrap();
    let table = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    (dir, table)
}

/// Asserts that resuming `dir` is refused with a one-line record error naming `id`'s file
/// and saying `what`; then deleting that record and resuming restores `table`.
fn assert_refused_then_rerun(dir: &Path, id: usize, what: &str, table: &str) {
    let e = run_study(&small_study(), dir, &resume(), &|_, _| {}).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, StudyError::Record { .. }), "{message}");
    let file = record_path(dir, id).display().to_string();
    assert!(message.starts_with(&format!("{file}: ")), "{message}");
    assert!(message.contains(what), "{message}");
    assert!(
        message.ends_with("delete the file to run the case again"),
        "{message}"
    );
    assert!(!message.contains('\n'), "{message}");

    std::fs::remove_file(record_path(dir, id)).unwrap();
    let summary = run_study(&small_study(), dir, &resume(), &|_, _| {}).unwrap();
    assert_eq!(summary.ran, 1);
    assert_eq!(
        std::fs::read_to_string(dir.join("results.csv")).unwrap(),
        table
    );
}

#[test]
fn records_have_a_status_and_failures_say_kind_and_time() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, _) = finished(tmp.path(), "run");
    let records = read_case_records(&dir).unwrap();
    let study = small_study();
    for (id, r) in &records {
        assert_eq!(study.check_record(r), Ok(()), "case {id}");
        // The thickness axis varies fastest: odd cases have the negative thickness.
        if id % 2 == 1 {
            assert_eq!(r.status, CaseStatus::Invalid);
            let failure = r.failure.as_ref().unwrap();
            assert_eq!(failure.kind, FailureKind::InvalidInput);
            assert_eq!(failure.time, None);
            assert_eq!(failure.message, r.error);
            assert!(r.error.contains("links.section.thickness"), "{}", r.error);
            assert!(r.quantities.iter().all(String::is_empty));
        } else {
            assert_eq!(r.status, CaseStatus::Ok, "{}", r.error);
            assert!(r.failure.is_none() && r.error.is_empty());
        }
    }
    // The record file says so too, in words.
    let text = std::fs::read_to_string(record_path(&dir, 1)).unwrap();
    assert!(text.contains("\"kind\": \"invalid_input\""), "{text}");
    assert!(text.contains("\"status\": \"invalid\""), "{text}");
}

/// The kinds and times come from the integrator's own messages: each variant's text, built
/// here from the integrator's error type, classifies to its kind and its time.
#[test]
fn run_failures_are_classified_from_the_integrators_messages() {
    let cases = [
        (
            IntegratorError::StepSizeTooSmall {
                t: 0.0125,
                h: 1e-18,
            },
            FailureKind::StepSize,
            0.0125,
        ),
        (
            IntegratorError::TooManySteps {
                t: 2.5e-3,
                max_steps: 3,
            },
            FailureKind::StepBudget,
            2.5e-3,
        ),
        (
            IntegratorError::NonFinite {
                t: 0.07,
                component: 4,
            },
            FailureKind::NonFinite,
            0.07,
        ),
        (
            IntegratorError::NewtonFailure { t: 0.1, h: 1e-6 },
            FailureKind::Newton,
            0.1,
        ),
        (
            IntegratorError::SingularMatrix { t: 0.2 },
            FailureKind::Newton,
            0.2,
        ),
        (
            IntegratorError::Stiff {
                t: 0.031,
                h_lambda: 3.3,
            },
            FailureKind::Stiff,
            0.031,
        ),
    ];
    for (error, kind, t) in cases {
        let run_error = flexprr_run::RunError::Integrator {
            method: "abm".to_string(),
            source: error,
        };
        let (found, time) = classify_run_failure(&run_error);
        assert_eq!(found, kind, "{run_error}");
        approx::assert_relative_eq!(time.unwrap(), t, max_relative = 1e-15);
    }
    let diverged = flexprr_run::RunError::Diverged {
        link: 0,
        t: 0.0561,
        xi: 0.5,
        w: 0.203,
        limit: 0.1,
        fraction: 0.5,
    };
    let (kind, time) = classify_run_failure(&diverged);
    assert_eq!(kind, FailureKind::Diverged);
    approx::assert_relative_eq!(time.unwrap(), 0.0561);
}

#[test]
fn an_edited_parameter_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, table) = finished(tmp.path(), "edited");
    edit(&dir, 2, |r| r["parameters"][0] = "21".into());
    assert_refused_then_rerun(
        &dir,
        2,
        "parameter 1 is \"21\", the case has \"20\"",
        &table,
    );
}

#[test]
fn a_nan_value_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, table) = finished(tmp.path(), "nan");
    edit(&dir, 4, |r| r["quantities"][1] = "NaN".into());
    assert_refused_then_rerun(
        &dir,
        4,
        "f_max_1_1_Hz = \"NaN\" is not a finite number",
        &table,
    );
    // A flag column takes only yes or no.
    edit(&dir, 0, |r| r["quantities"][2] = "maybe".into());
    assert_refused_then_rerun(&dir, 0, "buckles_1 = \"maybe\" is not yes or no", &table);
}

#[test]
fn a_wrong_number_of_values_is_refused_in_the_record_not_in_the_table() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, table) = finished(tmp.path(), "count");
    edit(&dir, 0, |r| {
        r["quantities"].as_array_mut().unwrap().pop();
    });
    assert_refused_then_rerun(
        &dir,
        0,
        "3 quantity values, the study has 4 quantity columns",
        &table,
    );
    edit(&dir, 2, |r| {
        r["parameters"].as_array_mut().unwrap().push("1".into());
    });
    assert_refused_then_rerun(&dir, 2, "3 parameters, the study has 2 axes", &table);
}

#[test]
fn status_and_failure_must_agree() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, table) = finished(tmp.path(), "status");
    // A failed case turned ok by hand, without values.
    edit(&dir, 1, |r| {
        r["status"] = "ok".into();
    });
    assert_refused_then_rerun(&dir, 1, "status ok with a failure", &table);
    // A failure without its object.
    edit(&dir, 3, |r| {
        r.as_object_mut().unwrap().remove("failure");
    });
    assert_refused_then_rerun(&dir, 3, "status invalid without a failure", &table);
    // A record moved to another case's file.
    std::fs::copy(record_path(&dir, 0), record_path(&dir, 2)).unwrap();
    assert_refused_then_rerun(&dir, 2, "holds case 0, not case 2", &table);
    // Not JSON at all.
    std::fs::write(record_path(&dir, 5), "{ half").unwrap();
    assert_refused_then_rerun(&dir, 5, "not a case record", &table);
}

#[test]
fn a_merge_refuses_a_bad_record_too() {
    let tmp = tempfile::tempdir().unwrap();
    let study = small_study();
    let mut shards = Vec::new();
    for k in 1..=2 {
        let dir = tmp.path().join(format!("shard{k}"));
        let options = StudyOptions {
            shard: Some(Shard { index: k, count: 2 }),
            ..resume()
        };
        run_study(&study, &dir, &options, &|_, _| {}).unwrap();
        shards.push(dir);
    }
    edit(&shards[0], 2, |r| r["quantities"][0] = "inf".into());
    let e = merge_studies(&shards, &tmp.path().join("merged")).unwrap_err();
    let file = record_path(&shards[0], 2).display().to_string();
    let message = e.to_string();
    assert!(
        message.starts_with(&format!("{file}: f_min_1_1_Hz = \"inf\"")),
        "{message}"
    );
}
