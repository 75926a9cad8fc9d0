//! The progress bar of the long-running commands (`bench`, `raster-bench`),
//! on standard error and hidden when that is not a terminal.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps named `unit` ("frames", "rows"), with the elapsed
/// time and an estimate of the time left.
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let template = format!("{{msg}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})");
    ProgressBar::new(len)
        .with_style(ProgressStyle::with_template(&template).expect("valid template").progress_chars("=> "))
}
