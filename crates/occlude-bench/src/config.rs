//! What a benchmark run is asked to do, checked before any work starts.

use crate::error::{invalid, Error, Result};
use crate::ideal::{IDEALS, SOURCE};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::{create, MethodOptions, METHOD_NAMES};
use occlude_core::{CameraPath, HierarchyKind, QueryMode, Sampling, UpdatePolicy};
use occlude_scenes::{ImportOptions, Size};
use occlude_soft::GpuModel;

/// Near clipping distance of every walkthrough camera, metres.
pub const NEAR_PLANE: f32 = 0.25;

/// Frame rate at which `occlude bench` samples a walkthrough unless told
/// otherwise (`--fps`).
pub const DEFAULT_FPS: f32 = 30.0;

/// Frames `occlude bench` renders unless told otherwise (`--frames`): the
/// first 10 s of the walkthrough at [`DEFAULT_FPS`]; a paper's run takes
/// the whole walkthrough.
pub const DEFAULT_FRAMES: usize = 300;

/// Image size of `occlude bench` unless told otherwise (`--resolution`).
pub const DEFAULT_RESOLUTION: (u32, u32) = (1024, 768);

/// [`BenchConfig::frames`] with a frame rate: every frame of the walkthrough
/// (`--frames all`).
pub const ALL_FRAMES: usize = usize::MAX;

/// Methods `occlude bench` compares when none are named.
pub const DEFAULT_METHODS: [&str; 4] = ["vfc", "sw", "chc", "opt"];

/// Which backend renders the frames and answers the queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BackendKind {
    /// The exact CPU rasterizer with the simulated GPU clock (deterministic).
    #[default]
    Soft,
    /// A real GPU through wgpu (measured, wall-clock times).
    Wgpu,
}

impl std::str::FromStr for BackendKind {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        match s {
            "soft" => Ok(Self::Soft),
            "wgpu" => Ok(Self::Wgpu),
            _ => Err(format!("unknown backend '{s}': expected 'soft' or 'wgpu'")),
        }
    }
}

impl std::fmt::Display for BackendKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Soft => "soft",
            Self::Wgpu => "wgpu",
        })
    }
}

/// A validated benchmark configuration.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Scene name (see `occlude scenes`) or model file (.gltf, .glb, .obj).
    pub scene: String,
    /// Scene size.
    pub size: Size,
    /// Seed of the procedural generator.
    pub seed: u64,
    /// Methods to compare, in table order.
    pub methods: Vec<String>,
    /// Frames of the walkthrough: with [`Self::fps`], the first this many
    /// ([`ALL_FRAMES`]: all of them); without, this many spread evenly over
    /// the whole walkthrough.
    pub frames: usize,
    /// The frame rate the walkthrough is sampled at, frames per second of
    /// walkthrough time (`None`: [`Self::frames`] spread over it).
    pub fps: Option<f32>,
    /// Image size in pixels.
    pub resolution: (u32, u32),
    /// Hierarchy builder.
    pub hierarchy: HierarchyKind,
    /// Hierarchy build options.
    pub build: BuildOptions,
    /// Backend that renders and answers queries.
    pub backend: BackendKind,
    /// How the backend counts occlusion queries' pixels (`--queries`).
    pub queries: QueryMode,
    /// Cost model of the simulated GPU (soft backend).
    pub gpu_model: GpuModel,
    /// Method parameters (`--method-opt method.key=value`).
    pub options: MethodOptions,
    /// How a model file is imported (`--split-triangles`, `--auto-path`).
    pub import: ImportOptions,
    /// A walkthrough replacing the scene's own (`--camera-path FILE`).
    pub camera_path: Option<CameraPath>,
    /// Frame (0-based) whose decisions the methods that can record them keep
    /// for [`crate::runner::FrameDump`] (`--dump-frame K`).
    pub dump_frame: Option<usize>,
    /// Whether the lanes of a frame (the `vfc` reference, each method and
    /// variant, each on its backend of its own) render side by side on the
    /// thread pool. Only the soft backend does: its figures are simulated,
    /// so they are the same either way (only `wall_ms` differs); the wgpu
    /// backend's lanes take turns, as they measure time on one GPU.
    pub parallel_lanes: bool,
    /// Share of the scene's instances that move (`--motion`, 0 to 1;
    /// `occlude_scenes::SceneMotion`): 0 is a still scene.
    pub motion: f64,
    /// When a moving scene's hierarchy is rebuilt rather than refitted
    /// (`--rebuild-ratio`).
    pub update_policy: UpdatePolicy,
}

impl Default for BenchConfig {
    fn default() -> Self {
        Self {
            scene: "city".into(),
            size: Size::Small,
            seed: 1,
            methods: DEFAULT_METHODS.iter().map(|s| s.to_string()).collect(),
            frames: DEFAULT_FRAMES,
            fps: None,
            resolution: DEFAULT_RESOLUTION,
            hierarchy: HierarchyKind::Bvh,
            build: BuildOptions::default(),
            backend: BackendKind::Soft,
            queries: QueryMode::Hardware,
            gpu_model: GpuModel::modern(),
            options: MethodOptions::default(),
            import: ImportOptions::default(),
            camera_path: None,
            dump_frame: None,
            parallel_lanes: true,
            motion: 0.0,
            update_policy: UpdatePolicy::default(),
        }
    }
}

impl BenchConfig {
    /// Rejects configurations that cannot run, with a message naming the
    /// offending value.
    pub fn validate(&self) -> Result<()> {
        if self.methods.is_empty() {
            invalid!("no methods given: expected a comma-separated list of {}", METHOD_NAMES.join(", "));
        }
        for m in self.methods.iter().filter(|m| !IDEALS.contains(&m.as_str())) {
            create(m, &self.options)?;
        }
        for ideal in IDEALS {
            if let Some(i) = self.methods.iter().position(|m| m == ideal) {
                if !self.methods[..i].iter().any(|m| m == SOURCE) {
                    invalid!("method {ideal} renders {SOURCE}'s visible set without queries: list {SOURCE} before it (e.g. --methods vfc,{SOURCE},{ideal})");
                }
                self.options.for_method(ideal).finish()?;
            }
        }
        self.options.check_methods(&self.methods)?;
        if let Some(dup) = self.methods.iter().enumerate().find(|(i, m)| self.methods[..*i].contains(m)) {
            invalid!("method '{}' is listed twice", dup.1);
        }
        if self.frames != ALL_FRAMES {
            crate::limits::check_frame_count(self.frames).map_err(|e| Error::Invalid(format!("--frames: {e}")))?;
        }
        if let Some(fps) = self.fps {
            crate::limits::check_fps(fps).map_err(|e| Error::Invalid(format!("--fps: {e}")))?;
        }
        if let Some(k) = self.dump_frame.filter(|&k| k >= self.frames) {
            invalid!("--dump-frame {k} is past the last frame: frames are numbered 0 to {}", self.frames - 1);
        }
        crate::limits::check_resolution(self.resolution).map_err(Error::Invalid)?;
        if self.build.leaf_size == 0 {
            invalid!("--leaf-size must be at least 1");
        }
        if !(0.0..=1.0).contains(&self.motion) {
            invalid!("--motion {} is out of range: expected a share of the instances from 0 to 1", self.motion);
        }
        let ratio = self.update_policy.max_cost_ratio;
        if ratio.is_nan() || ratio < 1.0 {
            invalid!("--rebuild-ratio {ratio} is out of range: expected 1 or more (inf: never rebuild)");
        }
        Ok(())
    }
}

impl BenchConfig {
    /// How the walkthrough is cut into frames: [`Self::fps`] and
    /// [`Self::frames`] as the path sampler takes them.
    pub fn sampling(&self) -> Sampling {
        match self.fps {
            Some(fps) => Sampling::Rate { fps, limit: (self.frames != ALL_FRAMES).then_some(self.frames) },
            None => Sampling::Spread(self.frames),
        }
    }
}

/// Parses `--frames`: a count of 1 to [`crate::limits::MAX_FRAMES`], or
/// `all` ([`ALL_FRAMES`]: every frame of the walkthrough, which may then
/// hold at most that many).
pub fn parse_frames(s: &str) -> Result<usize, String> {
    match s.trim() {
        "all" => Ok(ALL_FRAMES),
        n => crate::limits::parse_frame_count(n).map_err(|e| format!("{e}, or 'all'")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_parse_as_a_count_or_all_and_set_the_sampling() {
        assert_eq!(parse_frames("12"), Ok(12));
        assert_eq!(parse_frames("all"), Ok(ALL_FRAMES));
        assert!(parse_frames("-1").unwrap_err().contains("'-1'"));
        let c = BenchConfig { frames: 12, fps: Some(30.0), ..BenchConfig::default() };
        assert_eq!(c.sampling(), Sampling::Rate { fps: 30.0, limit: Some(12) });
        let c = BenchConfig { frames: ALL_FRAMES, ..c };
        assert_eq!(c.sampling(), Sampling::Rate { fps: 30.0, limit: None });
        let c = BenchConfig { fps: None, frames: 12, ..c };
        assert_eq!(c.sampling(), Sampling::Spread(12));
    }

    #[test]
    fn validation_names_the_bad_value() {
        let mut c = BenchConfig::default();
        c.validate().unwrap();
        c.methods = vec!["vfc".into(), "magic".into()];
        assert!(c.validate().unwrap_err().to_string().contains("magic"));
        c.methods = vec!["vfc".into(), "vfc".into()];
        assert!(c.validate().unwrap_err().to_string().contains("twice"));
        c = BenchConfig { resolution: (0, 10), ..BenchConfig::default() };
        assert!(c.validate().unwrap_err().to_string().contains("0x10"));
        c = BenchConfig { frames: 0, ..BenchConfig::default() };
        assert!(c.validate().is_err());
        c = BenchConfig { methods: vec!["vfc".into(), "ideal".into(), "sw".into()], ..BenchConfig::default() };
        assert!(c.validate().unwrap_err().to_string().contains("list sw before it"));
        c.methods = vec!["vfc".into(), "sw".into(), "ideal".into()];
        c.validate().unwrap();
        c.options = MethodOptions::parse(&["ideal.x=1"]).unwrap();
        assert!(c.validate().unwrap_err().to_string().contains("takes no parameters"));
        c = BenchConfig { fps: Some(0.0), ..BenchConfig::default() };
        assert!(c.validate().unwrap_err().to_string().contains("--fps: '0'"));
        c = BenchConfig { frames: crate::limits::MAX_FRAMES + 1, ..BenchConfig::default() };
        assert!(c.validate().unwrap_err().to_string().contains("--frames: '100001'"));
        c = BenchConfig { fps: Some(f32::NAN), ..BenchConfig::default() };
        assert!(c.validate().is_err());
        c = BenchConfig { frames: 5, dump_frame: Some(4), ..BenchConfig::default() };
        c.validate().unwrap();
        c.dump_frame = Some(5);
        assert!(c.validate().unwrap_err().to_string().contains("--dump-frame 5"));
    }
}
