//! The viewer's window (winit): flies through a glTF or OBJ model or a
//! generated scene with the library's renderer, its animations playing,
//! culling switched by keys, the frame's counts and the culling passes' GPU
//! time in the title. `--screenshot` renders off-screen instead and writes
//! the last frame as a PNG.
//!
//! `cargo run --release -p gltf-viewer -- [FILE.gltf|FILE.glb|FILE.obj|SCENE] [--size small|medium|paper]
//! [--culling off|hiz|roc|ioc|chcpp|chc|vfc|...] [--frames N] [--resolution WxH] [--screenshot FILE.png]`

use gltf_viewer::{open_device, request_device, start, Drawn, Fly, Offscreen, Renderer};
use occlude::methods::Method;
use occlude::scenes::{load_moving, ImportOptions, Size};
use std::error::Error;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The culling modes key M steps through.
const MODES: [&str; 7] = ["hiz", "chcpp", "roc", "ioc", "chc", "vfc", "off"];
/// Seconds between updates of the title.
const REFRESH_SECONDS: f32 = 0.25;
/// Seconds of motion per frame of a screenshot run (30 frames a second).
const SCREENSHOT_STEP: f32 = 1.0 / 30.0;
/// Radians the arrow keys turn per second.
const TURN_RATE: f32 = 1.5;
/// Radians the view turns per pixel the mouse moves.
const TURN_PER_PIXEL: f32 = 0.004;

/// What the command line asks for.
struct Args {
    scene: String,
    size: Size,
    culling: String,
    frames: u32,
    resolution: (u32, u32),
    screenshot: Option<PathBuf>,
}

fn main() {
    if let Err(e) = run() {
        eprintln!("gltf-viewer: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn Error>> {
    let args = parse_args()?;
    let (scene, motion) = load_moving(&args.scene, args.size, 1, &ImportOptions::default())?;
    println!(
        "{}: {} meshes, {} instances, {} triangles{}",
        scene.name,
        scene.meshes.len(),
        scene.instances.len(),
        scene.triangle_count(),
        if motion.is_some() { ", moving" } else { "" }
    );
    let method = parse_culling(&args.culling)?;
    let Some(path) = &args.screenshot else {
        let event_loop = EventLoop::new().map_err(|e| format!("cannot open a window: {e}"))?;
        let mut app = App { args: &args, method, scene: Some((scene, motion)), window: None, outcome: Ok(()) };
        event_loop.run_app(&mut app)?;
        return app.outcome;
    };
    let (device, queue) = open_device()?;
    let (w, h) = args.resolution;
    let target = Offscreen::new(&device, w, h);
    let fly = Fly::from_keyframe(&start(&scene));
    let bounds = scene.bounds();
    let mut renderer = Renderer::new(device, queue, scene, motion, Offscreen::FORMAT);
    renderer.set_culling(method)?;
    for frame in 0..args.frames {
        renderer.set_time(frame as f32 * SCREENSHOT_STEP)?;
        renderer.render(&target.view(), fly.view(), fly.projection(w as f32 / h as f32, &bounds))?;
    }
    println!("{}", describe(&args.culling, &renderer, renderer.drawn()?));
    target.save_png(&renderer, path)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The command line, checked.
fn parse_args() -> Result<Args, Box<dyn Error>> {
    let mut args = Args {
        scene: "crowd".into(),
        size: Size::Small,
        culling: "hiz".into(),
        frames: 30,
        resolution: (1280, 720),
        screenshot: None,
    };
    let mut given = std::env::args().skip(1);
    while let Some(arg) = given.next() {
        let mut value = || given.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--size" => args.size = value()?.parse()?,
            "--culling" => args.culling = value()?,
            "--frames" => args.frames = value()?.parse().map_err(|e| format!("--frames: {e}"))?,
            "--resolution" => {
                let v = value()?;
                let parsed = v.split_once('x').and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
                args.resolution =
                    parsed.filter(|&(w, h)| w > 0 && h > 0).ok_or(format!("--resolution {v}: expected WxH"))?;
            }
            "--screenshot" => args.screenshot = Some(value()?.into()),
            flag if flag.starts_with('-') => return Err(format!("unknown option '{flag}' (see the README)").into()),
            _ => args.scene = arg,
        }
    }
    if args.frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    if args.screenshot.as_ref().is_some_and(|p| !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))) {
        return Err("--screenshot names a .png file".into());
    }
    Ok(args)
}

/// `off` or an occlude method with its parameters.
fn parse_culling(culling: &str) -> Result<Option<Method>, Box<dyn Error>> {
    Ok((culling != "off").then(|| culling.parse()).transpose()?)
}

/// The overlay's line: the culling mode, what was drawn and culled, and
/// the culling passes' GPU time.
fn describe(mode: &str, renderer: &Renderer, drawn: Drawn) -> String {
    let scene = renderer.scene();
    let shown: Vec<usize> = (0..scene.instances.len()).filter(|&i| scene.instances[i].enabled).collect();
    let triangles: u64 = shown.iter().map(|&i| scene.instance_triangles(i)).sum();
    let gpu = drawn.culling_gpu_ms.map_or_else(|| "-".into(), |ms| format!("{ms:.2} ms"));
    format!(
        "{mode}: drew {} instances ({} culled), {} triangles ({} culled); culling GPU time {gpu}",
        drawn.instances,
        shown.len() as u64 - drawn.instances.min(shown.len() as u64),
        drawn.triangles,
        triangles - drawn.triangles.min(triangles),
    )
}

/// The window, once open.
struct Open {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    view_format: wgpu::TextureFormat,
    renderer: Renderer,
    fly: Fly,
    /// Fly speed, metres per second.
    speed: f32,
    mode: usize,
    held: Vec<KeyCode>,
    /// A mouse button is held: moving the cursor turns the camera.
    looking: bool,
    cursor: Option<(f64, f64)>,
    /// Seconds of the scene's motion, and whether it plays.
    time: f32,
    playing: bool,
    last_frame: Instant,
    last_title: Instant,
    frame_ms: f32,
}

/// The viewer's event handler: the scene until the window opens, then the
/// window.
struct App<'a> {
    args: &'a Args,
    method: Option<Method>,
    scene: Option<(occlude::Scene, Option<occlude::scenes::OwnMotion>)>,
    window: Option<Open>,
    outcome: Result<(), Box<dyn Error>>,
}

impl App<'_> {
    /// Opens the window, its device and the renderer.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), Box<dyn Error>> {
        let Some((scene, motion)) = self.scene.take() else { return Ok(()) };
        let (w, h) = self.args.resolution;
        let attributes = Window::default_attributes()
            .with_title(format!("gltf-viewer: {}", scene.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let display = Box::new(event_loop.owned_display_handle());
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(display));
        let surface = instance.create_surface(Arc::clone(&window))?;
        let options = wgpu::RequestAdapterOptions { compatible_surface: Some(&surface), ..Default::default() };
        let adapter = pollster::block_on(instance.request_adapter(&options))?;
        let (device, queue) = request_device(&adapter)?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("the GPU adapter cannot draw to this window")?;
        // The renderer's colours reach the screen unchanged: drawn into a
        // view of the surface without sRGB encoding.
        let view_format = config.format.remove_srgb_suffix();
        config.view_formats.push(view_format);
        surface.configure(&device, &config);
        let fly = Fly::from_keyframe(&start(&scene));
        let speed = (scene.bounds().extent().length() / 20.0).clamp(1.0, 50.0);
        let mut renderer = Renderer::new(device, queue, scene, motion, view_format);
        renderer.set_culling(self.method.clone())?;
        let mode = MODES.iter().position(|&m| m == self.args.culling).unwrap_or(MODES.len());
        self.window = Some(Open {
            window,
            surface,
            config,
            view_format,
            renderer,
            fly,
            speed,
            mode,
            held: Vec::new(),
            looking: false,
            cursor: None,
            time: 0.0,
            playing: true,
            last_frame: Instant::now(),
            last_title: Instant::now(),
            frame_ms: 0.0,
        });
        Ok(())
    }
}

impl Open {
    /// Moves the camera and the scene by the time since the last frame,
    /// draws the frame into the window and, a few times a second, puts what
    /// it drew in the title.
    fn frame(&mut self) -> Result<(), Box<dyn Error>> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32().min(0.1);
        self.last_frame = now;
        let axis = |plus: KeyCode, minus: KeyCode| {
            f32::from(u8::from(self.held.contains(&plus))) - f32::from(u8::from(self.held.contains(&minus)))
        };
        let fast = if self.held.contains(&KeyCode::ShiftLeft) { 4.0 } else { 1.0 };
        let step = self.speed * fast * dt;
        let (forward, right, up) = (
            axis(KeyCode::KeyW, KeyCode::KeyS),
            axis(KeyCode::KeyD, KeyCode::KeyA),
            axis(KeyCode::KeyE, KeyCode::KeyQ),
        );
        self.fly.step(forward * step, right * step, up * step);
        let turn = TURN_RATE * dt;
        self.fly.turn(
            axis(KeyCode::ArrowRight, KeyCode::ArrowLeft) * turn,
            axis(KeyCode::ArrowUp, KeyCode::ArrowDown) * turn,
        );
        if self.playing {
            self.time += dt;
        }
        self.renderer.set_time(self.time)?;
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.reconfigure();
                return Ok(());
            }
            _ => return Ok(()),
        };
        let view = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor { format: Some(self.view_format), ..Default::default() });
        let aspect = self.config.width as f32 / self.config.height as f32;
        let bounds = self.renderer.scene().bounds();
        self.renderer.render(&view, self.fly.view(), self.fly.projection(aspect, &bounds))?;
        self.window.pre_present_notify();
        self.renderer.queue().present(texture);
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * dt * 1e3;
        if self.last_title.elapsed().as_secs_f32() >= REFRESH_SECONDS {
            self.last_title = Instant::now();
            let mode = MODES.get(self.mode).copied().unwrap_or("custom");
            let line = describe(mode, &self.renderer, self.renderer.drawn()?);
            self.window.set_title(&format!("{line}; frame {:.1} ms  [M culling, O off, Space pause]", self.frame_ms));
        }
        Ok(())
    }

    /// Configures the surface again at the window's size.
    fn reconfigure(&mut self) {
        let size = self.window.inner_size();
        if size.width > 0 && size.height > 0 {
            self.config.width = size.width;
            self.config.height = size.height;
            self.surface.configure(self.renderer.device(), &self.config);
        }
    }

    /// Switches to culling mode `mode` of [`MODES`].
    fn set_mode(&mut self, mode: usize) -> Result<(), Box<dyn Error>> {
        self.renderer.set_culling(parse_culling(MODES[mode])?)?;
        self.mode = mode;
        Ok(())
    }

    /// A key pressed (not a repeat).
    fn key(&mut self, event_loop: &ActiveEventLoop, key: KeyCode) -> Result<(), Box<dyn Error>> {
        let off = MODES.len() - 1;
        match key {
            KeyCode::KeyM => self.set_mode((self.mode + 1) % off)?,
            KeyCode::KeyO if self.mode == off => self.set_mode(0)?,
            KeyCode::KeyO => self.set_mode(off)?,
            KeyCode::Space => self.playing = !self.playing,
            KeyCode::Escape => event_loop.exit(),
            _ => {}
        }
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.open(event_loop) {
            self.outcome = Err(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _window: WindowId, event: WindowEvent) {
        let Some(open) = self.window.as_mut() else { return };
        let handled = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => open.frame(),
            WindowEvent::Resized(_) => {
                open.reconfigure();
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                open.held.retain(|&k| k != code);
                if event.state == ElementState::Pressed {
                    open.held.push(code);
                }
                match event.state == ElementState::Pressed && !event.repeat {
                    true => open.key(event_loop, code),
                    false => Ok(()),
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                open.looking = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = open.cursor.replace((position.x, position.y)).filter(|_| open.looking) {
                    open.fly.turn((position.x - x) as f32 * TURN_PER_PIXEL, (y - position.y) as f32 * TURN_PER_PIXEL);
                }
                Ok(())
            }
            WindowEvent::Focused(false) => {
                open.held.clear();
                open.looking = false;
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = handled {
            self.outcome = Err(e);
            event_loop.exit();
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(open) = &self.window {
            open.window.request_redraw();
        }
    }
}
