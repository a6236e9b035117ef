//! Parameter studies: the results table does not depend on threads, shards or resumes;
//! ranges follow their closed forms; derived quantities obey the laws of the model
//! (Euler-Bernoulli frequencies, forces proportional to f^2) and agree with direct runs.

use std::path::{Path, PathBuf};

use flexprr_run::run;
use flexprr_scene::Scene;
use flexprr_studies::study::{
    CaseStatus, RangeConfig, Shard, Spacing, Study, StudyOptions, merge_studies, read_case_records,
    run_study,
};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

/// The paper's scene with `output` and `time` overrides, `body` being the study's own keys.
fn study_with(body: &str, output: &str, time: &str) -> Study {
    let text = format!(
        "base = \"paper_f20.toml\"\n{body}\n[set.output]\n{output}\ncompare_without_axial_force = false\nplots = false\n[set.time]\n{time}\n"
    );
    Study::from_text("test.toml", "test", &text, &configs()).unwrap()
}

/// Frequencies only, over a short span.
fn study(body: &str) -> Study {
    study_with(
        body,
        r#"requests = ["frequencies"]"#,
        "end = 0.05\noutput_step = 1e-3",
    )
}

fn small_study() -> Study {
    study(
        r#"
quantities = [
    { kind = "frequency_range", link = 1, mode = 1 },
    { kind = "peak_axial_force", link = 2 },
    { kind = "buckling", link = 1 },
]
[[axis]]
key = "model.formulation"
values = ["paper", "consistent"]
[[axis]]
key = "trajectory.frequency"
values = [5.0, 20.0, 35]
[[axis]]
key = "links.section.thickness"
values = [0.002, -0.001]
"#,
    )
}

fn options(threads: usize) -> StudyOptions {
    StudyOptions {
        threads: Some(threads),
        ..StudyOptions::default()
    }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn table_is_identical_for_one_and_two_threads_and_three_merged_shards() {
    let s = small_study();
    assert_eq!(s.cases.len(), 12);
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let two = tmp.path().join("two");
    run_study(&s, &one, &options(1), &|_, _| {}).unwrap();
    run_study(&s, &two, &options(2), &|_, _| {}).unwrap();
    let mut shard_dirs = Vec::new();
    for k in 1..=3 {
        let dir = tmp.path().join(format!("shard{k}"));
        let opts = StudyOptions {
            shard: Some(Shard { index: k, count: 3 }),
            ..options(1)
        };
        let summary = run_study(&s, &dir, &opts, &|_, _| {}).unwrap();
        assert_eq!(summary.progress.total, 4);
        shard_dirs.push(dir);
    }
    // Merging needs every shard.
    let partial = merge_studies(&shard_dirs[..2], &tmp.path().join("partial"));
    assert!(
        partial
            .unwrap_err()
            .to_string()
            .contains("4 of 12 cases missing")
    );
    let merged = tmp.path().join("merged");
    let summary = merge_studies(&shard_dirs, &merged).unwrap();
    assert_eq!((summary.cases, summary.failed), (12, 6));

    let table = read(&one.join("results.csv"));
    assert_eq!(table, read(&two.join("results.csv")));
    assert_eq!(table, read(&merged.join("results.csv")));

    // Rows: header + 12 in id order; the first axis varies slowest; negative thickness is
    // recorded as invalid with the key in the message, and the study went on.
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(
        rows[0],
        "case,model.formulation,trajectory.frequency,links.section.thickness,f_min_1_1_Hz,f_max_1_1_Hz,P_max_2_N,P_min_2_N,buckles_1,buckling_start_1_s,status,error"
    );
    assert_eq!(rows.len(), 13);
    assert!(rows[1].starts_with("0,paper,5,0.002,"));
    assert!(rows[12].starts_with("11,consistent,35,-0.001,"));
    for (k, row) in rows[1..].iter().enumerate() {
        let invalid = k % 2 == 1;
        assert_eq!(row.contains(",invalid,"), invalid, "{row}");
        if invalid {
            assert!(row.contains("links.section.thickness"), "{row}");
        } else {
            assert!(row.ends_with(",ok,"), "{row}");
        }
    }
}

#[test]
fn resume_completes_an_interrupted_study_with_the_same_table() {
    let s = small_study();
    let tmp = tempfile::tempdir().unwrap();
    let full = tmp.path().join("full");
    run_study(&s, &full, &options(2), &|_, _| {}).unwrap();
    // An interrupted run: some case files and no table.
    let cut = tmp.path().join("cut");
    run_study(&s, &cut, &options(2), &|_, _| {}).unwrap();
    std::fs::remove_file(cut.join("results.csv")).unwrap();
    for id in [0, 3, 4, 11] {
        std::fs::remove_file(cut.join(format!("cases/{id:06}.json"))).unwrap();
    }
    // A stale temporary file from a killed writer is ignored.
    std::fs::write(cut.join("cases/.000003.json.1.tmp"), "{ half").unwrap();

    let again = run_study(&s, &cut, &options(1), &|_, _| {});
    assert!(again.unwrap_err().to_string().contains("--resume"));
    let resume = StudyOptions {
        resume: true,
        ..options(2)
    };
    let ran = std::sync::Mutex::new(Vec::new());
    let summary = run_study(&s, &cut, &resume, &|_, r| ran.lock().unwrap().push(r.id)).unwrap();
    let mut ran = ran.into_inner().unwrap();
    ran.sort_unstable();
    assert_eq!(ran, vec![0, 3, 4, 11]);
    assert_eq!((summary.ran, summary.progress.resumed), (4, 8));
    assert_eq!(
        read(&cut.join("results.csv")),
        read(&full.join("results.csv"))
    );

    // Another study in the same directory is refused.
    let other = study(
        r#"
[[axis]]
key = "trajectory.frequency"
values = [5.0]
"#,
    );
    let refused = run_study(&other, &cut, &resume, &|_, _| {});
    assert!(refused.unwrap_err().to_string().contains("another study"));
}

#[test]
fn ranges_follow_their_closed_forms() {
    let linear = RangeConfig {
        start: 5.0,
        end: 40.0,
        count: 71,
        spacing: Spacing::Linear,
    }
    .values();
    assert_eq!(linear.len(), 71);
    for (k, v) in linear.iter().enumerate() {
        approx::assert_relative_eq!(*v, 5.0 + 0.5 * k as f64, max_relative = 1e-15);
    }
    let log = RangeConfig {
        start: 1e-3,
        end: 1e-1,
        count: 5,
        spacing: Spacing::Log,
    }
    .values();
    for (k, v) in log.iter().enumerate() {
        approx::assert_relative_eq!(*v, 1e-3 * 10f64.powf(0.5 * k as f64), max_relative = 1e-14);
    }
    approx::assert_relative_eq!(log[4], 0.1);
}

#[test]
fn product_varies_the_last_axis_fastest_and_zip_pairs_values() {
    let product = study(
        r#"
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0]
[[axis]]
key = "machine.platform_mass"
range = { start = 0.1, end = 0.3, count = 3 }
"#,
    );
    let pairs: Vec<(f64, f64)> = product
        .cases
        .iter()
        .map(|c| {
            (
                c.values[0].as_float().unwrap(),
                c.values[1].as_float().unwrap(),
            )
        })
        .collect();
    let expected = [
        (5.0, 0.1),
        (5.0, 0.2),
        (5.0, 0.3),
        (10.0, 0.1),
        (10.0, 0.2),
        (10.0, 0.3),
    ];
    assert_eq!(pairs.len(), expected.len());
    for (p, e) in pairs.iter().zip(expected) {
        approx::assert_relative_eq!(p.0, e.0);
        approx::assert_relative_eq!(p.1, e.1, max_relative = 1e-15);
    }
    let zipped = study(
        r#"
combine = "zip"
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0, 15.0]
[[axis]]
key = "machine.platform_mass"
range = { start = 0.1, end = 0.3, count = 3 }
"#,
    );
    assert_eq!(zipped.cases.len(), 3);
    approx::assert_relative_eq!(zipped.cases[2].values[0].as_float().unwrap(), 15.0);
    approx::assert_relative_eq!(zipped.cases[2].values[1].as_float().unwrap(), 0.3);

    let bad = |body: &str| {
        Study::from_text(
            "bad.toml",
            "bad",
            &format!("base = \"paper_f20.toml\"\n{body}"),
            &configs(),
        )
        .unwrap_err()
        .to_string()
    };
    let mismatch = bad(r#"
combine = "zip"
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0]
[[axis]]
key = "machine.platform_mass"
values = [0.1]
"#);
    assert!(mismatch.contains("equal lengths"), "{mismatch}");
    let link = bad(r#"quantities = [{ kind = "buckling", link = 4 }]"#);
    assert!(link.contains("quantities.0.link"), "{link}");
    let log = bad(r#"
[[axis]]
key = "trajectory.frequency"
range = { start = 0.0, end = 10.0, count = 3, spacing = "log" }
"#);
    assert!(log.contains("axis.0.range"), "{log}");
    let unknown = bad(r#"
[[axis]]
key = "trajectory.frequency"
value = [1.0]
"#);
    assert!(unknown.contains("unknown field `value`"), "{unknown}");
    assert!("0/3".parse::<Shard>().is_err());
    assert!("4/3".parse::<Shard>().is_err());
    assert_eq!(
        "2/3".parse::<Shard>().unwrap(),
        Shard { index: 2, count: 3 }
    );
}

/// Columns of a results table as (header, rows).
fn parse_table(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header = reader.headers().unwrap().iter().map(String::from).collect();
    let rows = reader
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let c = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[c].parse().unwrap()).collect()
}

/// At a very slow motion the axial forces vanish and link 1's first frequency is the
/// Euler-Bernoulli pinned-pinned value f_1 = (pi / (2 l^2)) sqrt(E t^2 / (12 rho)), which is
/// proportional to the thickness t.
#[test]
fn slow_motion_frequencies_match_euler_bernoulli_for_every_thickness() {
    let s = study(
        r#"
quantities = [{ kind = "frequency_range", link = 1, mode = 1 }]
[set.trajectory]
frequency = 0.01
[[axis]]
key = "links.section.thickness"
range = { start = 1e-3, end = 4e-3, count = 3, spacing = "log" }
"#,
    );
    let tmp = tempfile::tempdir().unwrap();
    run_study(&s, tmp.path(), &options(2), &|_, _| {}).unwrap();
    let (header, rows) = parse_table(&read(&tmp.path().join("results.csv")));
    let (length, youngs, density) = (0.2_f64, 7.3e10_f64, 2770.0_f64);
    for (k, thickness) in [1e-3, 2e-3, 4e-3].into_iter().enumerate() {
        let euler = std::f64::consts::PI / (2.0 * length * length)
            * (youngs * thickness * thickness / (12.0 * density)).sqrt();
        for name in ["f_min_1_1_Hz", "f_max_1_1_Hz"] {
            let f = column(&header, &rows, name)[k];
            approx::assert_relative_eq!(f, euler, max_relative = 1e-6);
        }
    }
}

/// For a fixed path, accelerations and velocity products scale with f^2, so do the axial
/// forces, and with the paper's linear geometric stiffness so does the loss of stiffness
/// 1 - omega_min^2 / omega_0^2.
#[test]
fn axial_force_and_stiffness_loss_scale_with_the_square_of_the_speed() {
    let s = study_with(
        r#"
quantities = [
    { kind = "peak_axial_force", link = 1 },
    { kind = "stiffness_ratio", link = 1, mode = 1 },
]
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0, 20.0, 30.0]
"#,
        r#"requests = ["frequencies"]"#,
        "end = 0.2\noutput_step = 1e-4",
    );
    let tmp = tempfile::tempdir().unwrap();
    run_study(&s, tmp.path(), &options(2), &|_, _| {}).unwrap();
    let (header, rows) = parse_table(&read(&tmp.path().join("results.csv")));
    let f = column(&header, &rows, "trajectory.frequency");
    for name in ["P_max_1_N", "P_min_1_N"] {
        let p = column(&header, &rows, name);
        for k in 1..f.len() {
            approx::assert_relative_eq!(
                p[k] / (f[k] * f[k]),
                p[0] / (f[0] * f[0]),
                max_relative = 1e-3
            );
        }
    }
    let loss: Vec<f64> = column(&header, &rows, "stiffness_ratio_min_1_1")
        .iter()
        .zip(&f)
        .map(|(r, f)| (1.0 - r) / (f * f))
        .collect();
    for l in &loss[1..] {
        approx::assert_relative_eq!(*l, loss[0], max_relative = 1e-3);
    }
}

/// A case's quantities equal those of the same scene written by hand and run directly.
#[test]
fn case_quantities_agree_with_a_direct_run_of_the_edited_scene() {
    let s = study(
        r#"
quantities = [
    { kind = "frequency_range", link = 1, mode = 2 },
    { kind = "buckling", link = 1 },
]
[[axis]]
key = "trajectory.frequency"
values = [35.0]
"#,
    );
    let (record, _) = s.run_case(&s.cases[0]);
    assert_eq!(record.status, CaseStatus::Ok, "{}", record.error);

    let text = read(&configs().join("paper_f20.toml"))
        .replace("frequency = 20.0", "frequency = 35.0")
        .replace("end = 0.2", "end = 0.05")
        .replace("output_step = 1e-4", "output_step = 1e-3")
        .replace("compare_without_axial_force = true", "")
        .replace(
            r#"requests = ["kinematics", "driving_forces", "joint_reactions", "axial_forces", "frequencies", "modes", "modal_forces", "deflections", "energies", "viewer", "snapshots", "machine"]"#,
            r#"requests = ["frequencies"]"#,
        );
    let scene = Scene::from_text("hand.toml", "hand", &text).unwrap();
    let direct = run(&scene, &mut |_| {}).unwrap();
    let history = direct.frequencies.unwrap();
    let range = history
        .ranges
        .iter()
        .find(|r| r.link == 0 && r.mode == 1)
        .unwrap();
    let got: Vec<f64> = record.quantities[..2]
        .iter()
        .map(|q| q.parse().unwrap())
        .collect();
    approx::assert_relative_eq!(got[0], range.min_hz, max_relative = 1e-9);
    approx::assert_relative_eq!(got[1], range.max_hz, max_relative = 1e-9);
    let start = history
        .buckling
        .iter()
        .find(|b| b.link == 0)
        .expect("link 1 buckles at 35 Hz");
    assert_eq!(record.quantities[2], "yes");
    let t: f64 = record.quantities[3].parse().unwrap();
    approx::assert_relative_eq!(t, start.t_start, max_relative = 1e-9);
}

/// A run failure (step-size budget exhausted) and a quantity whose output was not requested
/// are recorded per case; the other cases run.
#[test]
fn failing_cases_are_recorded_and_the_study_continues() {
    let s = study_with(
        r#"
quantities = [{ kind = "peak_deflection", link = 1 }]
[[axis]]
key = "integrator.max_steps"
values = [3, 100000]
[[axis]]
key = "output.requests"
values = [["deflections"], ["frequencies"]]
"#,
        r#"requests = ["deflections"]"#,
        "end = 0.002\noutput_step = 1e-4",
    );
    let tmp = tempfile::tempdir().unwrap();
    let summary = run_study(&s, tmp.path(), &options(2), &|_, _| {}).unwrap();
    assert_eq!(summary.progress.failed, 3);
    let records = read_case_records(tmp.path()).unwrap();
    let status: Vec<CaseStatus> = records.values().map(|r| r.status).collect();
    assert_eq!(
        status,
        [
            CaseStatus::Failed,
            CaseStatus::Failed,
            CaseStatus::Ok,
            CaseStatus::Failed
        ]
    );
    assert!(
        records[&0]
            .error
            .contains("abm integrator: gave up after 3 steps"),
        "{}",
        records[&0].error
    );
    assert!(
        records[&3].error.contains("needs the output"),
        "{}",
        records[&3].error
    );
    let w: f64 = records[&2].quantities[0].parse().unwrap();
    assert!(w.is_finite() && w > 0.0);
}

/// A 1 mm link at 20 Hz buckles (its frequency history has a buckling interval); the
/// integrated deflection then grows past the link length, and the case is recorded as a
/// divergence instead of tabulating a meaningless peak.
#[test]
fn buckling_divergence_is_a_recorded_failure() {
    let s = study_with(
        r#"
quantities = [{ kind = "peak_deflection", link = 1 }, { kind = "buckling", link = 1 }]
[[axis]]
key = "links.section.thickness"
values = [0.001, 0.004]
"#,
        r#"requests = ["deflections", "frequencies"]"#,
        "end = 0.1\noutput_step = 1e-4",
    );
    let (thin, _) = s.run_case(&s.cases[0]);
    assert_eq!(thin.status, CaseStatus::Failed);
    assert!(thin.error.contains("diverged"), "{}", thin.error);
    assert!(thin.error.contains("a link buckles"), "{}", thin.error);
    let (thick, _) = s.run_case(&s.cases[1]);
    assert_eq!(thick.status, CaseStatus::Ok, "{}", thick.error);
    assert_eq!(thick.quantities[1], "no");
    let w: f64 = thick.quantities[0].parse().unwrap();
    assert!(w > 0.0 && w < 0.01 * 0.2, "{w}");
}

/// `case_outputs` writes each case's full outputs next to its record; the record reader
/// ignores those directories, and the plots are drawn from the table.
#[test]
fn case_outputs_and_plots_are_written_on_request() {
    let s = study(
        r#"
quantities = [{ kind = "frequency_range", link = 1, mode = 1 }]
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0]
[[plot]]
file = "range.svg"
x = "trajectory.frequency"
y = ["f_min_1_1_Hz"]
"#,
    );
    let tmp = tempfile::tempdir().unwrap();
    let opts = StudyOptions {
        case_outputs: true,
        ..options(2)
    };
    run_study(&s, tmp.path(), &opts, &|_, _| {}).unwrap();
    for id in 0..2 {
        let table = read(&tmp.path().join(format!("cases/{id:06}/frequencies.csv")));
        assert!(table.starts_with("t_s,f_1_1_Hz"), "{}", &table[..40]);
    }
    assert_eq!(read_case_records(tmp.path()).unwrap().len(), 2);
    assert!(read(&tmp.path().join("range.svg")).contains("<svg"));
}
