//! A small wgpu renderer of its own, off-screen: its own WGSL shader, one
//! vertex and index buffer holding several meshes (cubes and wedges), a
//! per-instance buffer (offset, scale, colour) and two pipelines (two
//! shadings), drawing a grid of shapes behind three walls with two gaps.
//! With culling off it draws every instance with its mesh and pipeline;
//! with culling on,
//! occlude's `chcpp` (`occlude::wgpu::embed::Culler`) decides which boxes
//! to draw and calls this renderer's draw code for them, inside its own
//! passes on this renderer's device and attachments; or occlude's `hiz`,
//! `roc` or `ioc` (`occlude::wgpu::embed::GpuCuller`) writes the visible
//! instances' ids into lists on the GPU with one draw command per mesh and
//! pipeline, which this renderer draws with one multi-draw per pipeline.
//!
//! The lines that integrate occlude are marked `occlude:` (counted in
//! the README).

mod timer;

use glam::{Mat4, Vec3};
use occlude::methods::Method;
use occlude::wgpu::embed::{
    AnyCuller, Attachments, Draws, FrameTarget, IndirectDraw, InstanceDraw, PassCounts, Viewport, VisibleList,
    DRAW_FEATURES, RASTER_FEATURES,
};
use occlude::{Aabb, Camera};
use std::error::Error;
use timer::Timer;
pub use timer::{GpuTimes, TIMER_FEATURES};
use wgpu::util::DeviceExt;

/// Colour format of the off-screen image.
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Background colour.
const CLEAR_COLOR: wgpu::Color = wgpu::Color { r: 0.55, g: 0.7, b: 0.85, a: 1.0 };
/// Metres between neighbouring boxes of the grid.
const SPACING: f32 = 2.0;

/// What to render.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Image width and height in pixels.
    pub size: u32,
    /// The grid is `grid` x `grid` boxes.
    pub grid: u32,
    /// Reverse Z: depth 1 nearest, cleared to 0, test `GreaterEqual`, an
    /// infinite far plane; otherwise depth 0 nearest, test `Less`.
    pub reverse_z: bool,
    /// Depth format: `Depth32Float` (whose image can be read back) or
    /// `Depth24Plus`.
    pub depth_format: wgpu::TextureFormat,
    /// Distinct meshes (cubes and wedges, alternating), each at its own
    /// place in the vertex and index buffers; instances take them in turn.
    pub meshes: u32,
    /// Samples per pixel: 1, or the MSAA count (the colour resolved into a
    /// single-sample image, which is what is read back).
    pub samples: u32,
    /// The rectangle of the image drawn into, or `None` for all of it.
    pub viewport: Option<Viewport>,
}

/// Draw groups: pipelines of two shadings.
const GROUPS: usize = 2;
/// Each group's fragment entry point.
const SHADINGS: [&str; GROUPS] = ["fs_main", "fs_tinted"];

/// Where a mesh lies in the vertex and index buffers.
#[derive(Clone, Copy, Debug)]
struct MeshRange {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
}

/// One instance as the vertex shader reads it (`@location(2..4)`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct InstanceData {
    offset: [f32; 3],
    scale: [f32; 3],
    color: [f32; 3],
}

/// The renderer: device, pipelines, buffers and its off-screen image.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    options: Options,
    uniforms: wgpu::Buffer,
    draw: DrawState,
    /// World box of each instance (what occlude culls).
    bounds: Vec<Aabb>,
    color: wgpu::Texture,
    /// With MSAA, the single-sample image the colour resolves into.
    resolved: Option<wgpu::Texture>,
    depth: wgpu::Texture,
    /// occlude: the culling method, when culling is on.
    culling: Option<AnyCuller>,
    /// Timestamps around a GPU-driven frame's passes, when asked for
    /// ([`Renderer::time_gpu`]).
    timer: Option<Timer>,
}

/// What the renderer draws with: pipelines, bind groups, buffers, and each
/// instance's mesh and pipeline.
struct DrawState {
    /// Per draw group: draws instances from the instance vertex buffer.
    pipelines: [wgpu::RenderPipeline; GROUPS],
    /// Per draw group: draws listed instances, ids from a list (group 1),
    /// instances from storage; one layout for both.
    listed: [wgpu::RenderPipeline; GROUPS],
    group: wgpu::BindGroup,
    /// The listed pipelines' group 0: the uniforms and the instances.
    listed_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    meshes: Vec<MeshRange>,
    instances: wgpu::Buffer,
    /// Each instance's mesh and draw group.
    draws: Vec<InstanceDraw>,
}

impl DrawState {
    /// Draws `instances`, each with its mesh and its group's pipeline.
    fn instances(&self, pass: &mut wgpu::RenderPass<'_>, instances: &[u32]) {
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_vertex_buffer(1, self.instances.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
        let mut bound = None;
        for &i in instances {
            let InstanceDraw { mesh, group } = self.draws[i as usize];
            if bound != Some(group) {
                pass.set_pipeline(&self.pipelines[group as usize]);
                bound = Some(group);
            }
            let m = self.meshes[mesh as usize];
            pass.draw_indexed(m.first_index..m.first_index + m.index_count, m.base_vertex, i..i + 1);
        }
    }

    /// Draws a list of occlude's GPU-driven culling: one multi-draw per
    /// group, with the group's pipeline.
    fn list(&self, pass: &mut wgpu::RenderPass<'_>, list: &VisibleList) {
        for (group, pipeline) in (0..).zip(&self.listed) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.listed_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
            list.draw_group(pass, group);
        }
    }
}

/// A device and queue on the first adapter wgpu finds (`WGPU_BACKEND` and
/// `WGPU_ADAPTER_NAME` narrow the choice), with the features occlude and
/// the GPU timer use where the adapter has them.
pub fn open_device() -> Result<(wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    // occlude: the features `roc` and `ioc` need (forced early depth tests), and those of multi-mesh draws.
    open_device_with(RASTER_FEATURES | DRAW_FEATURES | TIMER_FEATURES)
}

/// A device and queue as [`open_device`], with those of `wanted` that the
/// adapter has.
pub fn open_device_with(wanted: wgpu::Features) -> Result<(wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let descriptor = wgpu::DeviceDescriptor { required_features: adapter.features() & wanted, ..Default::default() };
    Ok(pollster::block_on(adapter.request_device(&descriptor))?)
}

impl Renderer {
    /// The renderer on `device`, its scene built, culling off.
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, options: Options) -> Self {
        let data = scene(options.grid);
        let bounds =
            data.iter().map(|d| Aabb::new(d.offset.into(), Vec3::from(d.offset) + Vec3::from(d.scale))).collect();
        let (vertices, indices, meshes) = meshes(options.meshes.max(1));
        // The grid's shapes take the meshes and groups in turn; the walls
        // (last) are cubes.
        let boxes = options.grid * options.grid;
        let draws = (0..data.len() as u32)
            .map(|i| {
                let (mesh, group) = if i < boxes { (i % meshes.len() as u32, (i / 7) % GROUPS as u32) } else { (0, 0) };
                InstanceDraw { mesh, group }
            })
            .collect();
        let buffer = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let vertices = buffer("mesh vertices", bytemuck::cast_slice(&vertices), wgpu::BufferUsages::VERTEX);
        let indices = buffer("mesh indices", bytemuck::cast_slice(&indices), wgpu::BufferUsages::INDEX);
        let instances =
            buffer("instances", bytemuck::cast_slice(&data), wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE);
        let uniforms = buffer("uniforms", &[0; 64], wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST);
        let [plain, listed] = layouts(&device);
        let pipelines = SHADINGS.map(|fragment| pipeline(&device, options, &plain, fragment));
        let listed = SHADINGS.map(|fragment| pipeline_listed(&device, options, &listed, fragment));
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("uniforms"),
            layout: &pipelines[0].get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        let listed_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("uniforms and instances"),
            layout: &listed[0].get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: instances.as_entire_binding() },
            ],
        });
        let texture = |label, format, sample_count| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: options.size, height: options.size, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let color = texture("colour", COLOR_FORMAT, options.samples);
        let resolved = (options.samples > 1).then(|| texture("resolved colour", COLOR_FORMAT, 1));
        let depth = texture("depth", options.depth_format, options.samples);
        Self {
            device,
            queue,
            options,
            uniforms,
            draw: DrawState { pipelines, listed, group, listed_group, vertices, indices, meshes, instances, draws },
            bounds,
            color,
            resolved,
            depth,
            culling: None,
            timer: None,
        }
    }

    /// Instances in the scene (boxes and walls).
    pub fn instance_count(&self) -> u32 {
        self.bounds.len() as u32
    }

    /// The depth test the pipeline uses.
    fn compare(&self) -> wgpu::CompareFunction {
        if self.options.reverse_z {
            wgpu::CompareFunction::GreaterEqual
        } else {
            wgpu::CompareFunction::Less
        }
    }

    /// Times each GPU-driven frame's culling passes and drawing passes on
    /// the GPU from now on ([`Renderer::gpu_times`]), or stops. A device
    /// without [`TIMER_FEATURES`] is an error.
    pub fn time_gpu(&mut self, on: bool) -> Result<(), Box<dyn Error>> {
        self.timer = if on {
            Some(Timer::new(&self.device, &self.queue).ok_or("the device lacks timestamp queries between passes")?)
        } else {
            None
        };
        Ok(())
    }

    /// The last GPU-driven frame's GPU times (blocking), when timed
    /// ([`Renderer::time_gpu`]).
    pub fn gpu_times(&self) -> Result<Option<GpuTimes>, Box<dyn Error>> {
        self.timer.as_ref().map(|t| t.read(&self.device)).transpose()
    }

    /// The passes and dispatches the last frame's GPU-driven culling
    /// recorded; `None` with culling off or query-driven.
    pub fn pass_counts(&self) -> Option<PassCounts> {
        match &self.culling {
            Some(AnyCuller::Gpu(culler)) => Some(culler.pass_counts()),
            _ => None,
        }
    }

    /// The late test a GPU-driven frame ran, and whether `auto` was probing
    /// it (see `GpuCuller::late_test`); `None` for other culling.
    pub fn late_test(&self) -> Option<(&'static str, bool)> {
        match &self.culling {
            Some(AnyCuller::Gpu(culler)) => Some(culler.late_test()),
            _ => None,
        }
    }

    /// Culls with occlude's method `method` from now on (`None`: culling off).
    pub fn set_culling(&mut self, method: Option<Method>) -> Result<(), Box<dyn Error>> {
        // occlude: the attachments, the instance boxes and the method, once.
        let attachments = Attachments {
            color: Some(COLOR_FORMAT),
            depth: self.options.depth_format,
            compare: self.compare(),
            samples: self.options.samples,
        };
        let meshes = self.draw.meshes.iter().map(|m| IndirectDraw::Indexed {
            index_count: m.index_count,
            first_index: m.first_index,
            base_vertex: m.base_vertex,
        });
        let draws = Draws::Meshes { meshes: meshes.collect(), instances: self.draw.draws.clone() };
        self.culling = match method {
            Some(method) => Some(
                AnyCuller::new(&self.device, &self.queue, attachments, &self.bounds, method, draws)?
                    .with_list_pipeline(&self.draw.listed[0], 1, 0)?,
            ),
            None => None,
        };
        // occlude: end.
        Ok(())
    }

    /// Renders frame `t` (0 to 1 along the camera's path) and returns how
    /// many instances it drew.
    pub fn render(&mut self, t: f32) -> Result<u64, Box<dyn Error>> {
        let (view, projection) = self.camera(t);
        self.queue.write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&(projection * view).to_cols_array()));
        let color = self.color.create_view(&Default::default());
        let resolve = self.resolved.as_ref().map(|t| t.create_view(&Default::default()));
        let depth = self.depth.create_view(&Default::default());
        let views = Views { color: &color, resolve: resolve.as_ref(), depth: &depth };
        let Some(culling) = self.culling.as_mut() else {
            // Culling off: one pass, every instance drawn.
            let mut encoder = self.device.create_command_encoder(&Default::default());
            let n = self.instance_count();
            let all: Vec<u32> = (0..n).collect();
            self.draw.instances(&mut begin_pass(&mut encoder, &views, self.options, true), &all);
            self.queue.submit([encoder.finish()]);
            return Ok(u64::from(n));
        };
        // occlude: the frame's camera and views; occlude's method draws the
        // instances it finds visible with this renderer's draw code.
        let camera = Camera::from_matrices(view, projection, self.options.reverse_z)?;
        let target = FrameTarget {
            resolve: resolve.as_ref(),
            viewport: self.options.viewport,
            ..FrameTarget::new(Some(&color), CLEAR_COLOR, &depth)
        };
        let draw = &self.draw;
        let culler = match culling {
            // A query-driven method draws lists of instances in its passes.
            AnyCuller::Queries(culler) => {
                let mut drawn = 0u64;
                culler.render(&camera, target, |pass, instances| {
                    draw.instances(pass, instances);
                    drawn += instances.len() as u64;
                })?;
                return Ok(drawn);
            }
            AnyCuller::Gpu(culler) => culler,
        };
        // A GPU-driven one records its two phases into this renderer's
        // encoder, around the passes drawing its lists with one multi-draw
        // per pipeline; timestamps between them when timed.
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let stamp = |encoder: &mut wgpu::CommandEncoder, k| self.timer.iter().for_each(|t| t.stamp(encoder, k));
        stamp(&mut encoder, 0);
        culler.encode_early(&mut encoder, &camera, &target)?;
        stamp(&mut encoder, 1);
        draw.list(&mut begin_pass(&mut encoder, &views, self.options, true), &culler.lists()[0]);
        stamp(&mut encoder, 2);
        culler.encode_late(&mut encoder, &target)?;
        stamp(&mut encoder, 3);
        draw.list(&mut begin_pass(&mut encoder, &views, self.options, false), &culler.lists()[1]);
        stamp(&mut encoder, 4);
        self.queue.submit([encoder.finish()]);
        // The lists' lengths, read back for the printout and the test (the
        // frame itself reads nothing back).
        let drawn = culler.read_counts()?.iter().map(|&n| u64::from(n)).sum();
        // occlude: end.
        Ok(drawn)
    }

    /// View and projection of frame `t`: walking sideways in front of the
    /// walls, looking down the grid.
    fn camera(&self, t: f32) -> (Mat4, Mat4) {
        let eye = Vec3::new(-6.0 + 12.0 * t, 1.7, 6.0);
        let view = Mat4::look_at_rh(eye, Vec3::new(eye.x * 0.5, 1.5, -30.0), Vec3::Y);
        let fov = 60f32.to_radians();
        let aspect = self.options.viewport.map_or(1.0, |v| v.width as f32 / v.height as f32);
        let projection = if self.options.reverse_z {
            Mat4::perspective_infinite_reverse_rh(fov, aspect, 0.1)
        } else {
            Mat4::perspective_rh(fov, aspect, 0.1, 300.0)
        };
        (view, projection)
    }

    /// Waits until the GPU has finished everything submitted (to time a
    /// frame from its start to the GPU being idle).
    pub fn wait_idle(&self) -> Result<(), Box<dyn Error>> {
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        Ok(())
    }

    /// The last frame's colour image (resolved, with MSAA), RGBA8 rows
    /// from the top (blocking).
    pub fn color_image(&self) -> Result<Vec<u8>, Box<dyn Error>> {
        self.read(self.resolved.as_ref().unwrap_or(&self.color), wgpu::TextureAspect::All)
    }

    /// The last frame's depth image, rows from the top (blocking; a
    /// `Depth24Plus` or multisampled image cannot be read back and is an
    /// error).
    pub fn depth_image(&self) -> Result<Vec<f32>, Box<dyn Error>> {
        let bytes = self.read(&self.depth, wgpu::TextureAspect::DepthOnly)?;
        Ok(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
    }

    /// Writes the last frame's colour image as a PNG.
    pub fn save_png(&self, path: &std::path::Path) -> Result<(), Box<dyn Error>> {
        let size = self.options.size;
        image::save_buffer(path, &self.color_image()?, size, size, image::ColorType::Rgba8)?;
        Ok(())
    }

    /// The pixels of `texture` (4 bytes each), rows packed (blocking).
    fn read(&self, texture: &wgpu::Texture, aspect: wgpu::TextureAspect) -> Result<Vec<u8>, Box<dyn Error>> {
        let size = self.options.size;
        let row = size * 4;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size: u64::from(padded * size),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(size),
                },
            },
            wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 1 },
        );
        self.queue.submit([encoder.finish()]);
        let bytes = read_buffer(&self.device, &buffer)?;
        Ok(bytes.chunks_exact(padded as usize).flat_map(|r| &r[..row as usize]).copied().collect())
    }
}

/// The bytes of `buffer` (`MAP_READ` usage), once the GPU has finished
/// everything submitted (blocking); the buffer is unmapped again.
fn read_buffer(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, Box<dyn Error>> {
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = sender.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receiver.recv()??;
    let bytes = buffer.slice(..).get_mapped_range()?.to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// The views a frame draws into.
struct Views<'a> {
    color: &'a wgpu::TextureView,
    /// With MSAA, the single-sample view the colour resolves into.
    resolve: Option<&'a wgpu::TextureView>,
    depth: &'a wgpu::TextureView,
}

/// A render pass on `views`, clearing them (`clear`) or loading what is
/// there, in the viewport of `options`.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    views: &Views<'_>,
    options: Options,
    clear: bool,
) -> wgpu::RenderPass<'e> {
    let far = if options.reverse_z { 0.0 } else { 1.0 };
    let (color_load, depth_load) = if clear {
        (wgpu::LoadOp::Clear(CLEAR_COLOR), wgpu::LoadOp::Clear(far))
    } else {
        (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
    };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: views.color,
            depth_slice: None,
            resolve_target: views.resolve,
            ops: wgpu::Operations { load: color_load, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: views.depth,
            depth_ops: Some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        ..Default::default()
    });
    if let Some(v) = options.viewport {
        pass.set_viewport(v.x as f32, v.y as f32, v.width as f32, v.height as f32, 0.0, 1.0);
    }
    pass
}

/// The mesh vertex buffer's layout (position, normal).
const MESH_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 24,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
};

/// The render pipeline of group shading `fragment`: mesh vertices
/// (position, normal) and instances (offset, scale, colour) as vertex
/// buffers, the uniforms in group 0, back faces culled, depth written and
/// tested with `Less`, or `GreaterEqual` for reverse Z.
fn pipeline(
    device: &wgpu::Device,
    options: Options,
    layout: &wgpu::PipelineLayout,
    fragment: &str,
) -> wgpu::RenderPipeline {
    let buffers = [
        Some(MESH_LAYOUT),
        Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<InstanceData>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![2 => Float32x3, 3 => Float32x3, 4 => Float32x3],
        }),
    ];
    render_pipeline(device, options, layout, ("vs_main", fragment), &buffers)
}

/// The pipeline drawing a list of visible instances (`vs_listed`): mesh
/// vertices as a vertex buffer, the instances beside the uniforms in group
/// 0, the list in group 1; otherwise the render pipeline.
fn pipeline_listed(
    device: &wgpu::Device,
    options: Options,
    layout: &wgpu::PipelineLayout,
    fragment: &str,
) -> wgpu::RenderPipeline {
    render_pipeline(device, options, layout, ("vs_listed", fragment), &[Some(MESH_LAYOUT)])
}

/// The pipeline layouts, one for each group's pipeline alike (so that one
/// bind group serves both): group 0 the uniforms; for listed draws also
/// the instances, and group 1 the list.
fn layouts(device: &wgpu::Device) -> [wgpu::PipelineLayout; 2] {
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let uniform = entry(0, wgpu::BufferBindingType::Uniform);
    let storage = |binding| entry(binding, wgpu::BufferBindingType::Storage { read_only: true });
    let group = |entries: &[wgpu::BindGroupLayoutEntry]| {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries })
    };
    let layout = |groups: &[Option<&wgpu::BindGroupLayout>]| {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: groups,
            immediate_size: 0,
        })
    };
    let plain = group(&[uniform]);
    let listed = group(&[uniform, storage(1)]);
    let list = group(&[storage(0)]);
    [layout(&[Some(&plain)]), layout(&[Some(&listed), Some(&list)])]
}

/// A pipeline of the renderer's shader with the `(vertex, fragment)` entry
/// points reading `buffers`.
fn render_pipeline(
    device: &wgpu::Device,
    options: Options,
    layout: &wgpu::PipelineLayout,
    (vertex, fragment): (&str, &str),
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("own renderer"),
        source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
    });
    let compare = if options.reverse_z { wgpu::CompareFunction::GreaterEqual } else { wgpu::CompareFunction::Less };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("own renderer"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState { cull_mode: Some(wgpu::Face::Back), ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: options.depth_format,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: options.samples, ..Default::default() },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &[Some(COLOR_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The meshes: `count` of them, cubes and wedges in turn, each inside the
/// unit box `[0, 1]^3`, its indices counted from its own base vertex:
/// vertices (position, normal), indices, and where each mesh lies.
fn meshes(count: u32) -> (Vec<[f32; 6]>, Vec<u16>, Vec<MeshRange>) {
    let (mut vertices, mut indices, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..count {
        let faces = if k % 2 == 0 { cube() } else { wedge() };
        let (base_vertex, first_index) = (vertices.len() as i32, indices.len() as u32);
        let mut local = 0u16;
        for corners in faces {
            let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize();
            for c in &corners {
                vertices.push([c.x, c.y, c.z, normal.x, normal.y, normal.z]);
            }
            // A fan of counter-clockwise triangles seen from outside.
            for j in 1..corners.len() as u16 - 1 {
                indices.extend([local, local + j, local + j + 1]);
            }
            local += corners.len() as u16;
        }
        ranges.push(MeshRange { first_index, index_count: indices.len() as u32 - first_index, base_vertex });
    }
    (vertices, indices, ranges)
}

/// A unit cube's faces, corners counter-clockwise seen from outside.
fn cube() -> Vec<Vec<Vec3>> {
    // Each face: its first corner and two edge directions whose cross
    // product points out.
    let faces: [[[f32; 3]; 3]; 6] = [
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
        [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    ];
    faces
        .iter()
        .map(|&[o, u, v]| {
            let (o, u, v) = (Vec3::from(o), Vec3::from(u), Vec3::from(v));
            vec![o, o + u, o + u + v, o + v]
        })
        .collect()
}

/// A wedge in the unit box: full height at x = 0, sloping to the floor at
/// x = 1; faces as [`cube`]'s.
fn wedge() -> Vec<Vec<Vec3>> {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    vec![
        vec![p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(1.0, 0.0, 1.0), p(0.0, 0.0, 1.0)],
        vec![p(0.0, 0.0, 0.0), p(0.0, 0.0, 1.0), p(0.0, 1.0, 1.0), p(0.0, 1.0, 0.0)],
        vec![p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(0.0, 1.0, 1.0), p(1.0, 0.0, 1.0)],
        vec![p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(1.0, 0.0, 0.0)],
        vec![p(0.0, 0.0, 1.0), p(1.0, 0.0, 1.0), p(0.0, 1.0, 1.0)],
    ]
}

/// The instances: a `grid` x `grid` grid of boxes of varied sizes and
/// colours behind three walls (two gaps between them), walls last.
fn scene(grid: u32) -> Vec<InstanceData> {
    let mut out = Vec::new();
    let half = grid as f32 * SPACING / 2.0;
    for gz in 0..grid {
        for gx in 0..grid {
            // A small integer hash gives each box its own size and colour.
            let h = (gx.wrapping_mul(73_856_093) ^ gz.wrapping_mul(19_349_663)).wrapping_mul(2_654_435_761);
            let unit = |shift: u32| ((h >> shift) & 0xff) as f32 / 255.0;
            let width = 0.6 + 0.8 * unit(0);
            let height = 0.5 + 2.5 * unit(8);
            let x = gx as f32 * SPACING - half;
            let z = -20.0 - gz as f32 * SPACING;
            out.push(InstanceData {
                offset: [x, 0.0, z],
                scale: [width, height, width],
                color: [0.3 + 0.7 * unit(16), 0.3 + 0.7 * unit(24), 0.3 + 0.5 * unit(4)],
            });
        }
    }
    let wall =
        |x0: f32, x1: f32| InstanceData { offset: [x0, 0.0, -12.0], scale: [x1 - x0, 5.0, 0.5], color: [0.6; 3] };
    let reach = half + 40.0;
    out.extend([wall(-reach, -9.0), wall(-5.0, 5.0), wall(9.0, reach)]);
    out
}
