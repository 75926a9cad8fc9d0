//! `occlude view`: a window that flies through a scene with any culling method
//! on the GPU (the wgpu backend), shows the frame's statistics, and can show
//! what the method asked the GPU: each query's boxes coloured by its answer
//! (the CHC paper's Figure 4), or the depth-pyramid level each of `hiz`'s
//! box tests read.
//!
//! The method renders into the backend's off-screen target exactly as in
//! `occlude bench` (`occlude_core::render_frame`); after the frame the
//! viewer draws the query boxes (`boxes`) and the statistics (`overlay`) over
//! that image and copies it to the window (`present`). Query boxes and their
//! results are caught by `occlude_core::recording::RecordingBackend`, an
//! [`occlude_core::Backend`] wrapper, so no method knows it is being watched.
//! The window and its event loop are in `app`; the fly camera and walkthrough
//! playback in `camera_control`; key bindings in `input`; recording a
//! fly-through as a camera path for `bench --camera-path` in
//! `path_recorder`.

mod app;
mod boxes;
mod camera_control;
mod input;
mod overlay;
mod path_recorder;
mod present;

use anyhow::{bail, Result};
use occlude_bench::BenchConfig;
use occlude_core::methods::{create, METHOD_NAMES};
use std::path::PathBuf;

/// Method `occlude view` starts with.
pub const DEFAULT_METHOD: &str = "chcpp";

/// Where a recorded camera path goes unless `--record` names a file.
pub const DEFAULT_RECORD_FILE: &str = "camera-path.json";

/// Why the viewer cannot start: the machine has no display to open a window
/// on. The command line treats it as bad input (exit code 2), as it does a
/// missing GPU adapter.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No window can be opened (no `DISPLAY` or `WAYLAND_DISPLAY`, or the
    /// display refused the connection).
    #[error(
        "cannot open a window ({0}). occlude view needs a desktop session (DISPLAY or WAYLAND_DISPLAY); \
         without one, run it under a virtual X server: xvfb-run -a occlude view ..."
    )]
    NoDisplay(String),
}

/// What `occlude view` is asked to show, checked before any window opens.
#[derive(Clone, Debug)]
pub struct ViewConfig {
    /// Scene, size, seed, hierarchy, method parameters and camera path as
    /// `bench` reads them; `resolution` is the window size and `frames` the
    /// frames rendered before a `--screenshot`. Its `methods` are ignored.
    pub scene: BenchConfig,
    /// The method shown first (keys switch to the others).
    pub method: String,
    /// Play the scene's walkthrough from the start (`--play`).
    pub play: bool,
    /// Show the query boxes from the first frame on (`--figure4`; key V).
    pub figure4: bool,
    /// Show the box tests' boxes coloured by the depth-pyramid level each
    /// was tested at from the first frame on (`--pyramid-levels`; key Z).
    pub pyramid_levels: bool,
    /// Render `scene.frames` frames, save the last as this PNG and exit.
    pub screenshot: Option<PathBuf>,
    /// Where key R writes the recorded camera path.
    pub record: PathBuf,
}

impl ViewConfig {
    /// Rejects what cannot be shown, with the same messages as `bench`:
    /// every method's parameters are checked (keys switch between all of
    /// them), then the starting method's name.
    pub fn validate(&self) -> Result<()> {
        let every_method = BenchConfig { methods: METHOD_NAMES.map(String::from).to_vec(), ..self.scene.clone() };
        every_method.validate()?;
        create(&self.method, &self.scene.options)?;
        if let Some(path) = &self.screenshot {
            let png = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
            if !png {
                bail!("--screenshot {}: the screenshot is written as PNG, name a .png file", path.display());
            }
        }
        Ok(())
    }
}

/// Opens the window and runs the viewer until it is closed (or, with a
/// screenshot, until the screenshot is written). Fails with [`ViewError`]
/// without a display, with `occlude_wgpu::GpuError::NoAdapter` without a
/// GPU, and with `occlude_scenes::LoadError` for a model that cannot be
/// imported. Check `config` with [`ViewConfig::validate`] first: a bad
/// method or parameter is otherwise found only once the window is open.
pub fn run(config: &ViewConfig) -> Result<()> {
    app::run(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> ViewConfig {
        ViewConfig {
            scene: BenchConfig::default(),
            method: DEFAULT_METHOD.into(),
            play: false,
            figure4: false,
            pyramid_levels: false,
            screenshot: None,
            record: DEFAULT_RECORD_FILE.into(),
        }
    }

    #[test]
    fn validation_names_the_bad_value() {
        config().validate().unwrap();
        let unknown = ViewConfig { method: "magic".into(), ..config() };
        assert!(unknown.validate().unwrap_err().to_string().contains("unknown method 'magic'"));
        let jpeg = ViewConfig { screenshot: Some("shot.jpg".into()), ..config() };
        assert!(jpeg.validate().unwrap_err().to_string().contains("shot.jpg"));
        let mut other = config();
        // A parameter of a method other than the first one shown is fine:
        // keys switch to it.
        other.scene.options = occlude_core::methods::MethodOptions::parse(&["chc.tav=2"]).unwrap();
        other.validate().unwrap();
        other.scene.options = occlude_core::methods::MethodOptions::parse(&["chc.nope=2"]).unwrap();
        assert!(other.validate().unwrap_err().to_string().contains("nope"));
    }
}
