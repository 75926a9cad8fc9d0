//! Runs the methods frame by frame and checks each against view-frustum
//! culling's depth image (the correctness rule of `docs/design.md`).

use super::config::{BackendKind, BenchConfig, NEAR_PLANE};
use super::dump::FrameDump;
use super::ideal::{self, DrawCalls, DrawLog, Ideal, IDEAL};
use super::summary::{BenchReport, SceneStats};
use crate::progress::stage;
use anyhow::{Context, Result};
use indicatif::ProgressBar;
use occlude_core::methods::{check_support, create, BuiltMethod, DrawnSet, MethodOptions};
use occlude_core::{differing_pixels, render_frame, Backend, Camera, FrameStats, Hierarchy, QueryMode, Scene};
use occlude_soft::SoftBackend;
use occlude_wgpu::{GpuContext, GpuScene, WgpuBackend};
use std::collections::BTreeMap;
use std::rc::Rc;
use std::sync::Arc;

/// Everything a run measured, before summarising.
pub struct BenchRun {
    /// Scene, hierarchy and path figures.
    pub scene: SceneStats,
    /// Per method (in configuration order), its per-frame statistics.
    pub methods: Vec<MethodRun>,
    /// Per variant given to [`run_scene_with_variants`] (in that order), its
    /// per-frame statistics (empty for [`run_scene`]).
    pub variants: Vec<MethodRun>,
    /// View-frustum culling's frames (the reference, always run).
    pub reference: Vec<FrameStats>,
    /// The decisions of frame [`BenchConfig::dump_frame`] of each method that
    /// records them, in configuration order (empty when none was asked for).
    pub dumps: Vec<FrameDump>,
    /// The GPU adapter the wgpu backend ran on (`None` on the soft backend).
    pub adapter: Option<String>,
    /// Why the run stopped before the walkthrough's end (a lost GPU device):
    /// the frames kept are those every method finished.
    pub aborted: Option<String>,
    /// Warnings the methods gave about their parameters on this scene
    /// (printed above the progress bar as they come).
    pub warnings: Vec<String>,
}

/// Makes each method's backend: the soft rasterizer, or the wgpu backend
/// over one scene upload shared by all methods.
enum Renderer {
    Soft,
    Wgpu(Arc<GpuScene>),
}

impl Renderer {
    /// Opens the GPU and uploads `scene` when `config` asks for wgpu; an
    /// adapter that cannot count queries as `config.queries` asks is
    /// refused.
    fn new(config: &BenchConfig, scene: &Scene) -> Result<Self> {
        Ok(match config.backend {
            BackendKind::Soft => Self::Soft,
            BackendKind::Wgpu => {
                let ctx = Arc::new(GpuContext::new()?);
                if config.queries == QueryMode::Hib {
                    ctx.gpu_culling_support()?;
                }
                Self::Wgpu(Arc::new(GpuScene::new(ctx, scene)?))
            }
        })
    }

    fn backend<'s>(&self, scene: &'s Scene, config: &BenchConfig) -> Result<Box<dyn Backend + 's>> {
        let (w, h) = config.resolution;
        Ok(match self {
            Self::Soft => {
                let mut soft = SoftBackend::new(scene, w, h, config.gpu_model.clone());
                soft.set_query_mode(config.queries);
                Box::new(soft)
            }
            Self::Wgpu(gpu) => {
                let mut backend = WgpuBackend::new(Arc::clone(gpu), scene, w, h);
                backend.set_query_mode(config.queries)?;
                Box::new(backend)
            }
        })
    }

    fn adapter(&self) -> Option<String> {
        match self {
            Self::Soft => None,
            Self::Wgpu(gpu) => Some(gpu.context().adapter_name()),
        }
    }
}

/// One method's measurements.
#[derive(Clone, Debug)]
pub struct MethodRun {
    /// Method name.
    pub name: String,
    /// Parameter values in use.
    pub params: Vec<(String, String)>,
    /// Statistics of every frame.
    pub frames: Vec<FrameStats>,
    /// The method's own counters (`CullingMethod::counters`), one value per
    /// frame each.
    pub counters: BTreeMap<String, Vec<f64>>,
}

/// A method with options of its own, run as one more lane beside the
/// configured methods, on the same frames and checked against the same
/// `vfc` reference: how a paper's table of one method's settings is made
/// without rendering the reference again per setting.
#[derive(Clone, Debug)]
pub struct Variant {
    /// The method, as `--methods` names it.
    pub method: String,
    /// Its options (each `method.key=value` naming [`Self::method`]); the
    /// configuration's own options do not apply to it.
    pub options: MethodOptions,
}

impl Variant {
    /// The variant's method, built with its options; fails on an unknown
    /// method, or an option naming another method or a key the method lacks.
    fn create(&self) -> Result<BuiltMethod> {
        self.options.check_methods(std::slice::from_ref(&self.method))?;
        Ok(create(&self.method, &self.options)?)
    }
}

/// One method with its own backend and state across frames.
struct Lane<'s> {
    built: BuiltMethod,
    backend: Box<dyn Backend + 's>,
    drawn: DrawnSet,
    frames: Vec<FrameStats>,
    counters: BTreeMap<String, Vec<f64>>,
}

impl<'s> Lane<'s> {
    fn new(built: BuiltMethod, backend: Box<dyn Backend + 's>) -> Self {
        Self { built, backend, drawn: DrawnSet::default(), frames: Vec::new(), counters: BTreeMap::new() }
    }

    /// The lane's measurements.
    fn into_run(self) -> MethodRun {
        MethodRun {
            name: self.built.method.name().to_string(),
            params: self.built.params,
            frames: self.frames,
            counters: self.counters,
        }
    }

    /// Renders one frame; returns its statistics.
    fn frame(&mut self, scene: &Scene, hierarchy: &Hierarchy, camera: &Camera) -> FrameStats {
        let method = self.built.method.as_mut();
        let stats = render_frame(method, self.backend.as_mut(), scene, hierarchy, camera, &mut self.drawn);
        for (name, value) in self.built.method.counters() {
            self.counters.entry(name.to_string()).or_default().push(value);
        }
        stats
    }
}

/// Far clipping distance of every camera in `scene`: beyond the whole scene
/// seen from anywhere in it.
pub fn far_plane(scene: &Scene) -> f32 {
    (scene.bounds().extent().length() * 1.5).max(NEAR_PLANE * 10.0)
}

/// The walkthrough's cameras for `scene` at the configured resolution,
/// sampled as configured ([`BenchConfig::sampling`]).
pub fn cameras(scene: &Scene, config: &BenchConfig) -> Vec<Camera> {
    let (w, h) = config.resolution;
    scene.path.sample_with(config.sampling(), w as f32 / h as f32, NEAR_PLANE, far_plane(scene))
}

/// Generates or imports the scene (an import error stays an
/// [`occlude_scenes::LoadError`] inside the returned error, so that the
/// command line can tell it from a failure of the run), replaces its
/// walkthrough with the configured camera path if any, builds the hierarchy
/// and runs every method over the walkthrough; `progress` names the loading
/// and building stages and then advances once per frame.
pub fn run(config: &BenchConfig, progress: &ProgressBar) -> Result<BenchRun> {
    config.validate()?;
    let scene = stage(progress, &format!("loading {}", config.scene), || load_scene(config))?;
    run_scene(&scene, config, progress)
}

/// The configured scene, generated or imported, with the configured camera
/// path in place of its own walkthrough if one is given, validated. An
/// import error stays an [`occlude_scenes::LoadError`] inside the returned
/// error.
pub fn load_scene(config: &BenchConfig) -> Result<Scene> {
    let mut scene = occlude_scenes::load(&config.scene, config.size, config.seed, &config.import)?;
    if let Some(path) = &config.camera_path {
        scene.path = path.clone();
    }
    scene.validate().with_context(|| format!("scene '{}' is not usable", config.scene))?;
    Ok(scene)
}

/// Runs every method of `config` on an existing scene.
///
/// The run goes on a thread of a rayon pool (the caller's, or a new one of
/// rayon's default size when the caller is on none): the
/// soft rasterizer's parallel calls then start and end on the thread that
/// makes them, where from outside a pool each call is handed to the pool's
/// threads and the caller woken when they finish, and between calls their
/// spinning competes with the traversal for the cores.
pub fn run_scene(scene: &Scene, config: &BenchConfig, progress: &ProgressBar) -> Result<BenchRun> {
    run_scene_with_variants(scene, config, &[], progress)
}

/// [`run_scene`] with `variants` run as further lanes after the configured
/// methods ([`BenchRun::variants`]).
pub fn run_scene_with_variants(
    scene: &Scene,
    config: &BenchConfig,
    variants: &[Variant],
    progress: &ProgressBar,
) -> Result<BenchRun> {
    if rayon::current_thread_index().is_some() {
        return run_scene_here(scene, config, variants, progress);
    }
    let pool = rayon::ThreadPoolBuilder::new().build().context("cannot start the thread pool")?;
    pool.install(|| run_scene_here(scene, config, variants, progress))
}

/// [`run_scene_with_variants`] on the calling thread.
fn run_scene_here(
    scene: &Scene,
    config: &BenchConfig,
    variants: &[Variant],
    progress: &ProgressBar,
) -> Result<BenchRun> {
    config.validate()?;
    let variant_methods = variants.iter().map(Variant::create).collect::<Result<Vec<_>>>()?;
    let hierarchy = stage(progress, &format!("building the {}", config.hierarchy), || {
        Hierarchy::build(scene, config.hierarchy, config.build)
    });
    let cameras = cameras(scene, config);
    anyhow::ensure!(!cameras.is_empty(), "scene '{}' has no camera path", scene.name);

    let renderer = stage(progress, "uploading the scene", || Renderer::new(config, scene))?;
    let mut reference = Lane::new(create("vfc", &config.options)?, renderer.backend(scene, config)?);
    // `ideal` replays the draw calls `sw` (listed before it) made in the frame.
    let replayed = config.methods.iter().any(|m| m == IDEAL);
    let calls = DrawCalls::default();
    let mut lanes = config
        .methods
        .iter()
        .filter(|m| m.as_str() != "vfc")
        .map(|m| {
            let backend = renderer.backend(scene, config)?;
            Ok(match m.as_str() {
                IDEAL => {
                    let built = BuiltMethod { method: Box::new(Ideal::new(Rc::clone(&calls))), params: Vec::new() };
                    Lane::new(built, backend)
                }
                ideal::SOURCE if replayed => {
                    Lane::new(create(m, &config.options)?, Box::new(DrawLog::new(backend, Rc::clone(&calls))))
                }
                _ => Lane::new(create(m, &config.options)?, backend),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    for built in variant_methods {
        lanes.push(Lane::new(built, renderer.backend(scene, config)?));
    }
    for lane in &mut lanes {
        let method = lane.built.method.as_ref();
        if let Err(e) = check_support(method, lane.backend.as_mut()) {
            return Err(anyhow::Error::new(e).context(format!("method {} cannot run", method.name())));
        }
    }
    let mut warnings = Vec::new();

    progress.set_length(cameras.len() as u64);
    progress.set_position(0);
    let mut dumps = Vec::new();
    let mut aborted = None;
    // The frame's depth images, VFC's and a method's, in memory reused frame
    // after frame.
    let (mut expected, mut image) = (Vec::new(), Vec::new());
    'frames: for (k, camera) in cameras.iter().enumerate() {
        let stats = reference.frame(scene, &hierarchy, camera);
        reference.frames.push(stats);
        depth_image(reference.backend.as_mut(), &mut expected)?;
        if let Some(e) = reference.backend.failure() {
            aborted = Some(format!("frame {k}, method vfc: {e}"));
            break;
        }
        let dump = config.dump_frame == Some(k);
        for lane in &mut lanes {
            lane.built.method.set_debug(dump);
            let mut stats = lane.frame(scene, &hierarchy, camera);
            depth_image(lane.backend.as_mut(), &mut image)?;
            if let Some(e) = lane.backend.failure() {
                aborted = Some(format!("frame {k}, method {}: {e}", lane.built.method.name()));
                break 'frames;
            }
            stats.missing_pixels = differing_pixels(&expected, &image);
            lane.frames.push(stats);
            for w in lane.built.method.take_warnings() {
                let w = format!("{}: {w}", lane.built.method.name());
                progress.println(format!("warning: {w}"));
                warnings.push(w);
            }
            if let Some(view) = lane.built.method.debug_view().filter(|_| dump) {
                let name = lane.built.method.name().to_string();
                let depth = image.clone();
                dumps.push(FrameDump { method: name, frame: k, resolution: config.resolution, depth, view });
            }
        }
        progress.inc(1);
    }
    // Keep only the frames every method finished.
    let finished = lanes.iter().map(|l| l.frames.len()).chain([reference.frames.len()]).min().unwrap_or(0);
    if aborted.is_some() {
        reference.frames.truncate(finished);
        lanes.iter_mut().for_each(|l| l.frames.truncate(finished));
        lanes.iter_mut().flat_map(|l| l.counters.values_mut()).for_each(|c| c.truncate(finished));
        reference.counters.values_mut().for_each(|c| c.truncate(finished));
    }

    let reference = reference.into_run();
    let mut lanes = lanes.into_iter().map(Lane::into_run);
    let methods = config
        .methods
        .iter()
        .map(|m| if m == "vfc" { reference.clone() } else { lanes.next().expect("one lane per method") })
        .collect();
    Ok(BenchRun {
        scene: SceneStats::new(scene, &hierarchy, finished),
        methods,
        variants: lanes.collect(),
        reference: reference.frames,
        dumps,
        adapter: renderer.adapter(),
        aborted,
        warnings,
    })
}

/// The depth image of `backend`'s last frame, for the correctness rule;
/// an error for a backend without [`occlude_core::Instruments`].
fn depth_image(backend: &mut dyn Backend, out: &mut Vec<f32>) -> Result<()> {
    let instruments = backend.instruments().context("the backend has no depth image to check")?;
    instruments.depth_image(out);
    Ok(())
}

impl BenchRun {
    /// The summary tables and JSON are made from.
    pub fn report(&self, config: &BenchConfig) -> BenchReport {
        BenchReport::new(self, config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_variant_with_options_its_method_lacks_is_refused_with_the_option_named() {
        let variant = |method: &str, items: &[&str]| Variant {
            method: method.into(),
            options: MethodOptions::parse(items).unwrap(),
        };
        assert!(variant("chc", &["chc.tav=2", "chc.nvp=25"]).create().is_ok());
        for (v, needle) in [
            (variant("chc", &["sw.tav=2"]), "sw.tav"),
            (variant("chc", &["chc.nosuchkey=1"]), "nosuchkey"),
            (variant("chc", &["chc.tav=many"]), "many"),
            (variant("magic", &[]), "magic"),
        ] {
            let e = v.create().err().expect("refused").to_string();
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }
}
