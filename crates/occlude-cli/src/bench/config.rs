//! What a benchmark run is asked to do, checked before any work starts.

use super::ideal::{IDEALS, SOURCE};
use anyhow::{bail, Context, Result};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::{create, MethodOptions, METHOD_NAMES};
use occlude_core::{CameraPath, HierarchyKind, QueryMode, Sampling};
use occlude_scenes::{ImportOptions, Size};
use occlude_soft::GpuModel;
use std::path::Path;

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
    fn from_str(s: &str) -> Result<Self, Self::Err> {
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
    /// for [`super::dump`] (`--dump-frame K`).
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
        }
    }
}

impl BenchConfig {
    /// Rejects configurations that cannot run, with a message naming the
    /// offending value.
    pub fn validate(&self) -> Result<()> {
        if self.methods.is_empty() {
            bail!("no methods given: expected a comma-separated list of {}", METHOD_NAMES.join(", "));
        }
        for m in self.methods.iter().filter(|m| !IDEALS.contains(&m.as_str())) {
            create(m, &self.options)?;
        }
        for ideal in IDEALS {
            if let Some(i) = self.methods.iter().position(|m| m == ideal) {
                if !self.methods[..i].iter().any(|m| m == SOURCE) {
                    bail!("method {ideal} renders {SOURCE}'s visible set without queries: list {SOURCE} before it (e.g. --methods vfc,{SOURCE},{ideal})");
                }
                self.options.for_method(ideal).finish()?;
            }
        }
        self.options.check_methods(&self.methods)?;
        if let Some(dup) = self.methods.iter().enumerate().find(|(i, m)| self.methods[..*i].contains(m)) {
            bail!("method '{}' is listed twice", dup.1);
        }
        if self.frames == 0 {
            bail!("--frames must be at least 1");
        }
        if self.fps.is_some_and(|f| !(f > 0.0 && f <= MAX_FPS)) {
            bail!(
                "--fps {} is out of range: expected a frame rate above 0 and at most {MAX_FPS}",
                self.fps.unwrap_or(0.0)
            );
        }
        if let Some(k) = self.dump_frame.filter(|&k| k >= self.frames) {
            bail!("--dump-frame {k} is past the last frame: frames are numbered 0 to {}", self.frames - 1);
        }
        let (w, h) = self.resolution;
        if w == 0 || h == 0 || w > 16384 || h > 16384 {
            bail!("resolution {w}x{h} is out of range: each side must be 1 to 16384 pixels");
        }
        if self.build.leaf_size == 0 {
            bail!("--leaf-size must be at least 1");
        }
        if !(0.0..=1.0).contains(&self.motion) {
            bail!("--motion {} is out of range: expected a share of the instances from 0 to 1", self.motion);
        }
        Ok(())
    }
}

/// The highest frame rate `--fps` accepts.
const MAX_FPS: f32 = 1000.0;

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

/// Parses `--frames`: a count of at least 1, or `all` ([`ALL_FRAMES`]).
pub fn parse_frames(s: &str) -> Result<usize, String> {
    match s.trim() {
        "all" => Ok(ALL_FRAMES),
        n => n.parse::<usize>().map_err(|_| format!("'{s}' is not a frame count (a whole number, or 'all')")),
    }
}

/// Reads a walkthrough from a JSON file of camera keyframes,
/// `{"keyframes":[{"time":0,"position":[x,y,z],"target":[x,y,z],"fov_y_deg":60}, ...]}`
/// (the serde form of [`CameraPath`]), and checks that it can be replayed:
/// at least one keyframe, finite values, times strictly increasing, a field
/// of view between 0 and 180 degrees, a target apart from the position.
pub fn load_camera_path(path: &Path) -> Result<CameraPath> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read camera path {}", path.display()))?;
    let camera_path: CameraPath = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a camera path (JSON of keyframes)", path.display()))?;
    if camera_path.keyframes.is_empty() {
        bail!("camera path {} has no keyframes", path.display());
    }
    for (i, k) in camera_path.keyframes.iter().enumerate() {
        let finite = k.time.is_finite() && k.position.is_finite() && k.target.is_finite();
        let usable = finite && k.fov_y_deg > 0.0 && k.fov_y_deg < 180.0 && k.position != k.target;
        if !usable {
            bail!(
                "camera path {}: keyframe {i} needs finite values, a target apart from the position \
                 and fov_y_deg between 0 and 180",
                path.display()
            );
        }
        if i > 0 && k.time <= camera_path.keyframes[i - 1].time {
            bail!("camera path {}: keyframe {i} is not later than the one before", path.display());
        }
    }
    Ok(camera_path)
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 1024x768)"))?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("'{s}' is not WIDTHxHEIGHT (e.g. 1024x768)"));
    Ok((parse(w)?, parse(h)?))
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
    fn resolution_parses_and_rejects() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert!(parse_resolution("640").is_err());
        assert!(parse_resolution("ax480").is_err());
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
        assert!(c.validate().unwrap_err().to_string().contains("--fps 0"));
        c = BenchConfig { fps: Some(f32::NAN), ..BenchConfig::default() };
        assert!(c.validate().is_err());
        c = BenchConfig { frames: 5, dump_frame: Some(4), ..BenchConfig::default() };
        c.validate().unwrap();
        c.dump_frame = Some(5);
        assert!(c.validate().unwrap_err().to_string().contains("--dump-frame 5"));
    }
}
