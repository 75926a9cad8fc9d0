//! How a long run reports where it is: the steps of a walkthrough or a
//! table as they finish, and the stages before the first (loading, building,
//! uploading). The command line draws a progress bar; a caller that wants
//! none passes `&()`.

/// Where a run is, told as it goes. Every method does nothing by default.
pub trait Progress: Sync {
    /// Names the work under way ("city small: vfc, chc").
    fn message(&self, _text: &str) {}

    /// Starts counting `total` steps from none done.
    fn start(&self, _total: u64) {}

    /// Adds `n` steps to the total.
    fn add_steps(&self, _n: u64) {}

    /// Counts `n` more steps done.
    fn advance(&self, _n: u64) {}

    /// Shows `line` (a warning) to the user now, beside the progress.
    fn println(&self, _line: &str) {}

    /// Runs `work`, a stage before the first step that may take seconds,
    /// with `what` ("building the bvh") shown while it runs.
    fn stage(&self, _what: &str, work: &mut dyn FnMut()) {
        work()
    }
}

/// No progress shown.
impl Progress for () {}

/// [`Progress::stage`] for work that returns a value.
pub fn stage<T>(progress: &dyn Progress, what: &str, work: impl FnOnce() -> T) -> T {
    let (mut work, mut result) = (Some(work), None);
    progress.stage(what, &mut || result = work.take().map(|w| w()));
    result.expect("a stage runs its work once")
}
