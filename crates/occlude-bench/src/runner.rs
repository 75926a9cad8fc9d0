//! Runs the methods frame by frame and checks each against view-frustum
//! culling's depth image (the correctness rule of `docs/design.md`).
//!
//! Each method is a lane with a backend of its own; on the soft backend the
//! lanes of a frame render side by side on the thread pool
//! ([`BenchConfig::parallel_lanes`]), and are then checked and recorded in
//! report order, so the results are those of rendering them one by one.

use crate::config::{BackendKind, BenchConfig, NEAR_PLANE};
use crate::error::{Error, Result, ResultExt};
use crate::ideal::{self, DrawCalls, DrawLog, Ideal, IDEAL, IDEALS};
use crate::progress::{stage, Progress};
use crate::summary::{BenchReport, SceneStats};
use occlude_core::methods::{check_support, create, BuiltMethod, DebugView, DrawnSet, MethodOptions};
use occlude_core::{differing_pixels, render_frame, Backend, Camera, FrameStats, Hierarchy, QueryMode, Scene, Upkeep};
use occlude_scenes::{Motion, OwnMotion};
use occlude_soft::{DrawReplay, SharedSetup, SoftBackend};
use occlude_wgpu::{GpuContext, GpuScene, WgpuBackend};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

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
    /// (shown through [`Progress::println`] as they come).
    pub warnings: Vec<String>,
}

/// One method's decisions in one frame, with the frame's depth image
/// ([`BenchConfig::dump_frame`]).
#[derive(Clone, Debug)]
pub struct FrameDump {
    /// Method name.
    pub method: String,
    /// Frame number, 0-based.
    pub frame: usize,
    /// Image size in pixels.
    pub resolution: (u32, u32),
    /// The frame's depth image, row by row (1.0 where nothing was drawn).
    pub depth: Vec<f32>,
    /// What the method decided.
    pub view: DebugView,
}

/// Makes each method's backend: the soft rasterizer (its backends sharing
/// their triangles' set-up when given one, `occlude_soft::SharedSetup`:
/// same figures, less CPU time when several lanes draw the same frame), or
/// the wgpu backend over one scene upload shared by all methods.
enum Renderer {
    Soft(Option<SharedSetup>),
    Wgpu(Arc<GpuScene>),
}

impl Renderer {
    /// Opens the GPU and uploads `scene` when `config` asks for wgpu; an
    /// adapter that cannot count queries as `config.queries` asks is
    /// refused. Soft backends share their set-up when `lanes` (the run's
    /// lane count) is more than one; a lone lane sets up in the
    /// rasterizer's parallel steps instead.
    fn new(config: &BenchConfig, scene: &Scene, lanes: usize) -> Result<Self> {
        Ok(match config.backend {
            BackendKind::Soft => Self::Soft((lanes > 1).then(SharedSetup::new)),
            BackendKind::Wgpu => {
                let ctx = Arc::new(GpuContext::new()?);
                if config.queries == QueryMode::Hib {
                    ctx.gpu_culling_support()?;
                }
                Self::Wgpu(Arc::new(GpuScene::new(ctx, scene)?))
            }
        })
    }

    /// A lane's backend; on the soft backend, `draws` says whether it keeps
    /// its draws' counts for another or takes them from one.
    fn backend(&self, scene: &Scene, config: &BenchConfig, draws: Draws) -> Result<Box<dyn Backend + Send>> {
        let (w, h) = config.resolution;
        Ok(match self {
            Self::Soft(shared) => {
                let mut soft = SoftBackend::new(scene, w, h, config.gpu_model.clone());
                soft.set_query_mode(config.queries);
                if let Some(shared) = shared {
                    soft.share_setup(shared.clone());
                }
                match draws {
                    Draws::Own => {}
                    Draws::Record(shared) => soft.record_draws(shared),
                    Draws::Replay(shared) => soft.replay_draws(shared),
                }
                Box::new(soft)
            }
            Self::Wgpu(gpu) => {
                let mut backend = WgpuBackend::new(Arc::clone(gpu), scene, w, h);
                backend.set_query_mode(config.queries)?;
                Box::new(backend)
            }
        })
    }

    /// Whether frame times are simulated (soft) rather than measured.
    fn models_time(&self) -> bool {
        matches!(self, Self::Soft(_))
    }

    fn adapter(&self) -> Option<String> {
        match self {
            Self::Soft(_) => None,
            Self::Wgpu(gpu) => Some(gpu.context().adapter_name()),
        }
    }

    /// Whether lanes may render side by side: on the soft backend, whose
    /// figures are simulated, when `config` asks; never on a GPU, whose
    /// times the lanes would disturb.
    fn parallel_lanes(&self, config: &BenchConfig) -> bool {
        matches!(self, Self::Soft(_)) && config.parallel_lanes
    }
}

/// Where a soft lane's draws are counted: `sw`'s backend rasterizes them
/// and keeps their counts and its final image for `ideal`'s, which replays
/// the same draws without rasterizing them (`occlude_soft::DrawReplay`:
/// same counts, same image, so the same figures). On the GPU every lane
/// draws for itself: its times are measured.
enum Draws {
    Own,
    Record(DrawReplay),
    Replay(DrawReplay),
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
struct Lane {
    built: BuiltMethod,
    backend: Box<dyn Backend + Send>,
    drawn: DrawnSet,
    frames: Vec<FrameStats>,
    counters: BTreeMap<String, Vec<f64>>,
    /// The statistics of the frame last rendered, until the runner checks
    /// and records them.
    stats: FrameStats,
    /// The depth image of the frame last rendered, in memory reused frame
    /// after frame.
    image: Vec<f32>,
    /// The upkeep of a moving scene before the coming frame (only its
    /// `update_ms`, `update_charged_ms`, `instances_moved` and `rebuilds`):
    /// the charged time is CPU work done before the frame begins (each
    /// frame starts with the GPU idle).
    update: FrameStats,
}

impl Lane {
    fn new(built: BuiltMethod, backend: Box<dyn Backend + Send>) -> Self {
        Self {
            built,
            backend,
            drawn: DrawnSet::default(),
            frames: Vec::new(),
            counters: BTreeMap::new(),
            stats: FrameStats::default(),
            image: Vec::new(),
            update: FrameStats::default(),
        }
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

    /// Renders one frame into [`Self::stats`] and [`Self::image`].
    fn frame(&mut self, scene: &Scene, hierarchy: &Hierarchy, camera: &Camera) -> Result<()> {
        let method = self.built.method.as_mut();
        self.stats = render_frame(method, self.backend.as_mut(), scene, hierarchy, camera, &mut self.drawn);
        let u = std::mem::take(&mut self.update);
        self.stats.frame_ms += u.update_charged_ms;
        self.stats.cpu_ms += u.update_charged_ms;
        (self.stats.update_ms, self.stats.update_charged_ms, self.stats.instances_moved, self.stats.rebuilds) =
            (u.update_ms, u.update_charged_ms, u.instances_moved, u.rebuilds);
        for (name, value) in self.built.method.counters() {
            self.counters.entry(name.to_string()).or_default().push(value);
        }
        depth_image(self.backend.as_mut(), &mut self.image)
    }
}

/// A run's lanes in chains: the lanes of a chain render a frame one after
/// another (`ideal` after the `sw` whose draws it replays), the chains side
/// by side when [`Self::parallel`]. Nothing else is shared between lanes
/// but the set-up of the frame's triangles (`SharedSetup`), the same
/// whichever lane makes it, so the order they render in changes no figure.
struct Lanes {
    chains: Vec<Vec<Lane>>,
    /// Per lane in report order (the `vfc` reference first), its chain and
    /// place in it.
    order: Vec<(usize, usize)>,
    parallel: bool,
}

impl Lanes {
    /// `reference` alone, its lanes to render side by side when `parallel`.
    fn new(reference: Lane, parallel: bool) -> Self {
        Self { chains: vec![vec![reference]], order: vec![(0, 0)], parallel }
    }

    /// Appends `lane` in report order, in a chain of its own or, with
    /// `after`, after the lane of that index in its chain.
    fn push(&mut self, lane: Lane, after: Option<usize>) {
        let chain = match after {
            Some(i) => self.order[i].0,
            None => {
                self.chains.push(Vec::new());
                self.chains.len() - 1
            }
        };
        self.order.push((chain, self.chains[chain].len()));
        self.chains[chain].push(lane);
    }

    fn len(&self) -> usize {
        self.order.len()
    }

    /// The lane of index `i` in report order (0: the reference).
    fn get_mut(&mut self, i: usize) -> &mut Lane {
        let (chain, at) = self.order[i];
        &mut self.chains[chain][at]
    }

    /// Every lane in report order.
    fn iter(&self) -> impl Iterator<Item = &Lane> {
        self.order.iter().map(|&(chain, at)| &self.chains[chain][at])
    }

    /// Gives every lane's backend the `changed` instances of `scene` and
    /// records, for its coming frame, the time that took with `upkeep` (the
    /// hierarchy's), and the time its frame is charged: `modelled_ms` on
    /// the soft backend's simulated clock, else that measured time.
    fn update_instances(&mut self, scene: &Scene, changed: &[u32], upkeep: &Upkeep, modelled_ms: Option<f64>) {
        for lane in self.chains.iter_mut().flatten() {
            let start = Instant::now();
            lane.backend.update_instances(scene, changed);
            let update_ms = (upkeep.time + start.elapsed()).as_secs_f64() * 1e3;
            lane.update = FrameStats {
                update_ms,
                update_charged_ms: modelled_ms.unwrap_or(update_ms),
                instances_moved: upkeep.instances as u64,
                rebuilds: u64::from(upkeep.rebuilt),
                ..FrameStats::default()
            };
        }
    }

    /// Renders one frame on every lane.
    fn frame(&mut self, scene: &Scene, hierarchy: &Hierarchy, camera: &Camera) -> Result<()> {
        let chain = |lanes: &mut Vec<Lane>| lanes.iter_mut().try_for_each(|l| l.frame(scene, hierarchy, camera));
        if self.parallel {
            self.chains.par_iter_mut().try_for_each(chain)
        } else {
            self.chains.iter_mut().try_for_each(chain)
        }
    }

    /// Sets every lane's `missing_pixels` but the reference's: the pixels
    /// where its image differs from `expected`, the reference's. The lanes
    /// are compared side by side when [`Self::parallel`].
    fn count_missing(&mut self, expected: &[f32]) {
        let reference = self.order[0];
        let chain = |(c, lanes): (usize, &mut Vec<Lane>)| {
            for (at, lane) in lanes.iter_mut().enumerate() {
                if (c, at) != reference {
                    lane.stats.missing_pixels = differing_pixels(expected, &lane.image);
                }
            }
        };
        if self.parallel {
            self.chains.par_iter_mut().enumerate().for_each(chain);
        } else {
            self.chains.iter_mut().enumerate().for_each(chain);
        }
    }

    /// The lanes in report order.
    fn into_vec(self) -> Vec<Lane> {
        let mut chains: Vec<Vec<Option<Lane>>> =
            self.chains.into_iter().map(|c| c.into_iter().map(Some).collect()).collect();
        self.order.iter().map(|&(chain, at)| chains[chain][at].take().expect("each lane once")).collect()
    }
}

/// The simulated CPU time of `upkeep` on `config`'s GPU model: a refit
/// recomputes each node it visits at the cost of visiting a node in a
/// traversal (`cpu_node_us`: a box union against a frustum test); a
/// rebuild (after its refit) reads every instance's box once per level of
/// the new tree `h`, as a binned SAH build does.
fn modelled_upkeep_ms(config: &BenchConfig, upkeep: &Upkeep, h: &Hierarchy) -> f64 {
    let rebuild = if upkeep.rebuilt { h.items.len() * (h.max_depth() as usize + 1) } else { 0 };
    (upkeep.visited + rebuild) as f64 * config.gpu_model.cpu_node_us * 1e-3
}

/// Far clipping distance of every camera in `scene`: its
/// [`Scene::view_distance`] if it has one, else beyond the whole scene seen
/// from anywhere in it.
pub fn far_plane(scene: &Scene) -> f32 {
    scene.view_distance.unwrap_or(scene.bounds().extent().length() * 1.5).max(NEAR_PLANE * 10.0)
}

/// The walkthrough's cameras for `scene` at the configured resolution,
/// sampled as configured ([`BenchConfig::sampling`]) and checked by
/// [`crate::camera_path::cameras`] (bounded in number, each able to render).
pub fn cameras(scene: &Scene, config: &BenchConfig) -> Result<Vec<Camera>> {
    let (w, h) = config.resolution;
    crate::camera_path::cameras(&scene.path, config.sampling(), w as f32 / h as f32, NEAR_PLANE, far_plane(scene))
        .context(|| format!("scene '{}'", scene.name))
}

/// Generates or imports the scene (an import error is an
/// [`Error::Load`], so that the command line can tell it from a failure of
/// the run), replaces its
/// walkthrough with the configured camera path if any, builds the hierarchy
/// and runs every method over the walkthrough, playing the scene's own
/// motion if it has one (a model's animation, a generated scene's script);
/// `progress` names the loading and building stages and then
/// advances once per frame.
pub fn run(config: &BenchConfig, progress: &dyn Progress) -> Result<BenchRun> {
    config.validate()?;
    let (scene, own) = stage(progress, &format!("loading {}", config.scene), || load_scene(config))?;
    run_moving_scene(&scene, own.as_ref(), config, &[], progress)
}

/// The configured scene, generated or imported, with the configured camera
/// path in place of its own walkthrough if one is given, validated, and
/// its own motion if it has one (a model's animation, a generated scene's
/// script). An import error is an [`Error::Load`].
pub fn load_scene(config: &BenchConfig) -> Result<(Scene, Option<OwnMotion>)> {
    let (mut scene, own) = occlude_scenes::load_moving(&config.scene, config.size, config.seed, &config.import)?;
    if let Some(path) = &config.camera_path {
        scene.path = path.clone();
    }
    scene.validate().context(|| format!("scene '{}' is not usable", config.scene))?;
    Ok((scene, own))
}

/// Runs every method of `config` on an existing scene.
///
/// The run goes on a thread of a rayon pool (the caller's, or a new one of
/// rayon's default size when the caller is on none): the
/// soft rasterizer's parallel calls then start and end on the thread that
/// makes them, where from outside a pool each call is handed to the pool's
/// threads and the caller woken when they finish, and between calls their
/// spinning competes with the traversal for the cores.
pub fn run_scene(scene: &Scene, config: &BenchConfig, progress: &dyn Progress) -> Result<BenchRun> {
    run_scene_with_variants(scene, config, &[], progress)
}

/// [`run_scene`] with `variants` run as further lanes after the configured
/// methods ([`BenchRun::variants`]).
pub fn run_scene_with_variants(
    scene: &Scene,
    config: &BenchConfig,
    variants: &[Variant],
    progress: &dyn Progress,
) -> Result<BenchRun> {
    run_moving_scene(scene, None, config, variants, progress)
}

/// [`run_scene_with_variants`] playing `own`, the scene's own motion, along
/// the walkthrough (with `--motion`'s scripted motion of the instances it
/// does not move, see [`Motion`]).
pub fn run_moving_scene(
    scene: &Scene,
    own: Option<&OwnMotion>,
    config: &BenchConfig,
    variants: &[Variant],
    progress: &dyn Progress,
) -> Result<BenchRun> {
    if rayon::current_thread_index().is_some() {
        return run_scene_here(scene, own, config, variants, progress);
    }
    let pool = rayon::ThreadPoolBuilder::new().build().map_err(Error::ThreadPool)?;
    pool.install(|| run_scene_here(scene, own, config, variants, progress))
}

/// [`run_moving_scene`] on the calling thread.
fn run_scene_here(
    scene: &Scene,
    own: Option<&OwnMotion>,
    config: &BenchConfig,
    variants: &[Variant],
    progress: &dyn Progress,
) -> Result<BenchRun> {
    config.validate()?;
    let variant_methods = variants.iter().map(Variant::create).collect::<Result<Vec<_>>>()?;
    let mut hierarchy = stage(progress, &format!("building the {}", config.hierarchy), || {
        Hierarchy::build(scene, config.hierarchy, config.build)
    });
    let cameras = cameras(scene, config)?;
    if cameras.is_empty() {
        return Err(Error::Invalid(format!("scene '{}' has no camera path", scene.name)));
    }
    let times = scene.path.frame_times(config.sampling());
    let motion = Motion::new(scene, own.cloned(), config.motion, config.seed);
    // The scene as it moves, frame by frame; the caller's stays as built.
    let mut moving = scene.clone();

    let lanes = 1 + config.methods.iter().filter(|m| m.as_str() != "vfc").count() + variant_methods.len();
    let renderer = stage(progress, "uploading the scene", || Renderer::new(config, scene, lanes))?;
    let mut lanes = build_lanes(scene, config, variant_methods, &renderer)?;
    let mut warnings = Vec::new();

    progress.start(cameras.len() as u64);
    let mut dumps = Vec::new();
    let mut aborted = None;
    for (k, camera) in cameras.iter().enumerate() {
        let dump = config.dump_frame == Some(k);
        for i in 1..lanes.len() {
            lanes.get_mut(i).built.method.set_debug(dump);
        }
        if let Some(motion) = &motion {
            let changed = moving.apply(&motion.changes_at(times[k]))?;
            let upkeep = hierarchy.update(&moving, &changed, config.update_policy);
            let modelled = renderer.models_time().then(|| modelled_upkeep_ms(config, &upkeep, &hierarchy));
            lanes.update_instances(&moving, &changed, &upkeep, modelled);
        }
        lanes.frame(&moving, &hierarchy, camera)?;
        if let Some(e) = lanes.iter().find_map(|l| l.backend.failure().map(|e| (l.built.method.name(), e))) {
            aborted = Some(format!("frame {k}, method {}: {}", e.0, e.1));
            break;
        }
        // VFC's depth image, the one every other lane's must equal.
        let expected = std::mem::take(&mut lanes.get_mut(0).image);
        lanes.count_missing(&expected);
        for i in 0..lanes.len() {
            let lane = lanes.get_mut(i);
            lane.frames.push(lane.stats);
            for w in lane.built.method.take_warnings() {
                let w = format!("{}: {w}", lane.built.method.name());
                progress.println(&format!("warning: {w}"));
                warnings.push(w);
            }
            if let Some(view) = lane.built.method.debug_view().filter(|_| dump) {
                let name = lane.built.method.name().to_string();
                let depth = lane.image.clone();
                dumps.push(FrameDump { method: name, frame: k, resolution: config.resolution, depth, view });
            }
        }
        lanes.get_mut(0).image = expected;
        progress.advance(1);
    }
    let mut lanes = lanes.into_vec();
    // Keep only the frames every lane finished (all of them unless aborted).
    let finished = lanes.iter().map(|l| l.frames.len()).min().unwrap_or(0);
    for lane in &mut lanes {
        lane.frames.truncate(finished);
        lane.counters.values_mut().for_each(|c| c.truncate(finished));
    }

    let mut lanes = lanes.into_iter().map(Lane::into_run);
    let reference = lanes.next().expect("the reference lane");
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

/// The run's lanes on `renderer`'s backends: the `vfc` reference, each
/// configured method but `vfc`, then `variants`; a method the backend
/// cannot run is refused.
fn build_lanes(scene: &Scene, config: &BenchConfig, variants: Vec<BuiltMethod>, renderer: &Renderer) -> Result<Lanes> {
    let reference = Lane::new(create("vfc", &config.options)?, renderer.backend(scene, config, Draws::Own)?);
    let mut lanes = Lanes::new(reference, renderer.parallel_lanes(config));
    // `ideal` replays the draw calls `sw` (listed before it) made in the
    // frame, after it in its chain, with the counts of `sw`'s backend;
    // `ideal-sorted` draws them in another order, after it in its chain, on
    // a backend of its own.
    let replayed = config.methods.iter().any(|m| IDEALS.contains(&m.as_str()));
    let (calls, counts) = (DrawCalls::default(), DrawReplay::default());
    let mut source = None;
    for m in config.methods.iter().filter(|m| m.as_str() != "vfc") {
        match m.as_str() {
            name if IDEALS.contains(&name) => {
                let built =
                    BuiltMethod { method: Box::new(Ideal::named(name, Arc::clone(&calls))), params: Vec::new() };
                let draws = if name == IDEAL { Draws::Replay(counts.clone()) } else { Draws::Own };
                lanes.push(Lane::new(built, renderer.backend(scene, config, draws)?), source);
            }
            ideal::SOURCE if replayed => {
                source = Some(lanes.len());
                let backend = renderer.backend(scene, config, Draws::Record(counts.clone()))?;
                let log = Box::new(DrawLog::new(backend, Arc::clone(&calls)));
                lanes.push(Lane::new(create(m, &config.options)?, log), None);
            }
            _ => lanes.push(Lane::new(create(m, &config.options)?, renderer.backend(scene, config, Draws::Own)?), None),
        }
    }
    for built in variants {
        lanes.push(Lane::new(built, renderer.backend(scene, config, Draws::Own)?), None);
    }
    for i in 1..lanes.len() {
        let lane = lanes.get_mut(i);
        let method = lane.built.method.as_ref();
        check_support(method, lane.backend.as_mut()).context(|| format!("method {} cannot run", method.name()))?;
    }
    Ok(lanes)
}

/// The depth image of `backend`'s last frame, for the correctness rule;
/// an error for a backend without [`occlude_core::Instruments`].
fn depth_image(backend: &mut dyn Backend, out: &mut Vec<f32>) -> Result<()> {
    let instruments =
        backend.instruments().ok_or_else(|| Error::Backend("the backend has no depth image to check".into()))?;
    instruments.depth_image(out);
    Ok(())
}

impl BenchRun {
    /// The summary tables and JSON are made from.
    pub fn report(&self, config: &BenchConfig) -> BenchReport {
        BenchReport::new(self, config)
    }

    /// The run cut to its first `frames` frames and to `methods` (by name,
    /// in that order) and their warnings, without variants or dumps. For a
    /// run that sampled its walkthrough at a frame rate
    /// ([`BenchConfig::fps`]), whose first frames are then those of a
    /// shorter run at that rate: a frame's figures depend only on the
    /// frames before it and never on the lanes beside it, so this is what
    /// a run of `methods` over those frames measures (tested), but for wall
    /// times. CHC++'s Figure 9 takes its FIX run from here instead of
    /// rendering it again.
    ///
    /// # Panics
    /// If a name in `methods` is not one of the run's methods.
    pub fn first_frames(&self, methods: &[&str], frames: usize) -> BenchRun {
        let frames = frames.min(self.reference.len());
        let cut = |name: &str| {
            let m = self.methods.iter().find(|m| m.name == name).expect("a method of the run");
            MethodRun {
                name: m.name.clone(),
                params: m.params.clone(),
                frames: m.frames[..frames].to_vec(),
                counters: m.counters.iter().map(|(k, v)| (k.clone(), v[..frames.min(v.len())].to_vec())).collect(),
            }
        };
        BenchRun {
            scene: SceneStats { frames, ..self.scene.clone() },
            methods: methods.iter().map(|&name| cut(name)).collect(),
            variants: Vec::new(),
            reference: self.reference[..frames].to_vec(),
            dumps: Vec::new(),
            adapter: self.adapter.clone(),
            // Stopped early only if it stopped before those frames' end.
            aborted: self.aborted.clone().filter(|_| frames == self.reference.len()),
            warnings: self
                .warnings
                .iter()
                .filter(|w| methods.iter().any(|m| w.strip_prefix(m).is_some_and(|rest| rest.starts_with(':'))))
                .cloned()
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small scene's walkthrough with the Table 1 lanes, `ideal` chained
    /// after `sw`, methods that use the thread pool themselves (`moc`) or
    /// keep state across frames (`chc`, `chcpp`), one that records its
    /// decisions (`om`, the dumped frame), and a variant.
    fn lanes_config() -> (BenchConfig, Vec<Variant>) {
        let methods = ["vfc", "sw", "chc", "ideal", "chcpp", "om", "moc", "opt"];
        let config = BenchConfig {
            methods: methods.map(String::from).to_vec(),
            frames: 8,
            resolution: (160, 112),
            hierarchy: occlude_core::HierarchyKind::KdTree,
            gpu_model: occlude_soft::GpuModel::gpu_2004(),
            dump_frame: Some(5),
            ..BenchConfig::default()
        };
        let variants = vec![Variant {
            method: "chc".into(),
            options: MethodOptions::parse(&["chc.tav=2", "chc.nvp=25"]).unwrap(),
        }];
        (config, variants)
    }

    /// `stats` without its wall-clock time, the one figure that depends on
    /// the machine.
    fn simulated(mut stats: FrameStats) -> FrameStats {
        stats.wall_ms = 0.0;
        stats
    }

    /// Lanes rendered side by side give, frame by frame, each lane's
    /// simulated statistics and depth image bit for bit as lanes rendered
    /// one after another.
    #[test]
    fn lanes_side_by_side_render_the_images_and_figures_of_lanes_one_by_one() {
        let (config, variants) = lanes_config();
        let scene = occlude_scenes::load("city", config.size, config.seed, &config.import).unwrap();
        let hierarchy = Hierarchy::build(&scene, config.hierarchy, config.build);
        let build = |parallel_lanes: bool| {
            let config = BenchConfig { parallel_lanes, ..config.clone() };
            let variants = variants.iter().map(Variant::create).collect::<Result<Vec<_>>>().unwrap();
            // Side by side with their set-up shared, one by one each its own.
            let renderer = Renderer::Soft(parallel_lanes.then(SharedSetup::new));
            build_lanes(&scene, &config, variants, &renderer).unwrap()
        };
        let (mut side_by_side, mut one_by_one) = (build(true), build(false));
        assert!(side_by_side.parallel && !one_by_one.parallel);
        assert_eq!(side_by_side.chains.len(), 8, "ideal shares sw's chain: {:?}", side_by_side.order);
        // Three threads, so that lanes overlap even on a one-core machine.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let mut drawn = 0;
        for camera in cameras(&scene, &config).unwrap() {
            pool.install(|| side_by_side.frame(&scene, &hierarchy, &camera)).unwrap();
            one_by_one.frame(&scene, &hierarchy, &camera).unwrap();
            for (a, b) in side_by_side.iter().zip(one_by_one.iter()) {
                let name = a.built.method.name();
                assert_eq!(simulated(a.stats), simulated(b.stats), "{name}");
                let bits = |image: &[f32]| image.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a.image), bits(&b.image), "{name}");
                assert_eq!(a.image.len(), 160 * 112, "{name}");
            }
            drawn += side_by_side.iter().next().unwrap().image.iter().filter(|&&d| d < 1.0).count();
        }
        assert!(drawn > 0, "the walkthrough sees geometry");
    }

    /// A run cut to its first frames and to some of its methods has, frame
    /// by frame, the simulated figures of a run of those methods over those
    /// frames alone.
    #[test]
    fn the_first_frames_of_a_run_are_a_shorter_run_of_some_of_its_methods() {
        let (config, _) = lanes_config();
        let config = BenchConfig { dump_frame: None, fps: Some(30.0), ..config };
        let scene = occlude_scenes::load("city", config.size, config.seed, &config.import).unwrap();
        let methods = ["vfc", "chcpp", "chc"];
        let shorter = BenchConfig { methods: methods.map(String::from).to_vec(), frames: 5, ..config.clone() };
        let (whole, alone) = (run_scene(&scene, &config, &()).unwrap(), run_scene(&scene, &shorter, &()).unwrap());
        let cut = whole.first_frames(&methods, 5);
        let simulated = |frames: &[FrameStats]| frames.iter().copied().map(simulated).collect::<Vec<_>>();
        assert_eq!((cut.scene.frames, cut.reference.len(), whole.reference.len()), (5, 5, 8));
        assert_eq!(simulated(&cut.reference), simulated(&alone.reference));
        assert_eq!(cut.methods.len(), 3);
        for (a, b) in cut.methods.iter().zip(&alone.methods) {
            assert_eq!((&a.name, &a.params), (&b.name, &b.params));
            assert_eq!(simulated(&a.frames), simulated(&b.frames), "{}", a.name);
            assert_eq!(a.counters, b.counters, "{}", a.name);
        }
        assert_ne!(simulated(&cut.methods[1].frames), simulated(&cut.methods[2].frames), "chcpp is not chc");
    }

    /// `ideal` on a backend replaying the counts of `sw`'s (as
    /// `build_lanes` wires them) gives, frame by frame over a walkthrough,
    /// the simulated statistics and depth image of an `ideal` that
    /// rasterizes the same draws itself.
    #[test]
    fn ideal_replaying_the_counts_of_sw_renders_the_figures_of_ideal_rasterizing() {
        let (config, _) = lanes_config();
        let scene = occlude_scenes::load("city", config.size, config.seed, &config.import).unwrap();
        let hierarchy = Hierarchy::build(&scene, config.hierarchy, config.build);
        let (calls, counts) = (DrawCalls::default(), DrawReplay::default());
        let backend = |draws| Renderer::Soft(None).backend(&scene, &config, draws).unwrap();
        let ideal = || BuiltMethod { method: Box::new(Ideal::new(Arc::clone(&calls))), params: Vec::new() };
        let vfc = Lane::new(create("vfc", &config.options).unwrap(), backend(Draws::Own));
        let mut lanes = Lanes::new(vfc, false);
        let sw = Box::new(DrawLog::new(backend(Draws::Record(counts.clone())), Arc::clone(&calls)));
        lanes.push(Lane::new(create("sw", &config.options).unwrap(), sw), None);
        lanes.push(Lane::new(ideal(), backend(Draws::Replay(counts))), Some(1));
        lanes.push(Lane::new(ideal(), backend(Draws::Own)), Some(1));
        let mut fragments = 0;
        for camera in cameras(&scene, &config).unwrap() {
            lanes.frame(&scene, &hierarchy, &camera).unwrap();
            let (replayed, rasterized) = (&lanes.chains[1][1], &lanes.chains[1][2]);
            assert_eq!(simulated(replayed.stats), simulated(rasterized.stats));
            let bits = |image: &[f32]| image.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&replayed.image), bits(&rasterized.image));
            fragments += rasterized.stats.fragments;
        }
        assert!(fragments > 0, "ideal draws something");
    }

    /// Everything a run records but wall-clock time: per method and
    /// variant its name, parameters, simulated statistics and counters;
    /// the reference; the dumped frame's images and decisions; warnings.
    fn figures(run: &BenchRun) -> String {
        let lane = |m: &MethodRun| {
            let frames: Vec<FrameStats> = m.frames.iter().copied().map(simulated).collect();
            format!("{} {:?} {frames:?} {:?}", m.name, m.params, m.counters)
        };
        let runs: Vec<String> = run.methods.iter().chain(&run.variants).map(lane).collect();
        let reference: Vec<FrameStats> = run.reference.iter().copied().map(simulated).collect();
        let dumps: Vec<String> = run
            .dumps
            .iter()
            .map(|d| {
                let bits: Vec<u32> = d.depth.iter().map(|x| x.to_bits()).collect();
                format!("{} {} {bits:?} {:?}", d.method, d.frame, d.view)
            })
            .collect();
        format!("{runs:#?}\n{reference:?}\n{dumps:?}\n{:?} {:?}", run.warnings, run.aborted)
    }

    /// A run with its lanes side by side records every figure of a run
    /// with its lanes one by one, and two such runs agree (determinism).
    #[test]
    fn a_run_with_lanes_side_by_side_gives_the_figures_of_one_with_lanes_in_turn() {
        let (config, variants) = lanes_config();
        let (scene, _) = load_scene(&config).unwrap();
        let run = |parallel_lanes: bool| {
            let config = BenchConfig { parallel_lanes, ..config.clone() };
            run_scene_with_variants(&scene, &config, &variants, &()).unwrap()
        };
        let one_by_one = run(false);
        // Every method is conservative; the variant (`nvp=25`) need not be.
        for m in &one_by_one.methods {
            assert!(m.frames.len() == 8 && m.frames.iter().all(|f| f.missing_pixels == 0), "{}", m.name);
        }
        assert_eq!((one_by_one.methods.len(), one_by_one.variants.len()), (8, 1));
        assert_eq!(one_by_one.dumps.iter().map(|d| (d.method.as_str(), d.frame)).collect::<Vec<_>>(), [("om", 5)]);
        let one_by_one = figures(&one_by_one);
        assert_eq!(figures(&run(true)), one_by_one);
        assert_eq!(figures(&run(true)), one_by_one);
    }

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
