//! The viewer's window and event loop: opening the window and the GPU that
//! can draw to it, running one method frame per redraw exactly as `bench`
//! does, and reacting to keys and the mouse.

use super::boxes::{geometry, of_box_tests, of_queries, BoxRenderer, Colouring, LEVEL_COLOURS};
use super::camera_control::{FlyCamera, Playback, DEFAULT_FOV_Y_DEG};
use super::input::{action, Action, HeldKeys};
use super::overlay::{Overlay, ShownStats, StatsAverage, REFRESH_SECONDS};
use super::path_recorder::{self, PathRecorder};
use super::present::{Blit, Presenter};
use super::{ViewConfig, ViewError};
use anyhow::{anyhow, bail, Context, Result};
use glam::Vec3;
use occlude_bench::config::{DEFAULT_FPS, NEAR_PLANE};
use occlude_bench::limits::MAX_FRAMES;
use occlude_bench::runner::{cameras, far_plane, load_scene};
use occlude_bench::BenchConfig;
use occlude_core::methods::{check_support, create, BuiltMethod, DrawnSet, METHOD_NAMES};
use occlude_core::recording::{RecordedBoxTest, RecordingBackend};
use occlude_core::render_frame;
use occlude_core::{Backend, Camera, Hierarchy, HierarchyKind, Keyframe, Scene};
use occlude_scenes::{Motion, OwnMotion};
use occlude_wgpu::{best_adapter, GpuContext, GpuError, GpuScene, WgpuBackend, COLOR_FORMAT};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{Window, WindowId};

/// Speed factor of one step of the mouse wheel.
const WHEEL_STEP: f32 = 1.25;

/// Longest time step the camera takes in one frame, seconds (a stall does
/// not throw the camera across the scene).
const MAX_STEP: f32 = 0.25;

/// Opens the window system, loads the scene and runs the viewer until its
/// window closes.
pub(super) fn run(config: &ViewConfig) -> Result<()> {
    let (scene, own) = load_scene(&config.scene)?;
    // The walkthrough as `--play` shows it, checked as bench checks its
    // frames at its default rate (playback itself follows the clock): a
    // path through its target is refused, naming the frame.
    if !scene.path.keyframes.is_empty() {
        let played = BenchConfig { fps: Some(DEFAULT_FPS), frames: MAX_FRAMES, ..config.scene.clone() };
        cameras(&scene, &played)?;
    }
    let event_loop = open_event_loop()?;
    let mut viewer = Viewer::new(&scene, own, config)?;
    event_loop.run_app(&mut viewer).map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    viewer.finish()
}

/// The event loop, or [`ViewError::NoDisplay`]. winit reports a missing
/// display as an error but panics on some broken ones (an X server without
/// the XKB extension, a missing libxkbcommon-x11): that panic is caught and
/// reported the same way, without its backtrace.
fn open_event_loop() -> Result<EventLoop<()>> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let opened = std::panic::catch_unwind(EventLoop::new);
    std::panic::set_hook(hook);
    match opened {
        Ok(Ok(event_loop)) => Ok(event_loop),
        Ok(Err(e)) => Err(ViewError::NoDisplay(os_message(&e.to_string())).into()),
        Err(panic) => {
            let why = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "the window system failed".into());
            Err(ViewError::NoDisplay(why).into())
        }
    }
}

/// winit's message without the source location it puts before an OS error
/// ("os error at path/to/winit/src/file.rs:765: what happened").
fn os_message(message: &str) -> String {
    let located = message.strip_prefix("os error at ").and_then(|rest| rest.split_once(".rs:"));
    match located.and_then(|(_, rest)| rest.split_once(": ")) {
        Some((_, what)) => what.to_string(),
        None => message.to_string(),
    }
}

/// The GPU side of the viewer, made once the window exists.
struct Gpu {
    window: Arc<Window>,
    adapter: String,
    scene: Arc<GpuScene>,
    backend: RecordingBackend<WgpuBackend>,
    /// The backend's colour image, bound for presenting.
    frame: wgpu::BindGroup,
    blit: Blit,
    presenter: Presenter,
    boxes: BoxRenderer,
    overlay: Overlay,
}

impl Gpu {
    /// Opens the window, an adapter that can draw to it and its device, and
    /// uploads the scene.
    fn open(event_loop: &ActiveEventLoop, scene: &Scene, config: &ViewConfig) -> Result<Self> {
        let (w, h) = config.scene.resolution;
        let attributes = Window::default_attributes()
            .with_title(format!("occlude view: {} ({})", config.scene.scene, config.scene.size))
            .with_inner_size(PhysicalSize::new(w, h))
            .with_resizable(config.screenshot.is_none());
        let window = Arc::new(
            event_loop.create_window(attributes).map_err(|e| ViewError::NoDisplay(os_message(&e.to_string())))?,
        );
        let display = Box::new(event_loop.owned_display_handle());
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(display));
        // No backend that can make a surface for the window means no adapter
        // for it either.
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| GpuError::NoAdapter(format!("no graphics backend can draw to the window: {e}")))?;
        let adapter = best_adapter(&instance, Some(&surface))?;
        let ctx = Arc::new(GpuContext::open(&adapter)?);
        let gpu_scene = Arc::new(GpuScene::new(Arc::clone(&ctx), scene)?);
        let device = &ctx.device;
        let blit = Blit::new(device);
        let presenter = Presenter::new(surface, &adapter, device, &blit, window.inner_size().into())?;
        let size = if config.screenshot.is_some() { (w, h) } else { window.inner_size().into() };
        let backend = RecordingBackend::new(WgpuBackend::new(Arc::clone(&gpu_scene), scene, size.0, size.1));
        Ok(Self {
            frame: blit.bind(device, backend.inner().color_view()),
            boxes: BoxRenderer::new(device, COLOR_FORMAT),
            overlay: Overlay::new(device, &blit, COLOR_FORMAT),
            adapter: format!("{} ({:?})", ctx.info.name, ctx.info.backend),
            window,
            scene: gpu_scene,
            backend,
            blit,
            presenter,
        })
    }

    fn ctx(&self) -> &GpuContext {
        self.scene.context()
    }

    /// Whether the adapter runs `method`: one that needs GPU-resident
    /// culling is refused, naming what the device lacks (as `bench` refuses
    /// it), rather than left to its view-frustum fallback.
    fn supports(&mut self, method: &BuiltMethod) -> Result<()> {
        let method = method.method.as_ref();
        check_support(method, &mut self.backend)
            .map_err(|e| anyhow::Error::new(e).context(format!("method {} cannot run", method.name())))
    }

    /// Renders from now on at `width` x `height` (a new backend; the
    /// method's state is kept).
    fn resize_backend(&mut self, scene: &Scene, (width, height): (u32, u32)) {
        if width == 0 || height == 0 || self.backend.inner().size() == (width, height) {
            return;
        }
        self.backend = RecordingBackend::new(WgpuBackend::new(Arc::clone(&self.scene), scene, width, height));
        self.frame = self.blit.bind(&self.ctx().device, self.backend.inner().color_view());
    }

    /// Draws the recorded boxes (when asked: `Some` of which box test,
    /// `None` inside for all), coloured as `colouring` says, and the overlay
    /// over the frame just rendered, and shows it in the window.
    fn compose(&mut self, camera: &Camera, boxes: Option<Option<usize>>, colouring: Colouring) {
        let ctx = Arc::clone(self.scene.context());
        let target = self.backend.inner().color_view();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        if let Some(shown_test) = boxes {
            let tests = self.backend.box_tests();
            let tests = match shown_test {
                Some(k) => tests.get(k..=k).unwrap_or_default(),
                None => tests,
            };
            let geometry = geometry(of_queries(self.backend.queries()).chain(of_box_tests(tests)), colouring);
            self.boxes.draw(&ctx.device, &ctx.queue, &mut encoder, target, camera, &geometry);
        }
        self.overlay.draw(&mut encoder, target);
        ctx.queue.submit([encoder.finish()]);
        self.presenter.present(&ctx.device, &ctx.queue, &self.frame);
    }

    /// Writes the last composed frame to `path` as a PNG.
    fn screenshot(&mut self, path: &std::path::Path) -> Result<()> {
        let (w, h) = self.backend.inner().size();
        let rgba = self.backend.inner_mut().color_image().map_err(|e| anyhow!("reading the frame back: {e}"))?;
        let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        image::save_buffer_with_format(path, &rgb, w, h, image::ColorType::Rgb8, image::ImageFormat::Png)
            .with_context(|| format!("cannot write screenshot {}", path.display()))
    }
}

/// Everything the viewer keeps between frames.
struct Viewer<'s> {
    /// The scene as it moves (its own motion, `--motion`), or as loaded.
    scene: Scene,
    /// How it moves, and since when (seconds of viewing).
    motion: Option<Motion>,
    motion_time: f32,
    config: &'s ViewConfig,
    far: f32,
    hierarchy_kind: HierarchyKind,
    hierarchy: Hierarchy,
    method_index: usize,
    method: BuiltMethod,
    drawn: DrawnSet,
    fly: FlyCamera,
    /// Fly speed, metres per second.
    speed: f32,
    playback: Playback,
    playing: bool,
    recording: Option<PathRecorder>,
    show_boxes: bool,
    /// What the boxes' colours show (key Z).
    colouring: Colouring,
    /// The one box test shown (key L), or all of them.
    shown_test: Option<usize>,
    held: HeldKeys,
    /// A mouse button is held: cursor motion turns the camera.
    looking: bool,
    /// Where the cursor was last seen in the window.
    cursor: Option<PhysicalPosition<f64>>,
    frames: usize,
    last_frame: Instant,
    last_refresh: Option<Instant>,
    average: StatsAverage,
    shown: ShownStats,
    gpu: Option<Gpu>,
    outcome: Result<()>,
}

impl<'s> Viewer<'s> {
    fn new(scene: &'s Scene, own: Option<OwnMotion>, config: &'s ViewConfig) -> Result<Self> {
        let method_index = METHOD_NAMES.iter().position(|&m| m == config.method).context("unknown method")?;
        let start = Playback::default().keyframe(&scene.path).unwrap_or_else(|| overview(scene));
        Ok(Self {
            scene: scene.clone(),
            motion: Motion::new(scene, own, config.scene.motion, config.scene.seed),
            motion_time: 0.0,
            config,
            far: far_plane(scene),
            hierarchy_kind: config.scene.hierarchy,
            hierarchy: Hierarchy::build(scene, config.scene.hierarchy, config.scene.build),
            method_index,
            method: create(&config.method, &config.scene.options)?,
            drawn: DrawnSet::default(),
            fly: FlyCamera::from_keyframe(&start),
            speed: cruise_speed(scene),
            playback: Playback::default(),
            playing: config.play,
            recording: None,
            show_boxes: config.figure4 || config.pyramid_levels,
            colouring: if config.pyramid_levels { Colouring::PyramidLevel } else { Colouring::Outcome },
            shown_test: None,
            held: HeldKeys::default(),
            looking: false,
            cursor: None,
            frames: 0,
            last_frame: Instant::now(),
            last_refresh: None,
            average: StatsAverage::default(),
            shown: ShownStats::default(),
            gpu: None,
            outcome: Ok(()),
        })
    }

    /// Stops the event loop with `error` as the viewer's outcome.
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        if self.outcome.is_ok() {
            self.outcome = Err(error);
        }
        event_loop.exit();
    }

    /// After the event loop: a recording still running is written, then
    /// the outcome.
    fn finish(mut self) -> Result<()> {
        let stopped = self.stop_recording();
        self.outcome.and(stopped)
    }

    fn stop_recording(&mut self) -> Result<()> {
        if let Some(recorder) = self.recording.take() {
            let path = recorder.finish(&self.fly);
            path_recorder::write(&path, &self.config.record)?;
            eprintln!("wrote camera path {} ({} keyframes)", self.config.record.display(), path.keyframes.len());
        }
        Ok(())
    }

    /// Switches to method `index` of `METHOD_NAMES`, fresh (no state from
    /// earlier frames, which may refer to another hierarchy).
    fn set_method(&mut self, index: usize) {
        let built =
            create(METHOD_NAMES[index], &self.config.scene.options).map_err(anyhow::Error::from).and_then(|b| {
                self.gpu.as_mut().map_or(Ok(()), |g| g.supports(&b))?;
                Ok(b)
            });
        match built {
            Ok(built) => {
                self.method = built;
                self.method_index = index;
                self.drawn = DrawnSet::default();
                self.average.take();
                self.last_refresh = None;
            }
            Err(e) => eprintln!("cannot switch to {}: {e}", METHOD_NAMES[index]),
        }
    }

    fn act(&mut self, event_loop: &ActiveEventLoop, action: Action) -> Result<()> {
        match action {
            Action::Method(i) => self.set_method(i),
            Action::NextMethod => self.set_method((self.method_index + 1) % METHOD_NAMES.len()),
            Action::ToggleHierarchy => {
                self.hierarchy_kind = match self.hierarchy_kind {
                    HierarchyKind::Bvh => HierarchyKind::KdTree,
                    HierarchyKind::KdTree => HierarchyKind::Bvh,
                };
                self.hierarchy = Hierarchy::build(&self.scene, self.hierarchy_kind, self.config.scene.build);
                self.set_method(self.method_index);
            }
            Action::ToggleBoxes => self.show_boxes = !self.show_boxes,
            Action::TogglePyramidLevels => {
                self.colouring = match self.colouring {
                    Colouring::Outcome => Colouring::PyramidLevel,
                    Colouring::PyramidLevel => Colouring::Outcome,
                };
                self.show_boxes = true;
            }
            Action::NextBoxTest => {
                let tests = self.gpu.as_ref().map_or(0, |g| g.backend.box_tests().len());
                self.shown_test = match self.shown_test {
                    None if tests > 0 => Some(0),
                    Some(k) if k + 1 < tests => Some(k + 1),
                    _ => None,
                };
            }
            Action::TogglePlayback => self.playing = !self.playing,
            Action::ToggleRecording => match self.recording {
                Some(_) => self.stop_recording()?,
                None => self.recording = Some(PathRecorder::start(&self.fly)),
            },
            Action::Quit => event_loop.exit(),
        }
        self.last_refresh = None;
        Ok(())
    }

    /// Moves the camera by `dt` seconds: along the walkthrough while it
    /// plays (in a screenshot, frame k of N samples it as `bench` does),
    /// else as the held keys say.
    fn move_camera(&mut self, dt: f32) {
        if self.playing {
            let path = &self.scene.path;
            match self.config.screenshot {
                Some(_) => self.playback = Playback::sampled(path, self.frames, self.config.scene.frames),
                None => self.playback.advance(path, dt),
            }
            if let Some(k) = self.playback.keyframe(path) {
                self.fly = FlyCamera::from_keyframe(&k);
            }
        } else {
            self.fly.step(&self.held.movement(), self.speed, dt);
        }
        if let Some(recorder) = &mut self.recording {
            recorder.sample(&self.fly, dt);
        }
    }

    /// Renders, composes and shows one frame; writes the screenshot and
    /// stops after the last frame of a screenshot run.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32().min(MAX_STEP);
        self.last_frame = now;
        self.move_camera(dt);
        let Some(gpu) = self.gpu.as_mut() else { return Ok(()) };
        if let Some(motion) = &self.motion {
            // The scene moves while you fly: its boxes (key V) follow. A
            // screenshot run steps it as `bench` does, one frame at its
            // default frame rate, so that the picture does not depend on
            // how fast the machine draws.
            self.motion_time += if self.config.screenshot.is_some() { 1.0 / DEFAULT_FPS } else { dt };
            let changed = self.scene.apply(&motion.changes_at(self.motion_time))?;
            self.hierarchy.update(&self.scene, &changed, self.config.scene.update_policy);
            gpu.backend.update_instances(&self.scene, &changed);
        }
        let (w, h) = gpu.backend.inner().size();
        let camera = self.fly.camera(w as f32 / h as f32, NEAR_PLANE, self.far);
        gpu.backend.set_recording(self.show_boxes);
        let stats = render_frame(
            self.method.method.as_mut(),
            &mut gpu.backend,
            &self.scene,
            &self.hierarchy,
            &camera,
            &mut self.drawn,
        );
        if let Some(e) = gpu.backend.failure() {
            bail!("the GPU failed: {e}");
        }
        self.average.add(stats);
        self.frames += 1;
        let last = self.config.screenshot.is_some() && self.frames >= self.config.scene.frames;
        if last || self.last_refresh.is_none_or(|t| t.elapsed().as_secs_f32() >= REFRESH_SECONDS) {
            self.shown = self.average.take().unwrap_or(self.shown);
            self.last_refresh = Some(now);
            let lines = self.overlay_lines();
            let gpu = self.gpu.as_mut().expect("checked above");
            let ctx = Arc::clone(gpu.scene.context());
            gpu.overlay.update(&ctx.device, &ctx.queue, &gpu.blit, &lines, (w, h))?;
        }
        let gpu = self.gpu.as_mut().expect("checked above");
        gpu.compose(&camera, self.show_boxes.then_some(self.shown_test), self.colouring);
        if let (true, Some(path)) = (last, &self.config.screenshot) {
            gpu.screenshot(path)?;
            eprintln!("wrote {} ({w}x{h}, frame {} of {})", path.display(), self.frames, self.config.scene.frames);
            event_loop.exit();
        }
        Ok(())
    }

    /// The overlay's text: what runs, its statistics, the camera's mode and
    /// the keys.
    fn overlay_lines(&self) -> Vec<String> {
        let adapter = self.gpu.as_ref().map_or("", |g| g.adapter.as_str());
        let mut lines = vec![format!("{} on {}   {adapter}", METHOD_NAMES[self.method_index], self.hierarchy_kind)];
        lines.extend(self.shown.lines());
        let mut mode = if self.playing {
            format!("walkthrough {:.1} / {:.1} s", self.playback.elapsed, self.scene.path.duration())
        } else {
            format!("flying at {:.1} m/s", self.speed)
        };
        if let Some(r) = &self.recording {
            mode += &format!("   recording path ({} keyframes)", r.keyframes());
        }
        lines.push(mode);
        if self.show_boxes {
            let tests = self.gpu.as_ref().map_or(&[][..], |g| g.backend.box_tests());
            match self.colouring {
                Colouring::Outcome => lines.push("query boxes: green visible, red occluded, yellow never read".into()),
                Colouring::PyramidLevel => lines.extend(level_lines(tests, self.shown_test)),
            }
            lines.extend(box_test_line(tests, self.shown_test));
        }
        lines.push(format!(
            "1-{}/M method  H hierarchy  V boxes  L box test  Z levels  P play  R record",
            METHOD_NAMES.len()
        ));
        lines.push("WASD QE: fly  Shift: fast  wheel: speed  drag: look".into());
        lines
    }
}

impl ApplicationHandler for Viewer<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match Gpu::open(event_loop, &self.scene, self.config) {
            Ok(mut gpu) => match gpu.supports(&self.method) {
                Ok(()) => {
                    gpu.window.request_redraw();
                    self.gpu = Some(gpu);
                }
                Err(e) => self.fail(event_loop, e),
            },
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _window: WindowId, event: WindowEvent) {
        let handled = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => self.frame(event_loop),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = self.gpu.as_mut() {
                    let size: (u32, u32) = size.into();
                    gpu.presenter.resize(&gpu.scene.context().device, size);
                    if self.config.screenshot.is_none() {
                        gpu.resize_backend(&self.scene, size);
                    }
                }
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                let pressed = event.state == ElementState::Pressed;
                self.held.set(code, pressed);
                match action(code).filter(|_| pressed && !event.repeat) {
                    Some(a) => self.act(event_loop, a),
                    None => Ok(()),
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left | MouseButton::Right, .. } => {
                self.looking = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some(last) = self.cursor.replace(position).filter(|_| self.looking) {
                    self.fly.turn((position.x - last.x) as f32, (position.y - last.y) as f32);
                }
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.speed = (self.speed * WHEEL_STEP.powf(steps)).clamp(0.01, 1e5);
                self.last_refresh = None;
                Ok(())
            }
            WindowEvent::Focused(false) => {
                self.held.clear();
                self.looking = false;
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = handled {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gpu) = &self.gpu {
            gpu.window.request_redraw();
        }
    }
}

/// The overlay lines of the pyramid-level colouring: the legend, then how
/// many of the shown box tests' boxes were tested at each level.
fn level_lines(tests: &[RecordedBoxTest], shown: Option<usize>) -> [String; 3] {
    let last = LEVEL_COLOURS.len() - 1;
    let legend: Vec<String> = LEVEL_COLOURS
        .iter()
        .enumerate()
        .map(|(k, (name, _))| if k == last { format!("{k}+ {name}") } else { format!("{k} {name}") })
        .collect();
    let (finer, coarser) = legend.split_at(LEVEL_COLOURS.len() / 2);
    let tests = match shown {
        Some(k) => tests.get(k..=k).unwrap_or_default(),
        None => tests,
    };
    let mut per_level = std::collections::BTreeMap::<Option<u32>, usize>::new();
    for level in tests.iter().flat_map(|t| &t.levels) {
        *per_level.entry(*level).or_default() += 1;
    }
    let counts: Vec<String> = per_level
        .iter()
        .map(|(level, n)| match level {
            Some(k) => format!("{k}:{n}"),
            None => format!("none:{n}"),
        })
        .collect();
    [
        format!("pyramid level tested: {}", finer.join("  ")),
        format!("{}  grey none, filled hidden", coarser.join("  ")),
        format!("boxes per level: {}", if counts.is_empty() { "no box test".into() } else { counts.join(" ") }),
    ]
}

/// The overlay line of the frame's box tests (`ioc`: one per level): each
/// batch's visible and tested boxes, the shown one in brackets; `None`
/// without box tests.
fn box_test_line(tests: &[RecordedBoxTest], shown: Option<usize>) -> Option<String> {
    let batches: Vec<String> = tests
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let counts = format!("{}/{}", t.visible_count(), t.boxes.len());
            if shown == Some(k) {
                format!("[{counts}]")
            } else {
                counts
            }
        })
        .collect();
    (!batches.is_empty()).then(|| format!("box tests, visible/tested: {}", batches.join(" ")))
}

/// A view of the whole scene from above one side, for a scene without a
/// walkthrough.
fn overview(scene: &Scene) -> Keyframe {
    let bounds = scene.bounds();
    let target = bounds.center();
    let position = target + Vec3::new(0.0, 0.5, 1.0) * bounds.extent().length().max(1.0);
    Keyframe { time: 0.0, position, target, fov_y_deg: DEFAULT_FOV_Y_DEG }
}

/// The fly speed to start with: the walkthrough's mean speed, or a
/// twentieth of the scene's size per second without one.
fn cruise_speed(scene: &Scene) -> f32 {
    let k = &scene.path.keyframes;
    let length: f32 = k.windows(2).map(|w| w[0].position.distance(w[1].position)).sum();
    let duration = scene.path.duration();
    let speed =
        if duration > 0.0 && length > 0.0 { length / duration } else { scene.bounds().extent().length() / 20.0 };
    speed.max(0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn winit_os_errors_lose_their_source_location() {
        let located = "os error at /home/x/winit-0.30.13/src/platform_impl/linux/mod.rs:788: Failed to open connection";
        assert_eq!(os_message(located), "Failed to open connection");
        assert_eq!(os_message("the event loop can't be recreated"), "the event loop can't be recreated");
    }
}
