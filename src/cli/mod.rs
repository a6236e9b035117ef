//! One module per subcommand. Each returns `Result<(), Failure>`; `main` prints the
//! one-line reason and exits with its code.

pub mod beam;
pub mod frf;
pub mod kinematics;
pub mod map;
pub mod modes;
pub mod run;
pub mod statespace;
pub mod study;
pub mod work_precision;

/// Exit code for bad input (scene file, arguments).
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that started but failed.
pub const EXIT_RUN_FAILURE: u8 = 1;

/// A failed command: the one-line reason and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// Exit code: [`EXIT_BAD_INPUT`] or [`EXIT_RUN_FAILURE`].
    pub code: u8,
    /// One-line reason.
    pub message: String,
}

impl Failure {
    /// Bad input (exit code 2).
    pub fn bad_input(message: impl std::fmt::Display) -> Self {
        Self {
            code: EXIT_BAD_INPUT,
            message: one_line(message),
        }
    }
    /// Run failure (exit code 1).
    pub fn run(message: impl std::fmt::Display) -> Self {
        Self {
            code: EXIT_RUN_FAILURE,
            message: one_line(message),
        }
    }
}

fn one_line(message: impl std::fmt::Display) -> String {
    message
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}
