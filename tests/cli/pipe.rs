//! A reader that stops early (`flexprr kinematics scene.toml | head`) ends the program
//! quietly, as it ends `cat`: no `error: Broken pipe`, no panic on stdout or stderr.

use std::io::Read;
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, Stdio};

/// Starts `flexprr args`, reads the first line of its stdout, closes the pipe and returns
/// the exit status and everything written to stderr.
fn read_one_line_then_close(args: &[&str]) -> (std::process::ExitStatus, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("flexprr starts");
    let mut stdout = child.stdout.take().expect("stdout is piped");
    let mut first = Vec::new();
    let mut byte = [0u8; 1];
    while stdout.read(&mut byte).expect("stdout is readable") == 1 && byte[0] != b'\n' {
        first.push(byte[0]);
    }
    assert!(!first.is_empty(), "nothing on stdout for {args:?}");
    drop(stdout);
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr is piped")
        .read_to_string(&mut stderr)
        .expect("stderr is readable");
    (child.wait().expect("flexprr ends"), stderr)
}

#[test]
fn kinematics_into_a_closed_pipe_ends_quietly() {
    // 2,001 rows of about 400 bytes: far more than a pipe buffer, so the pipe closes
    // while flexprr is still writing.
    let (status, stderr) = read_one_line_then_close(&["kinematics", "configs/paper_f20.toml"]);
    assert!(stderr.is_empty(), "stderr: {stderr}");
    // Either it finished before the reader left, or SIGPIPE ended it: never an error exit.
    assert!(
        status.success() || status.signal() == Some(13),
        "status {status:?}, stderr: {stderr}"
    );
}
