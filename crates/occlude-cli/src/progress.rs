//! The progress bar of the long-running commands (`bench`, `calibrate`,
//! `raster-bench`) on standard error: the harness's [`Progress`] drawn with
//! indicatif. Where that is not a terminal (a log file, CI) the bar
//! is not drawn; a line of its state is written every minute
//! instead, so that a run of an hour still shows where it is.

use indicatif::{HumanDuration, ProgressBar, ProgressStyle};
use occlude_bench::Progress;
use std::io::IsTerminal;
use std::time::Duration;

/// How often a bar is redrawn while a [`Progress::stage`] runs.
const STAGE_TICK: Duration = Duration::from_millis(250);

/// How often a bar that is not drawn writes its state as a line.
const LOG_EVERY: Duration = Duration::from_secs(60);

/// A command's progress bar.
pub struct Bar(ProgressBar);

/// A bar of `len` steps named `unit` ("frames", "rows"), with the elapsed
/// time and an estimate of the time left.
pub fn bar(len: u64, unit: &str) -> Bar {
    let template = format!("{{msg}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})");
    let bar = ProgressBar::new(len)
        .with_style(ProgressStyle::with_template(&template).expect("valid template").progress_chars("=> "));
    if !std::io::stderr().is_terminal() {
        log_lines(&bar, unit);
    }
    Bar(bar)
}

impl Bar {
    /// A spinner with its message, for work of no known length.
    pub fn spinner() -> Self {
        let bar = ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(200));
        Bar(bar)
    }

    /// Removes the bar from the terminal once the work is done.
    pub fn finish_and_clear(&self) {
        self.0.finish_and_clear();
    }
}

impl Progress for Bar {
    fn message(&self, text: &str) {
        self.0.set_message(text.to_string());
    }

    fn start(&self, total: u64) {
        self.0.set_length(total);
        self.0.set_position(0);
    }

    fn add_steps(&self, n: u64) {
        self.0.inc_length(n);
    }

    fn advance(&self, n: u64) {
        self.0.inc(n);
    }

    /// Writes `line` to standard error above the bar, or on its own where
    /// the bar is not drawn (indicatif drops what is printed through a
    /// hidden bar).
    fn println(&self, line: &str) {
        if self.0.is_hidden() {
            eprintln!("{line}");
        } else {
            self.0.println(line);
        }
    }

    /// Runs `work` with `what` ("generating swarm", "building the bvh")
    /// after the bar's message and the elapsed time ticking, then puts the
    /// message back: the steps before the first frame, which take seconds
    /// on a scene of a million instances, so that the bar shows what the
    /// run is doing.
    fn stage(&self, what: &str, work: &mut dyn FnMut()) {
        let bar = &self.0;
        let message = bar.message();
        bar.set_message(if message.is_empty() { what.to_string() } else { format!("{message}: {what}") });
        bar.enable_steady_tick(STAGE_TICK);
        work();
        bar.disable_steady_tick();
        bar.set_message(message);
    }
}

/// Starts a thread that writes `bar`'s state to standard error every
/// [`LOG_EVERY`] while it moves, and ends once the bar is finished or
/// dropped.
fn log_lines(bar: &ProgressBar, unit: &str) {
    let weak = bar.downgrade();
    let mut log = LogLines::new(unit);
    std::thread::spawn(move || loop {
        std::thread::sleep(LOG_EVERY);
        let Some(bar) = weak.upgrade() else { return };
        if bar.is_finished() {
            return;
        }
        if let Some(line) = log.line(&bar) {
            eprintln!("{line}");
        }
    });
}

/// The lines of a bar that is not drawn: one only when the bar moved (its
/// position, length or message changed) since the last, so that a long
/// stage does not repeat itself.
struct LogLines {
    unit: String,
    last: Option<(u64, Option<u64>, String)>,
}

impl LogLines {
    fn new(unit: &str) -> Self {
        Self { unit: unit.to_string(), last: None }
    }

    /// `bar`'s state as a line, or `None` when it has not moved.
    fn line(&mut self, bar: &ProgressBar) -> Option<String> {
        let state = (bar.position(), bar.length(), bar.message());
        if self.last.as_ref() == Some(&state) {
            return None;
        }
        let (pos, len, message) = state.clone();
        self.last = Some(state);
        let elapsed = HumanDuration(bar.elapsed());
        Some(match len {
            Some(len) if len > 0 => {
                format!("{message}: {pos}/{len} {}, {elapsed} (eta {})", self.unit, HumanDuration(bar.eta()))
            }
            _ => format!("{message}: {elapsed}"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use occlude_bench::progress::stage;

    #[test]
    fn a_stage_shows_its_name_and_puts_the_message_back() {
        let bar = bar(0, "frames");
        bar.message("swarm paper: hiz");
        let seen = stage(&bar, "building the bvh", || bar.0.message());
        assert_eq!(seen, "swarm paper: hiz: building the bvh");
        assert_eq!(bar.0.message(), "swarm paper: hiz");
        let plain = Bar(ProgressBar::hidden());
        assert_eq!(stage(&plain, "generating", || plain.0.message()), "generating");
        assert_eq!(plain.0.message(), "");
    }

    #[test]
    fn a_bar_that_is_not_drawn_logs_a_line_only_when_it_moved() {
        let bar = ProgressBar::hidden();
        bar.set_length(10);
        bar.set_message("city paper");
        let mut log = LogLines::new("frames");
        let first = log.line(&bar).expect("a first line");
        assert!(first.starts_with("city paper: 0/10 frames, "), "{first}");
        assert_eq!(log.line(&bar), None);
        bar.inc(3);
        let moved = log.line(&bar).expect("a line after moving");
        assert!(moved.starts_with("city paper: 3/10 frames, "), "{moved}");
        assert!(moved.contains("(eta "), "{moved}");
        bar.set_length(0);
        bar.set_message("plant paper: building the kd-tree");
        let stage = log.line(&bar).expect("a line for a stage");
        assert!(stage.starts_with("plant paper: building the kd-tree: "), "{stage}");
        assert!(!stage.contains("frames"), "{stage}");
    }
}
