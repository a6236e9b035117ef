//! Progress of a long linear analysis on standard error: nothing during its first second;
//! then a line when it enters a new stage, and every two seconds within one (the share done
//! where the stage knows it). A background thread watches the clock, so a stage that takes
//! long is reported while it runs.

use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What the work is doing now.
#[derive(Debug, Clone, Default)]
struct State {
    stage: String,
    share: Option<f64>,
    done: bool,
}

/// Where the lines go.
type Sink = Box<dyn Fn(String) + Send>;

/// Reports the progress of one command's work (see the module documentation).
pub struct Progress {
    shared: Arc<(Mutex<State>, Condvar)>,
    watcher: Option<JoinHandle<()>>,
}

/// Silence before the first line.
const QUIET_START: Duration = Duration::from_secs(1);
/// Interval of the lines within one stage.
const REPEAT: Duration = Duration::from_secs(2);

impl Progress {
    /// Starts watching for the command `name` (`"modes"`, `"frf"`), lines on standard
    /// error after a second; `quiet` prints nothing.
    pub fn start(name: &str, quiet: bool) -> Self {
        if quiet {
            return Self {
                shared: Arc::new((Mutex::new(State::default()), Condvar::new())),
                watcher: None,
            };
        }
        Self::start_with(name, QUIET_START, Box::new(|line| eprintln!("{line}")))
    }

    /// Starts watching, the first line after `quiet_start`, each line given to `sink`.
    pub fn start_with(name: &str, quiet_start: Duration, sink: Sink) -> Self {
        let shared = Arc::new((Mutex::new(State::default()), Condvar::new()));
        let watcher = {
            let shared = Arc::clone(&shared);
            let name = name.to_string();
            std::thread::spawn(move || watch(&name, &shared, quiet_start, &sink))
        };
        Self {
            shared,
            watcher: Some(watcher),
        }
    }

    /// The work entered `stage` (with the share done, when known).
    pub fn update(&self, stage: &str, share: Option<f64>) {
        let (lock, _) = &*self.shared;
        let mut state = lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if state.stage != stage {
            state.stage = stage.to_string();
        }
        state.share = share;
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        let (lock, wake) = &*self.shared;
        lock.lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .done = true;
        wake.notify_all();
        if let Some(watcher) = self.watcher.take() {
            let _ = watcher.join();
        }
    }
}

/// The watcher's loop: wakes every quarter second until the work is done.
fn watch(name: &str, shared: &(Mutex<State>, Condvar), quiet_start: Duration, sink: &Sink) {
    let (lock, wake) = shared;
    let start = Instant::now();
    let mut printed: Option<(String, Instant)> = None;
    let mut state = lock
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    loop {
        let (next, _) = wake
            .wait_timeout(state, Duration::from_millis(250))
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        state = next;
        if state.done {
            return;
        }
        let elapsed = start.elapsed();
        if elapsed < quiet_start || state.stage.is_empty() {
            continue;
        }
        let due = match &printed {
            None => true,
            Some((stage, at)) => *stage != state.stage || at.elapsed() >= REPEAT,
        };
        if due {
            let share = state
                .share
                .map(|s| format!(" {:.0} %", 100.0 * s))
                .unwrap_or_default();
            sink(format!(
                "{name}: {}{share} ({:.1} s so far)",
                state.stage,
                elapsed.as_secs_f64()
            ));
            printed = Some((state.stage.clone(), Instant::now()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;

    /// Issue 34, item 4: a stage that lasts is reported while it runs (here without the
    /// first second's silence), with its share; nothing is reported during the silence.
    #[test]
    fn a_long_stage_is_reported_while_it_runs() {
        let (send, receive) = mpsc::channel();
        let sink = Mutex::new(send);
        let progress = Progress::start_with(
            "frf",
            Duration::ZERO,
            Box::new(move |line| {
                let _ = sink.lock().map(|s| s.send(line));
            }),
        );
        progress.update("responses", Some(0.37));
        let line = receive.recv_timeout(Duration::from_secs(600)).unwrap();
        assert!(line.starts_with("frf: responses 37 % ("), "{line}");
        drop(progress);
        let (send, receive) = mpsc::channel();
        let sink = Mutex::new(send);
        let quiet = Progress::start_with(
            "modes",
            Duration::from_secs(3600),
            Box::new(move |line| {
                let _ = sink.lock().map(|s| s.send(line));
            }),
        );
        quiet.update("eigenvalues", None);
        drop(quiet);
        assert!(receive.try_recv().is_err());
    }
}
