//! The output-directory policy (`flexprr_outdir`, docs/scenes.md "Output
//! directory and run status"), checked on the file system: what is refused, what is kept,
//! what is replaced, and that an input or a foreign file is never overwritten or deleted.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use flexprr_outdir::{
    MARKER, OutputDir, OutputError, Products, check_output_file, write_file_atomic,
};

const PRODUCTS: Products = Products {
    kind: "test",
    names: Cow::Borrowed(&["a.csv", "b.csv", "summary.json"]),
    patterns: Cow::Borrowed(&[("plot_", ".svg")]),
    legacy: Some(flexprr_outdir::Legacy::JsonKey {
        file: "summary.json",
        key: "flexprr_version",
    }),
};

/// Every file under `dir` with its contents (directories as `/`).
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            let name = path.strip_prefix(dir).unwrap().display().to_string();
            if path.is_dir() {
                out.insert(format!("{name}/"), Vec::new());
                stack.push(path);
            } else {
                out.insert(name, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// Publishes `files` (name, text) into `dir` through a staging directory.
fn publish(dir: &OutputDir, files: &[(&str, &str)]) -> Result<Vec<String>, OutputError> {
    let staging = dir.stage()?;
    for (name, text) in files {
        std::fs::write(staging.path().join(name), text).unwrap();
    }
    staging.publish()
}

fn refused(result: Result<OutputDir, OutputError>) -> String {
    match result {
        Err(e @ OutputError::Refused { .. }) => e.to_string(),
        Err(e) => panic!("not a refusal: {e}"),
        Ok(_) => panic!("accepted"),
    }
}

fn marker_files(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join(MARKER)).unwrap();
    let marker: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(marker["kind"], "test");
    marker["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_new_directory_is_published_whole_and_marked() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("new/out");
    let dir = OutputDir::check(&out, PRODUCTS, false, &[], &[]).unwrap();
    publish(&dir, &[("a.csv", "1"), ("b.csv", "2")]).unwrap();
    assert_eq!(marker_files(&out), ["a.csv", "b.csv"]);
    // A staging directory abandoned by a killed process (no process has this id: Linux ids
    // stay below 2^22) is removed by the next output of the same name.
    let abandoned = tmp.path().join("new/.flexprr-staging-999999999-out");
    std::fs::create_dir_all(abandoned.join("half")).unwrap();
    let dir = OutputDir::check(&out, PRODUCTS, false, &[], &[]).unwrap();
    publish(&dir, &[("a.csv", "1")]).unwrap();
    #[cfg(target_os = "linux")]
    assert!(!abandoned.exists());
    // Nothing is left beside it: the staging directory was renamed.
    let parent: Vec<_> = std::fs::read_dir(tmp.path().join("new")).unwrap().collect();
    assert_eq!(parent.len(), 1);
}

#[test]
fn a_second_output_replaces_the_first_and_keeps_foreign_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let check = || OutputDir::check(&out, PRODUCTS, false, &[], &[]).unwrap();
    publish(&check(), &[("a.csv", "1"), ("b.csv", "2")]).unwrap();
    // Only its own files: replaced whole, so b.csv of the first output is gone.
    publish(&check(), &[("a.csv", "3")]).unwrap();
    assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "3");
    assert!(!out.join("b.csv").exists());
    // A file the user added is kept; the stale output file is removed.
    publish(&check(), &[("a.csv", "4"), ("b.csv", "5")]).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    publish(&check(), &[("a.csv", "6")]).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert!(!out.join("b.csv").exists());
    assert_eq!(marker_files(&out), ["a.csv"]);
}

#[test]
fn a_foreign_directory_needs_force_and_keeps_every_file() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "keep").unwrap();
    let before = tree(&out);
    let message = refused(OutputDir::check(&out, PRODUCTS, false, &[], &[]));
    assert!(message.contains("--force"), "{message}");
    assert_eq!(tree(&out), before);
    let dir = OutputDir::check(&out, PRODUCTS, true, &[], &[]).unwrap();
    publish(&dir, &[("a.csv", "1")]).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "keep"
    );
    // A foreign file with an output's name is refused, even forced, before any work.
    let clash = tmp.path().join("clash");
    std::fs::create_dir(&clash).unwrap();
    std::fs::write(clash.join("summary.json"), "{\"mine\": true}").unwrap();
    std::fs::write(clash.join("plot_x.svg"), "<svg/>").unwrap();
    let before = tree(&clash);
    let message = refused(OutputDir::check(&clash, PRODUCTS, true, &[], &[]));
    assert!(message.contains("plot_x.svg, summary.json"), "{message}");
    // An expected name (a study's plot file) counts as an output too.
    std::fs::remove_file(clash.join("summary.json")).unwrap();
    std::fs::write(clash.join("speed.svg"), "<svg/>").unwrap();
    let message = refused(OutputDir::check(
        &clash,
        PRODUCTS,
        true,
        &[],
        &["speed.svg"],
    ));
    assert!(message.contains("speed.svg"), "{message}");
    std::fs::write(clash.join("summary.json"), "{\"mine\": true}").unwrap();
    assert_eq!(tree(&clash).len(), before.len() + 1);
}

#[test]
fn inputs_are_never_overwritten_or_deleted() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("d");
    std::fs::create_dir(&d).unwrap();
    let scene = d.join("scene.toml");
    std::fs::write(&scene, "x").unwrap();
    // The directory holding the input is written into, forced, and the input stays.
    let dir = OutputDir::check(&d, PRODUCTS, true, &[&scene], &[]).unwrap();
    publish(&dir, &[("a.csv", "1")]).unwrap();
    let dir = OutputDir::check(&d, PRODUCTS, false, &[&scene], &[]).unwrap();
    publish(&dir, &[("b.csv", "2")]).unwrap();
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), "x");
    assert!(!d.join("a.csv").exists());
    // The output directory is an input: refused even forced.
    let message = refused(OutputDir::check(&d, PRODUCTS, true, &[&d], &[]));
    assert!(message.contains("input"), "{message}");
    // An input with an output's name in the directory: refused even forced.
    let named = d.join("a.csv");
    std::fs::write(&named, "input").unwrap();
    let message = refused(OutputDir::check(&d, PRODUCTS, true, &[&named], &[]));
    assert!(message.contains("input"), "{message}");
    assert_eq!(std::fs::read_to_string(&named).unwrap(), "input");
}

#[test]
fn root_files_other_kinds_and_broken_parents_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    refused(OutputDir::check(Path::new("/"), PRODUCTS, true, &[], &[]));
    refused(OutputDir::check(Path::new(""), PRODUCTS, true, &[], &[]));
    let file = tmp.path().join("f");
    std::fs::write(&file, "x").unwrap();
    refused(OutputDir::check(&file, PRODUCTS, true, &[], &[]));
    refused(OutputDir::check(
        &file.join("below"),
        PRODUCTS,
        true,
        &[],
        &[],
    ));
    let other = tmp.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(
        other.join(MARKER),
        r#"{"kind": "run", "files": ["summary.json"]}"#,
    )
    .unwrap();
    let message = refused(OutputDir::check(&other, PRODUCTS, true, &[], &[]));
    assert!(message.contains("flexprr run"), "{message}");
}

#[test]
fn an_output_written_before_markers_is_recognised_by_its_manifest() {
    let tmp = tempfile::tempdir().unwrap();
    let old = tmp.path().join("old");
    std::fs::create_dir(&old).unwrap();
    std::fs::write(old.join("summary.json"), r#"{"flexprr_version": "0.0.1"}"#).unwrap();
    std::fs::write(old.join("b.csv"), "old").unwrap();
    std::fs::write(old.join("notes.txt"), "mine").unwrap();
    let dir = OutputDir::check(&old, PRODUCTS, false, &[], &[]).unwrap();
    publish(&dir, &[("a.csv", "1"), ("summary.json", "{}")]).unwrap();
    assert!(!old.join("b.csv").exists(), "a stale output of the old run");
    assert_eq!(
        std::fs::read_to_string(old.join("notes.txt")).unwrap(),
        "mine"
    );
    // A summary.json of someone else is not a manifest: the directory is foreign.
    let other = tmp.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("summary.json"), r#"{"mine": 1}"#).unwrap();
    refused(OutputDir::check(&other, PRODUCTS, false, &[], &[]));
}

/// The current directory cannot be renamed: it is written in place, and nothing is left in
/// a hidden directory beside it. (The other tests use absolute paths, so changing the
/// directory here does not disturb them.)
#[test]
fn the_current_directory_is_written_in_place() {
    let tmp = tempfile::tempdir().unwrap();
    let here = tmp.path().join("here");
    std::fs::create_dir(&here).unwrap();
    let previous = std::env::current_dir().unwrap();
    std::env::set_current_dir(&here).unwrap();
    let outcome = (|| {
        let dir = OutputDir::check(Path::new("."), PRODUCTS, false, &[], &[])?;
        publish(&dir, &[("a.csv", "1"), ("b.csv", "2")])?;
        // What a killed process left inside is removed by the next output.
        std::fs::create_dir_all(".flexprr-staging-999999999/half").unwrap();
        let dir = OutputDir::check(Path::new("."), PRODUCTS, false, &[], &[])?;
        publish(&dir, &[("a.csv", "3")])
    })();
    std::env::set_current_dir(previous).unwrap();
    outcome.unwrap();
    let files: Vec<String> = tree(&here).into_keys().collect();
    #[cfg(target_os = "linux")]
    assert_eq!(files, [MARKER, "a.csv"]);
    let beside: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
    assert_eq!(beside.len(), 1, "a hidden staging directory was left");
}

#[test]
fn a_single_output_file_never_replaces_an_input_or_a_foreign_file() {
    let tmp = tempfile::tempdir().unwrap();
    let ours = |head: &str| head.starts_with("t_s,");
    let scene = tmp.path().join("scene.toml");
    std::fs::write(&scene, "x").unwrap();
    assert!(check_output_file(&scene, true, &[&scene], ours).is_err());
    let link = tmp.path().join("link.csv");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&scene, &link).unwrap();
        assert!(check_output_file(&link, true, &[&scene], ours).is_err());
        std::fs::remove_file(&link).unwrap();
    }
    let foreign = tmp.path().join("data.csv");
    std::fs::write(&foreign, "a,b\n").unwrap();
    assert!(check_output_file(&foreign, false, &[&scene], ours).is_err());
    assert!(check_output_file(&foreign, true, &[&scene], ours).is_ok());
    let mine = tmp.path().join("k.csv");
    std::fs::write(&mine, "t_s,x_m\n").unwrap();
    let path = check_output_file(&mine, false, &[&scene], ours).unwrap();
    write_file_atomic(&path, b"t_s,x_m\n0,0\n").unwrap();
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "t_s,x_m\n0,0\n");
    assert!(check_output_file(tmp.path(), true, &[], ours).is_err());
    assert!(check_output_file(Path::new("/dev/null"), true, &[], ours).is_err());
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), "x");
}
