//! The `flexprr` program end to end, in one test binary: each module exercises one command
//! or concern (runs, studies, the linear tools, planning, bad input, the viewer in a browser)
//! through the built binary; the helpers every module shares are in [`common`].

mod common;

mod adversarial;
mod basics;
mod beam;
mod collapse;
mod control;
mod csv_format;
mod drive;
mod frf;
mod fuzz;
mod inputs_untouched;
mod map;
mod modes;
#[cfg(unix)]
mod pipe;
mod run_outputs;
mod run_progress;
mod statespace;
mod study;
mod viewer_browser;
mod work_precision;
