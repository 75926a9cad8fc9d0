//! [`GpuSat`]: summed-area-table queries (Engelhardt and Dachsbacher,
//! section 3.1) on the GPU, the counterpart of `occlude_soft::sat`: the
//! instances drawn in index order (depth test *less*) into one to eight
//! RGBA colour targets, each pixel one-hot in the channel its object's
//! region set gives it there (`occlude_core::gvq::RegionSet::channel_at`,
//! in the fragment shader); the summed area table of every channel by
//! prefix sums in compute (one invocation per row, then one per column,
//! exact `u32` sums); each object's count from four reads per lookup, in
//! compute too. The region sets come from the CPU (`occlude_core::gvq::plan`),
//! as in the paper.

use std::sync::Arc;

use glam::Vec4;
use occlude_core::gvq::{RegionPlan, CHANNELS_PER_TARGET, MAX_TARGETS, NO_CHANNEL};
use occlude_core::{Camera, Scene};

use crate::context::GpuContext;
use crate::pipelines::{bind_group, compute_pipeline, texture_2d, DEPTH_FORMAT};
use crate::readback::{take_bytes, Mapping};

/// The colour targets' format: one 8-bit channel per colour.
const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Bytes of one vertex: a clip-space position and the object's index.
const VERTEX_BYTES: u64 = 20;

/// Invocations per compute workgroup (`sat.wgsl`).
const WORKGROUP: u32 = 64;

/// What the GPU counted in one frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpuSatFrame {
    /// Per instance, the count from its region set's lookups.
    pub counts: Vec<u64>,
    /// The colour targets read back as a channel image (row-major, one
    /// channel per pixel or `NO_CHANNEL`), to check the counts against.
    pub channel_image: Vec<u8>,
}

/// The pipelines and images of summed-area-table queries at one size and
/// number of colour targets.
pub struct GpuSat {
    ctx: Arc<GpuContext>,
    width: u32,
    height: u32,
    targets: u32,
    render: wgpu::RenderPipeline,
    rows: wgpu::ComputePipeline,
    columns: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    colours: Vec<wgpu::Texture>,
    depth: wgpu::TextureView,
}

/// `sat.wgsl` with the declarations of `targets` colour targets.
fn shader_source(targets: u32) -> String {
    let outputs: String = (0..targets).map(|k| format!("@location({k}) c{k}: vec4<f32>, ")).collect();
    let colours: Vec<String> = (0..targets).map(|k| format!("one_hot(c, {k}u)")).collect();
    let textures: String =
        (0..targets).map(|k| format!("@group(0) @binding({}) var t{k}: texture_2d<f32>;\n", 8 + k)).collect();
    let loads: String =
        (0..targets).map(|k| format!("        case {k}u: {{ v = textureLoad(t{k}, p, 0); }}\n")).collect();
    include_str!("sat.wgsl")
        .replace(
            "//@COLOURS",
            &format!(
                "struct Colours {{ {outputs}}}\n\
                 @fragment\nfn fs(in: Shaded) -> Colours {{\n    \
                 let c = channel_at(in.object, u32(in.clip.x), u32(in.clip.y));\n    \
                 return Colours({});\n}}",
                colours.join(", ")
            ),
        )
        .replace(
            "//@TEXTURES",
            &format!(
                "{textures}\nfn texel(channel: u32, x: u32, y: u32) -> u32 {{\n    \
                 let p = vec2<i32>(i32(x), i32(y));\n    var v = vec4<f32>(0.0);\n    \
                 switch (channel / 4u) {{\n{loads}        default: {{}}\n    }}\n    \
                 return u32(v[channel % 4u] > 0.5);\n}}"
            ),
        )
}

impl GpuSat {
    /// Queries on a `width` x `height` image with `targets` colour targets
    /// (1 to `MAX_TARGETS`; the plans counted must use as many).
    ///
    /// # Panics
    /// If `targets` is out of range.
    pub fn new(ctx: Arc<GpuContext>, width: u32, height: u32, targets: u32) -> Self {
        assert!((1..=MAX_TARGETS).contains(&targets), "{targets} colour targets: 1 to {MAX_TARGETS} supported");
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sat"),
            source: wgpu::ShaderSource::Wgsl(shader_source(targets).into()),
        });
        let colour_targets: Vec<Option<wgpu::ColorTargetState>> = (0..targets)
            .map(|_| {
                Some(wgpu::ColorTargetState { format: COLOUR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL })
            })
            .collect();
        let render = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sat render"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: VERTEX_BYTES,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Uint32],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &colour_targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let compute = |entry: &str| compute_pipeline(device, &module, entry);
        let (rows, columns, count) = (compute("rows"), compute("columns"), compute("count"));
        let texture = |label: &str, format, usage| texture_2d(device, label, (width, height), format, usage);
        let colour_usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let colours = (0..targets).map(|_| texture("sat colour", COLOUR_FORMAT, colour_usage)).collect();
        let depth =
            texture("sat depth", DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        Self { ctx, width, height, targets, render, rows, columns, count, colours, depth }
    }

    /// Every instance of `scene` drawn from `camera` and counted with
    /// `plan`'s region sets (one set per instance, `plan.channels` at most
    /// four per target), waiting for the GPU.
    pub fn query(&self, scene: &Scene, camera: &Camera, plan: &RegionPlan) -> Result<GpuSatFrame, String> {
        if plan.sets.len() != scene.instances.len() || plan.channels > self.targets * CHANNELS_PER_TARGET {
            return Err(format!(
                "a plan of {} objects and {} channels for {} instances and {} targets",
                plan.sets.len(),
                plan.channels,
                scene.instances.len(),
                self.targets
            ));
        }
        let device = &self.ctx.device;
        let (w, h) = (self.width, self.height);
        let objects = scene.instances.len() as u32;

        let view_projection = camera.view_projection();
        let (mut clip, mut triangles, mut vertices) = (Vec::new(), Vec::new(), Vec::<[u32; 5]>::new());
        for i in 0..objects {
            triangles.clear();
            scene.push_clip_triangles(i, &view_projection, &mut clip, &mut triangles);
            let vertex = |v: &Vec4| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits(), v.w.to_bits(), i];
            vertices.extend(triangles.iter().flatten().map(vertex));
        }
        let mut lookups: Vec<[u32; 8]> = Vec::new();
        let mut ranges: Vec<[u32; 2]> = Vec::with_capacity(plan.sets.len());
        for set in &plan.sets {
            ranges.push([lookups.len() as u32, set.lookups.len() as u32]);
            lookups
                .extend(set.lookups.iter().map(|l| [l.rect.x0, l.rect.y0, l.rect.x1, l.rect.y1, l.channel, 0, 0, 0]));
        }
        let size = [w, h, plan.channels, objects];
        let buffer = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (bytes.len() as u64).max(32),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.ctx.queue.write_buffer(&b, 0, bytes);
            b
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let vertex_buffer = buffer("sat vertices", bytemuck::cast_slice(&vertices), wgpu::BufferUsages::VERTEX);
        let lookup_buffer = buffer("sat lookups", bytemuck::cast_slice(&lookups), storage);
        let range_buffer = buffer("sat ranges", bytemuck::cast_slice(&ranges), storage);
        let size_buffer = buffer("sat size", bytemuck::cast_slice(&size), wgpu::BufferUsages::UNIFORM);
        let sum_bytes = u64::from(plan.channels) * u64::from(w + 1) * u64::from(h + 1) * 4;
        let sums = buffer("sat sums", &vec![0u8; sum_bytes as usize], storage);
        let count_bytes = u64::from(objects) * 4;
        let counts = buffer("sat counts", &vec![0u8; count_bytes as usize], storage | wgpu::BufferUsages::COPY_SRC);

        let mut encoder = device.create_command_encoder(&Default::default());
        let views: Vec<wgpu::TextureView> = self.colours.iter().map(|t| t.create_view(&Default::default())).collect();
        {
            let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
                .iter()
                .map(|view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sat render"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let group = bind_group(
                device,
                "sat",
                &self.render.get_bind_group_layout(0),
                &[(0, lookup_buffer.as_entire_binding()), (1, range_buffer.as_entire_binding())],
            );
            pass.set_pipeline(&self.render);
            pass.set_bind_group(0, &group, &[]);
            pass.set_vertex_buffer(0, vertex_buffer.slice(..));
            pass.draw(0..vertices.len() as u32, 0..1);
        }
        {
            let mut texture_entries: Vec<(u32, wgpu::BindingResource)> =
                vec![(2, sums.as_entire_binding()), (3, size_buffer.as_entire_binding())];
            texture_entries
                .extend(views.iter().enumerate().map(|(k, v)| (8 + k as u32, wgpu::BindingResource::TextureView(v))));
            let rows = bind_group(device, "sat", &self.rows.get_bind_group_layout(0), &texture_entries);
            let columns = bind_group(
                device,
                "sat",
                &self.columns.get_bind_group_layout(0),
                &[(2, sums.as_entire_binding()), (3, size_buffer.as_entire_binding())],
            );
            let count = bind_group(
                device,
                "sat",
                &self.count.get_bind_group_layout(0),
                &[
                    (0, lookup_buffer.as_entire_binding()),
                    (1, range_buffer.as_entire_binding()),
                    (2, sums.as_entire_binding()),
                    (3, size_buffer.as_entire_binding()),
                    (4, counts.as_entire_binding()),
                ],
            );
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.rows);
            pass.set_bind_group(0, &rows, &[]);
            pass.dispatch_workgroups(h.div_ceil(WORKGROUP), plan.channels, 1);
            pass.set_pipeline(&self.columns);
            pass.set_bind_group(0, &columns, &[]);
            pass.dispatch_workgroups((w + 1).div_ceil(WORKGROUP), plan.channels, 1);
            pass.set_pipeline(&self.count);
            pass.set_bind_group(0, &count, &[]);
            pass.dispatch_workgroups(objects.div_ceil(WORKGROUP).max(1), 1, 1);
        }
        let staging = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let counts_staging = staging("sat counts read-back", count_bytes);
        encoder.copy_buffer_to_buffer(&counts, 0, &counts_staging, 0, count_bytes.max(4));
        let row_bytes = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let image_bytes = u64::from(row_bytes) * u64::from(h);
        let images: Vec<wgpu::Buffer> = self
            .colours
            .iter()
            .map(|texture| {
                let out = staging("sat colour read-back", image_bytes);
                encoder.copy_texture_to_buffer(
                    texture.as_image_copy(),
                    wgpu::TexelCopyBufferInfo {
                        buffer: &out,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row_bytes),
                            rows_per_image: None,
                        },
                    },
                    wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                );
                out
            })
            .collect();
        self.ctx.queue.submit([encoder.finish()]);

        Mapping::start(&counts_staging, count_bytes.max(4)).wait(&self.ctx)?;
        let raw = take_bytes(&counts_staging, count_bytes.max(4))?;
        let counts = raw[..count_bytes as usize]
            .chunks_exact(4)
            .map(|b| u64::from(u32::from_le_bytes(b.try_into().expect("4 bytes"))))
            .collect();
        let mut channel_image = vec![NO_CHANNEL; (w * h) as usize];
        for (k, out) in images.iter().enumerate() {
            Mapping::start(out, image_bytes).wait(&self.ctx)?;
            let raw = take_bytes(out, image_bytes)?;
            for y in 0..h as usize {
                for x in 0..w as usize {
                    let texel = &raw[y * row_bytes as usize + 4 * x..][..4];
                    if let Some(c) = texel.iter().position(|&v| v > 127) {
                        channel_image[y * w as usize + x] = (k * CHANNELS_PER_TARGET as usize + c) as u8;
                    }
                }
            }
        }
        match self.ctx.failure() {
            Some(failure) => Err(failure),
            None => Ok(GpuSatFrame { counts, channel_image }),
        }
    }
}
