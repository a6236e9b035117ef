//! Every command leaves every input file and every foreign file untouched, and writes
//! nothing outside its output: the whole working tree is hashed before and after each
//! command, succeeding or refused, and compared file by file.

use crate::common::{TINY, configs, flexprr, tree};
use std::path::Path;

/// One command: its arguments (run in `dir`, relative to the work tree), the paths it may
/// write (prefixes relative to the work tree), the files that must stay even inside those,
/// and its expected exit code.
struct Step<'a> {
    dir: &'a str,
    args: Vec<&'a str>,
    outputs: Vec<&'a str>,
    kept: Vec<&'a str>,
    code: i32,
}

fn step<'a>(args: &[&'a str], outputs: &[&'a str], code: i32) -> Step<'a> {
    Step {
        dir: "",
        args: args.to_vec(),
        outputs: outputs.to_vec(),
        kept: Vec::new(),
        code,
    }
}

const STUDY: &str = r#"name = "sweep"
base = "scene.toml"
quantities = [{ kind = "frequency_range", link = 1, mode = 1 }]
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0, 15.0]
[[plot]]
file = "f.svg"
x = "trajectory.frequency"
y = ["f_min_1_1_Hz"]
"#;

const SEARCH: &str = r#"base = "scene.toml"
[search]
key = "trajectory.frequency"
low = 5.0
high = 40.0
tolerance = 5.0
time = 0.05
"#;

/// The work tree: inputs, files of the user's own (some with the names of outputs), and an
/// empty directory to run in.
fn work_tree(root: &Path) {
    let files = [
        ("scene.toml", TINY.to_string()),
        ("d/scene.toml", TINY.to_string()),
        ("d/notes.txt", "mine".to_string()),
        ("study.toml", STUDY.to_string()),
        ("search.toml", SEARCH.to_string()),
        (
            "link.toml",
            std::fs::read_to_string(configs().join("link_paper.toml")).unwrap(),
        ),
        ("foreign/results.csv", "my table\n".to_string()),
        ("foreign/summary.json", "{\"mine\": true}\n".to_string()),
        ("foreign/reference.csv", "t_s\n".to_string()),
        ("notes/notes.txt", "mine".to_string()),
        ("data.csv", "a,b\n".to_string()),
        ("here/.keep", String::new()),
    ];
    for (name, text) in &files {
        let path = root.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    std::fs::remove_file(root.join("here/.keep")).unwrap();
}

/// The commands of runs, kinematics and beams, in order.
fn run_steps() -> Vec<Step<'static>> {
    vec![
        step(&["check", "scene.toml"], &[], 0),
        step(&["run", "scene.toml", "--out", "r", "--quiet"], &["r/"], 0),
        step(&["run", "scene.toml", "--out", "r", "--quiet"], &["r/"], 0),
        step(
            &["run", "scene.toml", "--out", "foreign", "--quiet"],
            &[],
            2,
        ),
        step(
            &[
                "run",
                "scene.toml",
                "--out",
                "foreign",
                "--quiet",
                "--force",
            ],
            &[],
            2,
        ),
        step(&["run", "scene.toml", "--out", "/", "--quiet"], &[], 2),
        step(&["run", "d/scene.toml", "--out", "d", "--quiet"], &[], 2),
        Step {
            kept: vec!["d/scene.toml", "d/notes.txt"],
            ..step(
                &["run", "d/scene.toml", "--out", "d", "--quiet", "--force"],
                &["d/"],
                0,
            )
        },
        Step {
            dir: "here",
            ..step(
                &["run", "../scene.toml", "--out", ".", "--quiet"],
                &["here/"],
                0,
            )
        },
        step(
            &["kinematics", "scene.toml", "--out", "scene.toml", "--force"],
            &[],
            2,
        ),
        step(&["kinematics", "scene.toml", "--out", "data.csv"], &[], 2),
        step(
            &["kinematics", "scene.toml", "--out", "k.csv"],
            &["k.csv"],
            0,
        ),
        step(
            &["kinematics", "scene.toml", "--out", "k.csv"],
            &["k.csv"],
            0,
        ),
        step(&["beam", "link.toml"], &[], 0),
    ]
}

/// The commands of studies, merges and work-precision, in order (later ones read what
/// earlier ones wrote: shards, references).
fn study_steps() -> Vec<Step<'static>> {
    let wp = |out: &'static str| -> Vec<&'static str> {
        vec![
            "work-precision",
            "scene.toml",
            "--repeats",
            "1",
            "--warmup",
            "0",
            "--methods",
            "abm",
            "--tolerances",
            "1e-4",
            "--out",
            out,
        ]
    };
    let mut steps = vec![
        step(
            &["study", "study.toml", "--out", "s", "--quiet"],
            &["s/"],
            0,
        ),
        step(
            &["study", "study.toml", "--out", "s", "--quiet", "--resume"],
            &["s/"],
            0,
        ),
        step(
            &[
                "study",
                "study.toml",
                "--out",
                "foreign",
                "--quiet",
                "--force",
            ],
            &[],
            2,
        ),
        step(
            &["study", "study.toml", "--out", "study.toml", "--force"],
            &[],
            2,
        ),
        step(
            &[
                "study",
                "study.toml",
                "--out",
                "s1",
                "--shard",
                "1/2",
                "--quiet",
            ],
            &["s1/"],
            0,
        ),
        step(
            &[
                "study",
                "study.toml",
                "--out",
                "s2",
                "--shard",
                "2/2",
                "--quiet",
            ],
            &["s2/"],
            0,
        ),
        step(&["merge", "s1", "s2", "--out", "m"], &["m/"], 0),
        step(&["merge", "s1", "s2", "--out", "m"], &["m/"], 0),
        step(&["merge", "s1", "s2", "--out", "s1", "--force"], &[], 2),
        step(
            &["merge", "s1", "s2", "--out", "foreign", "--force"],
            &[],
            2,
        ),
        Step {
            kept: vec!["notes/notes.txt"],
            ..step(
                &["merge", "s1", "s2", "--out", "notes", "--force"],
                &["notes/"],
                0,
            )
        },
        step(
            &["study", "search.toml", "--out", "q", "--quiet"],
            &["q/"],
            0,
        ),
        step(
            &["study", "search.toml", "--out", "q", "--quiet"],
            &["q/"],
            0,
        ),
        step(&wp("w"), &["w/"], 0),
        step(&wp("foreign"), &[], 2),
        step(&[&wp("foreign")[..], &["--force"]].concat(), &[], 2),
    ];
    // Work-precision reads its own earlier reference from a copy, never from where it writes.
    steps.push(step(
        &[&wp("w")[..], &["--reference", "w/reference.csv"]].concat(),
        &[],
        2,
    ));
    steps
}

#[test]
fn no_command_touches_an_input_or_a_foreign_file() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("work");
    std::fs::create_dir(&root).unwrap();
    work_tree(&root);
    let steps: Vec<Step> = run_steps().into_iter().chain(study_steps()).collect();
    for s in &steps {
        let before = tree(&root);
        let output = flexprr()
            .current_dir(root.join(s.dir))
            .args(&s.args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(s.code), "{:?}: {stderr}", s.args);
        let after = tree(&root);
        let may_change = |name: &str| {
            s.outputs
                .iter()
                .any(|o| name.starts_with(o) || format!("{name}/") == *o)
                && !s.kept.contains(&name)
        };
        for (name, content) in &before {
            if !may_change(name) {
                assert!(
                    after.get(name) == Some(content),
                    "{:?} changed or removed {name}",
                    s.args
                );
            }
        }
        for name in after.keys().filter(|n| !before.contains_key(*n)) {
            assert!(may_change(name), "{:?} wrote {name}", s.args);
        }
        // Nothing beside the work tree.
        let beside: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert_eq!(beside.len(), 1, "{:?} wrote beside the work tree", s.args);
    }
}
