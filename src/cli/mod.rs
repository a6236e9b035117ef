//! One module per subcommand. Each returns `Result<(), Failure>`; `main` prints the
//! one-line reason and exits with its code.

pub mod beam;
pub mod frf;
pub mod kinematics;
pub mod map;
pub mod margins;
pub mod modes;
pub mod plan;
pub mod progress;
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

/// `value` rounded to `digits` significant digits and written in the shortest form that
/// reads back as that: plain between 1e-3 and 1e7, scientific outside.
pub fn short(value: f64, digits: usize) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let rounded: f64 = format!("{value:.prec$e}", prec = digits.max(1) - 1)
        .parse()
        .unwrap_or(value);
    if (1e-3..1e7).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

fn one_line(message: impl std::fmt::Display) -> String {
    message
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}
