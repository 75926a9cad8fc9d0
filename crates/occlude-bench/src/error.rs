//! Why a benchmark could not run: each kind its own variant, so that a
//! caller tells its user's input (a model file, a walkthrough, a GPU it
//! lacks) from a failure of the run.

use occlude_core::item_buffer::ItemBufferError;
use occlude_core::methods::{MethodError, OptionError, Unsupported};
use occlude_core::{GpuCullingUnsupported, MotionError, SceneError};
use occlude_scenes::{GenerateError, LoadError};
use occlude_wgpu::GpuError;

/// The result of the harness's fallible calls.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why a run, an experiment or a measurement failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input that cannot be used: a configuration out of range, options
    /// that cannot be combined, a camera path that is not one. The message
    /// names what to change.
    #[error("{0}")]
    Invalid(String),
    /// The scene could not be generated or imported.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// A built-in scene could not be generated.
    #[error(transparent)]
    Generate(#[from] GenerateError),
    /// The scene cannot be rendered.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene's motion could not be applied.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The walkthrough cannot be run as asked.
    #[error(transparent)]
    Walkthrough(#[from] crate::camera_path::UnusableWalkthrough),
    /// A method could not be built.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// A method option names another method or a key the method lacks.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// A method needs something the backend lacks.
    #[error(transparent)]
    Unsupported(#[from] Unsupported),
    /// The adapter cannot run GPU-driven culling.
    #[error(transparent)]
    GpuCulling(#[from] GpuCullingUnsupported),
    /// The item buffer's layout does not fit the scene.
    #[error(transparent)]
    ItemBuffer(#[from] ItemBufferError),
    /// The masked occlusion buffer could not be made.
    #[error(transparent)]
    Moc(#[from] occlude_moc::Error),
    /// No GPU could be opened, or the scene could not be uploaded to it.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A backend failed while drawing or measuring, or measured something
    /// that cannot be used.
    #[error("{0}")]
    Backend(String),
    /// The run's figures break the rule of [`crate::figures`]: `at` (a place
    /// in the report, `methods[1].per_frame[3].gpu_ms`) is not a finite
    /// number within ±[`crate::figures::MAX_FIGURE`].
    #[error(
        "the run's figures are not finite numbers within ±{max:e} ({at} is not): a GPU model's costs or the \
         walkthrough are out of proportion",
        max = crate::figures::MAX_FIGURE
    )]
    Figures {
        /// The place of the first figure out of range.
        at: String,
    },
    /// A file could not be read or written.
    #[error("{context}")]
    Io {
        /// What was being done, naming the file.
        context: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A JSON document could not be read or written.
    #[error("{context}")]
    Json {
        /// What was being read or written.
        context: String,
        /// The cause.
        source: serde_json::Error,
    },
    /// The GPU model could not be written as TOML.
    #[error("cannot write the GPU model as TOML")]
    Toml(#[source] toml::ser::Error),
    /// A thread pool could not be started.
    #[error("cannot start the thread pool")]
    ThreadPool(#[source] rayon::ThreadPoolBuildError),
    /// `source`, with what it happened to (a scene, a method).
    #[error("{context}")]
    Context {
        /// What failed.
        context: String,
        /// Why.
        source: Box<Error>,
    },
}

impl Error {
    /// The error under every [`Error::Context`] around it.
    pub fn innermost(&self) -> &Error {
        match self {
            Self::Context { source, .. } => source.innermost(),
            e => e,
        }
    }

    /// `self` with `context` (what it happened to) around it.
    pub(crate) fn context(self, context: String) -> Self {
        Self::Context { context, source: Box::new(self) }
    }
}

/// [`Error::context`] on a result.
pub(crate) trait ResultExt<T> {
    /// The error with `context()` around it.
    fn context(self, context: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<Error>> ResultExt<T> for std::result::Result<T, E> {
    fn context(self, context: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| e.into().context(context()))
    }
}

/// Returns an [`Error::Invalid`] with the message `format!` makes of the
/// arguments.
macro_rules! invalid {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Invalid(format!($($arg)*)))
    };
}
pub(crate) use invalid;
