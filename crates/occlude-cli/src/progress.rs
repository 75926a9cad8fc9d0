//! The progress bar of the long-running commands (`bench`, `raster-bench`),
//! on standard error and hidden when that is not a terminal.

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// How often a bar is redrawn while a [`stage`] runs.
const STAGE_TICK: Duration = Duration::from_millis(250);

/// A bar of `len` steps named `unit` ("frames", "rows"), with the elapsed
/// time and an estimate of the time left.
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let template = format!("{{msg}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})");
    ProgressBar::new(len)
        .with_style(ProgressStyle::with_template(&template).expect("valid template").progress_chars("=> "))
}

/// Runs `work` with `what` ("generating swarm", "building the bvh") after
/// the bar's message and the elapsed time ticking, then puts the message
/// back: the steps before the first frame, which take seconds on a scene of
/// a million instances, so that the bar shows what the run is doing.
pub fn stage<T>(bar: &ProgressBar, what: &str, work: impl FnOnce() -> T) -> T {
    let message = bar.message();
    bar.set_message(if message.is_empty() { what.to_string() } else { format!("{message}: {what}") });
    bar.enable_steady_tick(STAGE_TICK);
    let result = work();
    bar.disable_steady_tick();
    bar.set_message(message);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_shows_its_name_and_puts_the_message_back() {
        let bar = bar(0, "frames");
        bar.set_message("swarm paper: hiz");
        let seen = stage(&bar, "building the bvh", || bar.message());
        assert_eq!(seen, "swarm paper: hiz: building the bvh");
        assert_eq!(bar.message(), "swarm paper: hiz");
        let plain = ProgressBar::hidden();
        assert_eq!(stage(&plain, "generating", || plain.message()), "generating");
        assert_eq!(plain.message(), "");
    }
}
