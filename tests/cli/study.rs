//! `flexprr study` and `flexprr merge` as a user runs them: a study killed midway leaves only
//! complete case records, and `--resume` completes it with the table of an uninterrupted run.

use crate::common::{configs, flexprr};
use std::path::{Path, PathBuf};
use std::process::Stdio;

/// A study of `cases` frequencies-only cases of the paper's scene.
fn write_study(dir: &Path, cases: usize) -> PathBuf {
    let base = configs().join("paper_f20.toml");
    let text = format!(
        r#"
name = "kill_resume"
base = {base:?}
quantities = [
    {{ kind = "frequency_range", link = 1, mode = 1 }},
    {{ kind = "buckling", link = 1 }},
]
[set.output]
requests = ["frequencies"]
compare_without_axial_force = false
plots = false
[set.time]
end = 0.2
output_step = 1e-4
[[axis]]
key = "trajectory.frequency"
range = {{ start = 5.0, end = 35.0, count = {cases} }}
"#,
        base = base.display().to_string()
    );
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn case_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir.join("cases"))
        .map(|entries| {
            entries
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "json"))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn killed_study_resumes_to_the_table_of_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = 150;
    let study = write_study(tmp.path(), cases);

    let reference = tmp.path().join("reference");
    let status = flexprr()
        .args(["study", "--quiet", "--threads", "2", "--out"])
        .arg(&reference)
        .arg(&study)
        .status()
        .unwrap();
    assert!(status.success());

    // Start on one thread and kill it once a few cases are recorded.
    let cut = tmp.path().join("cut");
    let mut child = flexprr()
        .args(["study", "--quiet", "--threads", "1", "--out"])
        .arg(&cut)
        .arg(&study)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut finished_before_kill = false;
    loop {
        if case_files(&cut).len() >= 3 {
            break;
        }
        if child.try_wait().unwrap().is_some() {
            finished_before_kill = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !finished_before_kill,
        "the study ended before it could be killed"
    );

    // Consistent: every record is complete JSON, and the table was not written.
    let recorded = case_files(&cut);
    assert!(
        recorded.len() >= 3 && recorded.len() < cases,
        "{}",
        recorded.len()
    );
    for path in &recorded {
        let text = std::fs::read_to_string(path).unwrap();
        let record: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(record["status"], "ok");
    }
    assert!(!cut.join("results.csv").exists());

    // Without --resume the directory is protected; with it the study completes.
    let refused = flexprr()
        .args(["study", "--quiet", "--out"])
        .arg(&cut)
        .arg(&study)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
    let resumed = flexprr()
        .args(["study", "--quiet", "--resume", "--out"])
        .arg(&cut)
        .arg(&study)
        .output()
        .unwrap();
    assert!(resumed.status.success());
    let report = String::from_utf8_lossy(&resumed.stdout);
    assert!(
        report.contains(&format!("{} resumed", recorded.len())),
        "{report}"
    );

    let table = std::fs::read_to_string(cut.join("results.csv")).unwrap();
    assert_eq!(
        table,
        std::fs::read_to_string(reference.join("results.csv")).unwrap()
    );
    assert_eq!(table.lines().count(), cases + 1);
}

#[test]
fn shards_merge_into_the_single_run_table_and_errors_have_exit_codes() {
    let tmp = tempfile::tempdir().unwrap();
    let study = write_study(tmp.path(), 7);
    let single = tmp.path().join("single");
    assert!(
        flexprr()
            .args(["study", "--quiet", "--out"])
            .arg(&single)
            .arg(&study)
            .status()
            .unwrap()
            .success()
    );
    let mut shards = Vec::new();
    for k in 1..=2 {
        let dir = tmp.path().join(format!("shard{k}"));
        assert!(
            flexprr()
                .args(["study", "--quiet", "--shard", &format!("{k}/2"), "--out"])
                .arg(&dir)
                .arg(&study)
                .status()
                .unwrap()
                .success()
        );
        shards.push(dir);
    }
    // One shard alone is incomplete: run failure (1).
    let merged = tmp.path().join("merged");
    let partial = flexprr()
        .args(["merge", "--out"])
        .arg(&merged)
        .arg(&shards[0])
        .output()
        .unwrap();
    assert_eq!(partial.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&partial.stderr).contains("3 of 7 cases missing"));
    let ok = flexprr()
        .args(["merge", "--out"])
        .arg(&merged)
        .args(&shards)
        .status()
        .unwrap();
    assert!(ok.success());
    assert_eq!(
        std::fs::read_to_string(merged.join("results.csv")).unwrap(),
        std::fs::read_to_string(single.join("results.csv")).unwrap()
    );

    // A bad study file and a bad shard are bad input (2).
    let bad = tmp.path().join("bad.toml");
    std::fs::write(&bad, "base = \"nowhere.toml\"\ncombine = \"diagonal\"\n").unwrap();
    let out = flexprr()
        .args(["study", "--out"])
        .arg(tmp.path().join("x"))
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("combine"));
    let out = flexprr()
        .args(["study", "--out"])
        .arg(tmp.path().join("x"))
        .arg(tmp.path().join("no_such_study.toml"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no_such_study.toml"));
    let out = flexprr()
        .args(["study", "--shard", "3/2", "--out"])
        .arg(tmp.path().join("x"))
        .arg(&study)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn merge_names_the_absent_and_incomplete_shards_and_resume_keeps_the_shard() {
    let tmp = tempfile::tempdir().unwrap();
    let study = write_study(tmp.path(), 10);
    let run_shard = |k: usize, extra: &[&str]| {
        let dir = tmp.path().join(format!("shard-{k}"));
        let out = flexprr()
            .args(["study", "--quiet", "--shard", &format!("{k}/3"), "--out"])
            .arg(&dir)
            .args(extra)
            .arg(&study)
            .output()
            .unwrap();
        (dir, out)
    };
    let (s1, out) = run_shard(1, &[]);
    assert!(out.status.success());
    let (s2, out) = run_shard(2, &[]);
    assert!(out.status.success());
    // Shard 2/3 holds ids 1, 4, 7; lose two of them as a killed task would.
    std::fs::remove_file(s2.join("cases/000004.json")).unwrap();
    std::fs::remove_file(s2.join("cases/000007.json")).unwrap();

    // Shard 3/3 (ids 2, 5, 8) was never run: 3 + 2 of the 10 cases are missing.
    let merged = tmp.path().join("merged");
    let refused = flexprr()
        .args(["merge", "--out"])
        .arg(&merged)
        .args([&s1, &s2])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(1));
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(message.contains("5 of 10 cases missing"), "{message}");
    assert!(message.contains("has 1 of its 3 cases"), "{message}");
    assert!(
        message.contains("shard 3/3 has no directory (3 cases)"),
        "{message}"
    );
    assert!(!message.contains("shard 1/3"), "{message}");
    assert!(!merged.join("results.csv").exists());

    // Resuming shard 2 as another shard of another split is refused; as itself it completes.
    let wrong = flexprr()
        .args(["study", "--quiet", "--resume", "--shard", "2/2", "--out"])
        .arg(&s2)
        .arg(&study)
        .output()
        .unwrap();
    assert_eq!(wrong.status.code(), Some(1));
    let message = String::from_utf8_lossy(&wrong.stderr);
    assert!(
        message.contains("holds shard 2/3") && message.contains("this run is shard 2/2"),
        "{message}"
    );
    let (_, again) = run_shard(2, &["--resume"]);
    assert!(again.status.success());
    assert!(String::from_utf8_lossy(&again.stdout).contains("(2 run now, 1 resumed)"));
    let (s3, out) = run_shard(3, &[]);
    assert!(out.status.success());
    let ok = flexprr()
        .args(["merge", "--out"])
        .arg(&merged)
        .args([&s1, &s2, &s3])
        .status()
        .unwrap();
    assert!(ok.success());
    let single = tmp.path().join("single");
    assert!(
        flexprr()
            .args(["study", "--quiet", "--out"])
            .arg(&single)
            .arg(&study)
            .status()
            .unwrap()
            .success()
    );
    assert_eq!(
        std::fs::read_to_string(merged.join("results.csv")).unwrap(),
        std::fs::read_to_string(single.join("results.csv")).unwrap()
    );
}

/// Off a terminal the progress is one line per tenth of the cases (never more than ten),
/// `--quiet` prints none, and a failed case is one short line naming its parameters by key.
#[test]
fn progress_off_a_terminal_is_one_line_per_tenth_and_failures_are_short() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = 30;
    let study = write_study(tmp.path(), cases);
    let out = flexprr()
        .args(["study", "--threads", "2", "--out"])
        .arg(tmp.path().join("loud"))
        .arg(&study)
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let progress: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("kill_resume: "))
        .collect();
    assert!(!progress.is_empty() && progress.len() <= 10, "{progress:?}");
    let last = progress.last().unwrap();
    assert!(
        last.starts_with(&format!(
            "kill_resume: {cases}/{cases} cases (100 %), 0 failed"
        )),
        "{last}"
    );
    let quiet = flexprr()
        .args(["study", "--quiet", "--out"])
        .arg(tmp.path().join("quiet"))
        .arg(&study)
        .output()
        .unwrap();
    assert!(quiet.status.success());
    assert_eq!(String::from_utf8_lossy(&quiet.stderr), "");

    // Negative thicknesses: every other case is invalid.
    let text = std::fs::read_to_string(&study).unwrap()
        + "[[axis]]\nkey = \"links.section.thickness\"\nvalues = [0.002, -0.001]\n";
    let failing = tmp.path().join("failing.toml");
    std::fs::write(&failing, text).unwrap();
    let out = flexprr()
        .args(["study", "--quiet", "--out"])
        .arg(tmp.path().join("failing"))
        .arg(&failing)
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    // At most 20 failure lines, then one line pointing to the table.
    assert_eq!(lines.len(), 21, "{stderr}");
    assert!(lines[20].contains("results.csv"), "{}", lines[20]);
    for line in &lines[..20] {
        assert!(
            line.contains("(trajectory.frequency = ")
                && line.contains(", links.section.thickness = -0.001): invalid (invalid_input): "),
            "{line}"
        );
        assert!(line.chars().count() < 200, "{line}");
    }
}

/// Input files must be regular files of bounded size; study errors are located.
#[test]
fn bad_input_files_and_values_are_refused_with_where_and_why() {
    let tmp = tempfile::tempdir().unwrap();
    #[cfg(unix)]
    {
        let out = flexprr()
            .args(["study", "--out"])
            .arg(tmp.path().join("x"))
            .arg("/dev/zero")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains("not a regular file"), "{stderr}");
    }
    let bad = tmp.path().join("bad.toml");
    let base = configs().join("paper_f20.toml").display().to_string();
    std::fs::write(
        &bad,
        format!("base = {base:?}\nquantities = [{{ kind = \"buckling\", link = 4 }}]\n"),
    )
    .unwrap();
    let out = flexprr()
        .args(["study", "--out"])
        .arg(tmp.path().join("x"))
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Line 2, column of `link` (found by searching the line).
    let column = "quantities = [{ kind = \"buckling\", link = 4 }]"
        .find("link")
        .unwrap()
        + 1;
    assert!(
        stderr.contains(&format!(
            "{}:2:{column}: quantities.0.link: link must be 1, 2 or 3",
            bad.display()
        )),
        "{stderr}"
    );
}
