//! A viewer's renderer of its own for any scene occlude loads (glTF, OBJ,
//! a generated scene), drawing into any colour texture: one vertex and
//! index buffer holding every mesh, each instance's transform and base
//! colour (hashed from its material) in a storage buffer, flat shading
//! under one directional light. The scene's own motion (glTF animations, a
//! generated scene's script) moves the instances. With culling off every
//! instance is drawn, one draw each; with culling on, occlude's
//! GPU-driven `hiz`, `roc` or `ioc` writes lists of the visible instances
//! on the GPU, drawn with one multi-draw each (`vs_listed`), or a
//! query-driven method (`chcpp`, ...) calls this renderer's draw code with
//! the instances it finds visible.
//!
//! The lines that integrate occlude are marked `occlude:` (counted in the
//! README). The window is `main.rs`'s; tests draw off-screen ([`Offscreen`]).

mod camera;
mod instruments;

pub use camera::{Fly, NEAR};

use glam::{Mat4, Vec3};
use instruments::{read_buffer, Tally, Timer, TIMER_FEATURES};
use occlude::methods::Method;
use occlude::scenes::OwnMotion;
use occlude::wgpu::embed::{AnyCuller, Attachments, Draws, FrameTarget, IndirectDraw, InstanceDraw, DRAW_FEATURES};
use occlude::wgpu::embed::{VisibleList, RASTER_FEATURES};
use occlude::{Camera, Instance, Keyframe, Scene};
use std::error::Error;
use wgpu::util::DeviceExt;

/// Background colour.
const CLEAR_COLOR: wgpu::Color = wgpu::Color { r: 0.62, g: 0.74, b: 0.86, a: 1.0 };
/// The depth buffer's format (its image can be read back).
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A device and queue on the first adapter wgpu finds (`WGPU_BACKEND` and
/// `WGPU_ADAPTER_NAME` narrow the choice), for drawing off-screen.
pub fn open_device() -> Result<(wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    request_device(&adapter)
}

/// `adapter`'s device with the features occlude and the GPU timer use
/// where the adapter has them.
pub fn request_device(adapter: &wgpu::Adapter) -> Result<(wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    // occlude: forced early depth tests (`roc`, `ioc`) and multi-mesh draws.
    let wanted = RASTER_FEATURES | DRAW_FEATURES | TIMER_FEATURES;
    let descriptor = wgpu::DeviceDescriptor { required_features: adapter.features() & wanted, ..Default::default() };
    Ok(pollster::block_on(adapter.request_device(&descriptor))?)
}

/// Where the camera starts: the walkthrough's first eye, or for a scene
/// without one a view of all of it from above one side.
pub fn start(scene: &Scene) -> Keyframe {
    scene.path.keyframes.first().copied().unwrap_or_else(|| {
        let bounds = scene.bounds();
        let position = bounds.center() + Vec3::new(0.0, 0.5, 1.0) * bounds.extent().length().max(1.0);
        Keyframe { time: 0.0, position, target: bounds.center(), fov_y_deg: 60.0 }
    })
}

/// What the last frame drew, for the overlay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drawn {
    /// Instances drawn.
    pub instances: u64,
    /// Their triangles.
    pub triangles: u64,
    /// The GPU time of occlude's GPU-driven culling passes, milliseconds;
    /// `None` for a query-driven method (its queries are inside the draw
    /// passes), with culling off, or without timestamp queries.
    pub culling_gpu_ms: Option<f64>,
}

/// Where a mesh lies in the vertex and index buffers.
#[derive(Clone, Copy, Debug)]
struct MeshRange {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
}

/// One instance as the shader reads it: transform, then base colour and
/// material id.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct InstanceData {
    transform: [f32; 16],
    color: [f32; 4],
}

/// The renderer: its pipelines and buffers, the scene as it moves, and the
/// culling method.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    color_format: wgpu::TextureFormat,
    scene: Scene,
    motion: Option<OwnMotion>,
    draw: DrawState,
    uniforms: wgpu::Buffer,
    /// The depth buffer, made at the first target's size.
    depth: Option<wgpu::Texture>,
    /// occlude: the culling method, when culling is on.
    culling: Option<AnyCuller>,
    timer: Option<Timer>,
    tally: Tally,
    /// Triangles of each instance's mesh.
    triangles: Vec<u32>,
    /// What a frame drawn with culling off or a query-driven method drew:
    /// instances and triangles.
    counted: (u64, u64),
}

/// What the renderer draws with.
struct DrawState {
    /// Draws instances one by one (`vs_main`).
    pipeline: wgpu::RenderPipeline,
    /// Draws a visible list (`vs_listed`).
    listed: wgpu::RenderPipeline,
    /// Group 0 of both: the uniforms and the instances.
    group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    instances: wgpu::Buffer,
    meshes: Vec<MeshRange>,
    /// Each instance's mesh.
    mesh_of: Vec<u32>,
}

impl DrawState {
    /// Binds what both pipelines read, `pipeline` first.
    fn bind(&self, pass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline) {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }

    /// Draws `instances`, each with its mesh.
    fn instances(&self, pass: &mut wgpu::RenderPass<'_>, instances: &[u32]) {
        self.bind(pass, &self.pipeline);
        for &i in instances {
            let m = self.meshes[self.mesh_of[i as usize] as usize];
            pass.draw_indexed(m.first_index..m.first_index + m.index_count, m.base_vertex, i..i + 1);
        }
    }

    /// Draws a visible list of occlude's GPU-driven culling: one multi-draw.
    fn list(&self, pass: &mut wgpu::RenderPass<'_>, list: &VisibleList) {
        self.bind(pass, &self.listed);
        list.draw(pass);
    }
}

impl Renderer {
    /// A renderer of `scene`, moved by `motion`, drawing into colour
    /// targets of `color_format` on `device`; culling off.
    pub fn new(
        device: wgpu::Device,
        queue: wgpu::Queue,
        scene: Scene,
        motion: Option<OwnMotion>,
        color_format: wgpu::TextureFormat,
    ) -> Self {
        let (mut vertices, mut indices, mut meshes) = (Vec::<[f32; 3]>::new(), Vec::<u32>::new(), Vec::new());
        for mesh in &scene.meshes {
            let (first_index, base_vertex) = (indices.len() as u32, vertices.len() as i32);
            vertices.extend(mesh.positions.iter().map(|p| p.to_array()));
            indices.extend(&mesh.indices);
            meshes.push(MeshRange { first_index, index_count: mesh.indices.len() as u32, base_vertex });
        }
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let vertices = buffer("vertices", bytemuck::cast_slice(&vertices), wgpu::BufferUsages::VERTEX);
        let indices = buffer("indices", bytemuck::cast_slice(&indices), wgpu::BufferUsages::INDEX);
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let instances = buffer(
            "instances",
            bytemuck::cast_slice(&scene.instances.iter().map(instance_data).collect::<Vec<_>>()),
            usage,
        );
        let uniforms = buffer("uniforms", &[0; 80], wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST);
        let [plain, listed] = layouts(&device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("gltf-viewer"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let pipeline = render_pipeline(&device, &module, &plain, "vs_main", color_format);
        let listed = render_pipeline(&device, &module, &listed, "vs_listed", color_format);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("uniforms and instances"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: instances.as_entire_binding() },
            ],
        });
        let mesh_of = scene.instances.iter().map(|i| i.mesh).collect();
        let triangles: Vec<u32> =
            scene.instances.iter().map(|i| scene.meshes[i.mesh as usize].triangle_count() as u32).collect();
        Self {
            timer: Timer::new(&device, &queue),
            tally: Tally::new(&device),
            triangles,
            draw: DrawState { pipeline, listed, group, vertices, indices, instances, meshes, mesh_of },
            device,
            queue,
            color_format,
            scene,
            motion,
            uniforms,
            depth: None,
            culling: None,
            counted: (0, 0),
        }
    }

    /// The device it draws with.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue it submits to.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The scene as it stands.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Culls with occlude's `method` from now on (`None`: culling off).
    pub fn set_culling(&mut self, method: Option<Method>) -> Result<(), Box<dyn Error>> {
        // occlude: the attachments, the scene, each mesh's range and each
        // instance's mesh (one draw group), and the list's binding.
        let attachments = Attachments {
            color: Some(self.color_format),
            depth: DEPTH_FORMAT,
            compare: wgpu::CompareFunction::Less,
            samples: 1,
        };
        let meshes = self.draw.meshes.iter().map(|m| IndirectDraw::Indexed {
            index_count: m.index_count,
            first_index: m.first_index,
            base_vertex: m.base_vertex,
        });
        let instances = self.draw.mesh_of.iter().map(|&mesh| InstanceDraw { mesh, group: 0 }).collect();
        let draws = Draws::Meshes { meshes: meshes.collect(), instances };
        self.culling = match method {
            Some(method) => {
                let scene = self.scene.clone();
                let culler = AnyCuller::for_scene(&self.device, &self.queue, attachments, scene, method, draws)?;
                Some(culler.with_list_pipeline(&self.draw.listed, 1, 0)?)
            }
            None => None,
        };
        // occlude: end.
        Ok(())
    }

    /// Puts the scene's own motion at `t` seconds (looped as the motion
    /// says): the instances' transforms here, their boxes in the culler.
    pub fn set_time(&mut self, t: f32) -> Result<(), Box<dyn Error>> {
        let Some(motion) = &self.motion else { return Ok(()) };
        let changes = motion.changes_at(t);
        let changed = self.scene.apply(&changes)?;
        if changed.is_empty() {
            return Ok(());
        }
        for &i in &changed {
            let row = std::mem::size_of::<InstanceData>() as u64 * u64::from(i);
            let data = instance_data(&self.scene.instances[i as usize]);
            self.queue.write_buffer(&self.draw.instances, row, bytemuck::bytes_of(&data));
        }
        if let Some(culling) = &mut self.culling {
            culling.update(&changes)?; // occlude: the frame's changes.
        }
        Ok(())
    }

    /// Renders a frame seen with `view` and `projection` into `target`, a
    /// view of a texture in the colour format (`RENDER_ATTACHMENT` usage).
    pub fn render(&mut self, target: &wgpu::TextureView, view: Mat4, projection: Mat4) -> Result<(), Box<dyn Error>> {
        let eye = view.inverse().w_axis;
        let uniforms: Vec<f32> = (projection * view).to_cols_array().into_iter().chain(eye.to_array()).collect();
        self.queue.write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&uniforms));
        let size = target.texture().size();
        if self.depth.as_ref().is_none_or(|d| d.size() != size) {
            self.depth = Some(self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("depth"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DEPTH_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            }));
        }
        let depth = self.depth.as_ref().expect("made above").create_view(&Default::default());
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let Some(culling) = self.culling.as_mut() else {
            let enabled: Vec<u32> = (0..self.triangles.len() as u32).filter(|&i| self.is_enabled(i)).collect();
            self.draw.instances(&mut begin_pass(&mut encoder, target, &depth, true), &enabled);
            self.counted = (enabled.len() as u64, enabled.iter().map(|&i| u64::from(self.triangles[i as usize])).sum());
            self.queue.submit([encoder.finish()]);
            return Ok(());
        };
        // occlude: the camera and the views; a GPU-driven method's two
        // phases around this renderer's passes drawing its lists (timed),
        // a query-driven method's passes drawing the instances it finds.
        let camera = Camera::from_matrices(view, projection, false)?;
        let frame = FrameTarget::new(Some(target), CLEAR_COLOR, &depth);
        let draw = &self.draw;
        let stamp = |encoder: &mut wgpu::CommandEncoder, k| self.timer.iter().for_each(|t| t.stamp(encoder, k));
        match culling {
            AnyCuller::Gpu(culler) => {
                stamp(&mut encoder, 0);
                culler.encode_early(&mut encoder, &camera, &frame)?;
                stamp(&mut encoder, 1);
                draw.list(&mut begin_pass(&mut encoder, target, &depth, true), &culler.lists()[0]);
                stamp(&mut encoder, 2);
                culler.encode_late(&mut encoder, &frame)?;
                stamp(&mut encoder, 3);
                draw.list(&mut begin_pass(&mut encoder, target, &depth, false), &culler.lists()[1]);
                self.queue.submit([encoder.finish()]);
            }
            AnyCuller::Queries(culler) => {
                let (triangles, mut counted) = (&self.triangles, (0, 0));
                culler.render(&camera, frame, |pass, instances| {
                    draw.instances(pass, instances);
                    counted.0 += instances.len() as u64;
                    counted.1 += instances.iter().map(|&i| u64::from(triangles[i as usize])).sum::<u64>();
                })?;
                self.counted = counted;
            }
        }
        // occlude: end.
        Ok(())
    }

    /// Whether instance `i` is in the scene now (not hidden by its motion).
    fn is_enabled(&self, i: u32) -> bool {
        self.scene.instances[i as usize].enabled
    }

    /// What the last frame drew (blocking until the GPU has drawn it: call
    /// it a few times a second, not every frame).
    pub fn drawn(&self) -> Result<Drawn, Box<dyn Error>> {
        let Some(AnyCuller::Gpu(culler)) = &self.culling else {
            let (instances, triangles) = self.counted;
            return Ok(Drawn { instances, triangles, culling_gpu_ms: None });
        };
        let commands = culler.lists().each_ref().map(|l| l.indirect()); // occlude: the lists' draws.
        let (instances, triangles) = self.tally.count(&self.device, &self.queue, &commands)?;
        let culling_gpu_ms = self.timer.as_ref().map(|t| t.read_ms(&self.device)).transpose()?;
        Ok(Drawn { instances, triangles, culling_gpu_ms })
    }

    /// The last frame's depth image, rows from the top (blocking).
    pub fn depth_image(&self) -> Result<Vec<f32>, Box<dyn Error>> {
        let depth = self.depth.as_ref().ok_or("no frame drawn yet")?;
        let bytes = read_texture(&self.device, &self.queue, depth, wgpu::TextureAspect::DepthOnly)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// An instance as the shader reads it: its transform, base colour and
/// material id.
fn instance_data(i: &Instance) -> InstanceData {
    InstanceData { transform: i.transform.to_cols_array(), color: material_color(i.material) }
}

/// The base colour of material `m` (a hash of its id, light and
/// unsaturated), then `m`.
fn material_color(m: u32) -> [f32; 4] {
    let h = m.wrapping_add(1).wrapping_mul(2_654_435_761) ^ m.wrapping_mul(40_503);
    let unit = |shift: u32| ((h >> shift) & 0xff) as f32 / 255.0;
    [0.35 + 0.6 * unit(0), 0.35 + 0.6 * unit(8), 0.35 + 0.6 * unit(16), (m % 8) as f32]
}

/// A render pass into `color` and `depth`, cleared (`clear`) or loaded.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    color: &wgpu::TextureView,
    depth: &wgpu::TextureView,
    clear: bool,
) -> wgpu::RenderPass<'e> {
    let (color_load, depth_load) = if clear {
        (wgpu::LoadOp::Clear(CLEAR_COLOR), wgpu::LoadOp::Clear(1.0))
    } else {
        (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
    };
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: color_load, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        ..Default::default()
    })
}

/// The pipeline layouts: drawing instances (group 0: uniforms and
/// instances) and drawing a list (the same group 0, the list in group 1).
fn layouts(device: &wgpu::Device) -> [wgpu::PipelineLayout; 2] {
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let storage = |binding| entry(binding, wgpu::BufferBindingType::Storage { read_only: true });
    let group = |entries: &[wgpu::BindGroupLayoutEntry]| {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries })
    };
    let scene = group(&[entry(0, wgpu::BufferBindingType::Uniform), storage(1)]);
    let list = group(&[storage(0)]);
    let layout = |groups: &[Option<&wgpu::BindGroupLayout>]| {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: groups,
            immediate_size: 0,
        })
    };
    [layout(&[Some(&scene)]), layout(&[Some(&scene), Some(&list)])]
}

/// The pipeline of vertex entry point `vertex`: positions as the one vertex
/// buffer, no face culling (models' windings vary), depth tested with
/// `Less` and written.
fn render_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    vertex: &str,
    color_format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(vertex),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3],
            })],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(color_format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// An off-screen colour target: for screenshots and tests.
pub struct Offscreen {
    texture: wgpu::Texture,
}

impl Offscreen {
    /// The colour format of off-screen targets.
    pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

    /// A `width` x `height` target on `device`.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("off-screen colour"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: Self::FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        Self { texture }
    }

    /// A view to render into.
    pub fn view(&self) -> wgpu::TextureView {
        self.texture.create_view(&Default::default())
    }

    /// The image, RGBA8 rows from the top (blocking).
    pub fn image(&self, renderer: &Renderer) -> Result<Vec<u8>, Box<dyn Error>> {
        read_texture(&renderer.device, &renderer.queue, &self.texture, wgpu::TextureAspect::All)
    }

    /// Writes the image as a PNG.
    pub fn save_png(&self, renderer: &Renderer, path: &std::path::Path) -> Result<(), Box<dyn Error>> {
        let size = self.texture.size();
        image::save_buffer(path, &self.image(renderer)?, size.width, size.height, image::ColorType::Rgba8)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        Ok(())
    }
}

/// The pixels of `texture` (4 bytes each), rows packed (blocking).
fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, Box<dyn Error>> {
    let size = texture.size();
    let row = size.width * 4;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: u64::from(padded * size.height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        size,
    );
    queue.submit([encoder.finish()]);
    let bytes = read_buffer(device, &buffer)?;
    Ok(bytes.chunks_exact(padded as usize).flat_map(|r| &r[..row as usize]).copied().collect())
}
