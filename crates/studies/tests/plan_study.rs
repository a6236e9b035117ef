//! `{ kind = "plan" }` in a study (configs/study_plan_thickness.toml): each case is planned
//! with its flexible check. Checked against the physics of the shaper, not the code: ZVD adds
//! one damped period of the lowest mode, the links' first bending mode, whose frequency is
//! the paper's 116.4 Hz (Table I) at 2 mm and scales with the thickness (a pinned-pinned
//! beam's `f ~ t`), so the shaped minus the unshaped cycle time is `1 / f(t)`; the shaped
//! move leaves a small fraction of the unshaped residual vibration.

use std::path::{Path, PathBuf};

use flexprr_studies::study::{Study, StudyOptions, read_case_records, run_study};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

#[test]
fn the_planned_cycle_time_grows_by_one_period_of_the_links_mode_when_shaped() {
    let text = std::fs::read_to_string(configs().join("study_plan_thickness.toml")).unwrap();
    let study = Study::from_text("study_plan_thickness.toml", "plan", &text, &configs()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_study(&study, dir.path(), &StudyOptions::default(), &|_, _| {}).unwrap();
    let records = read_case_records(dir.path()).unwrap();
    let columns = study.columns();
    let value = |id: usize, name: &str| -> f64 {
        // After the case number and the two axes.
        let k = columns.iter().position(|c| c == name).unwrap() - 3;
        records[&id].quantities[k].parse().unwrap()
    };
    let thickness = [1.5e-3, 2e-3, 3e-3, 4e-3];
    for (k, t) in thickness.iter().enumerate() {
        // Product order: thickness slowest, then shaping ("none", "zvd").
        let (none, zvd) = (2 * k, 2 * k + 1);
        for id in [none, zvd] {
            assert_eq!(records[&id].status.name(), "ok", "{:?}", records[&id].error);
        }
        let f = 116.4 * t / 2e-3;
        let extra = value(zvd, "cycle_time_s") - value(none, "cycle_time_s");
        assert!(
            (extra * f - 1.0).abs() < 0.01,
            "t = {t}: the shaper adds {extra} s, one period of {f} Hz is {} s",
            1.0 / f
        );
        let (shaped, unshaped) = (
            value(zvd, "residual_vibration_m"),
            value(none, "residual_vibration_m"),
        );
        assert!(shaped < 0.05 * unshaped, "t = {t}: {shaped} vs {unshaped}");
        // The peak deflection of the planned run is at least the mid-point's.
        for id in [none, zvd] {
            assert!(value(id, "plan_peak_deflection_m") >= value(id, "w_peak_1_m") * (1.0 - 1e-9));
        }
    }
}

#[test]
fn the_plan_quantity_needs_a_plan_section() {
    let text = "base = \"paper_f20.toml\"\nquantities = [{ kind = \"plan\" }]\n[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [10.0]\n";
    let study = Study::from_text("noplan.toml", "noplan", text, &configs());
    let message = match study {
        Err(e) => e.to_string(),
        Ok(study) => {
            let dir = tempfile::tempdir().unwrap();
            run_study(&study, dir.path(), &StudyOptions::default(), &|_, _| {}).unwrap();
            let records = read_case_records(dir.path()).unwrap();
            records[&0].error.clone()
        }
    };
    assert!(message.contains("needs a [plan] section"), "{message}");
}
