//! [`DepthRaster`]: bare depth rasterization on the GPU, the counterpart of the soft
//! backend's `Rasterizer` for benchmarks: clip-space triangles drawn depth-only
//! (depth test LESS with depth write, two-sided), occlusion queries over groups
//! of them (back faces culled, no depth write; or two-sided with depth test
//! EQUAL, an object's own triangles against the depth pass that drew them), and
//! groups drawn depth-tested without writing (the fragments a shadow volume's
//! stencil pass rasterizes), with no scene, camera or colour.

use std::ops::Range;
use std::sync::Arc;

use glam::Vec4;

use crate::context::GpuContext;
use crate::pipelines::{texture_2d, DEPTH_FORMAT};
use crate::queries::{encode_resolve, read_values, QueryPool, QUERIES_PER_SET};
use crate::readback::Mapping;

/// Bytes of one vertex: a clip-space position.
const VERTEX_BYTES: u64 = 16;

/// The vertex shader passes clip-space positions through; there is no fragment
/// shader (depth only).
const SHADER: &str = "@vertex fn vs(@location(0) p: vec4<f32>) -> @builtin(position) vec4<f32> { return p; }";

/// A depth buffer on the GPU and the two pipelines that rasterize into it.
pub struct DepthRaster {
    ctx: Arc<GpuContext>,
    draw: wgpu::RenderPipeline,
    query: wgpu::RenderPipeline,
    /// Queries two-sided at depth test EQUAL.
    equal_query: wgpu::RenderPipeline,
    /// Draws two-sided at depth test LESS without depth write.
    tested: wgpu::RenderPipeline,
    /// The depth texture's view and size.
    depth: Option<(wgpu::TextureView, u32, u32)>,
    /// The uploaded triangles' vertices, and the buffer's capacity in bytes.
    vertices: Option<(wgpu::Buffer, u64)>,
    queries: QueryPool,
}

impl DepthRaster {
    /// The pipelines on `ctx`'s device; the depth buffer is made by [`Self::clear`].
    pub fn new(ctx: Arc<GpuContext>) -> Self {
        let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("depth raster"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("depth raster"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
        let pipeline = |label: &str, depth_write: bool, cull_mode: Option<wgpu::Face>, compare| {
            ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: VERTEX_BYTES,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x4],
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            })
        };
        let less = wgpu::CompareFunction::Less;
        let draw = pipeline("depth draw", true, None, less);
        let query = pipeline("depth query", false, Some(wgpu::Face::Back), less);
        let equal_query = pipeline("depth query at equal depth", false, None, wgpu::CompareFunction::Equal);
        let tested = pipeline("depth-tested draw", false, None, less);
        Self { ctx, draw, query, equal_query, tested, depth: None, vertices: None, queries: QueryPool::default() }
    }

    /// Clears the depth buffer to the far plane (1.0), first making it `width` x
    /// `height` if it is not, and waits until the GPU has done so.
    pub fn clear(&mut self, width: u32, height: u32) -> Result<(), String> {
        if !matches!(self.depth, Some((_, w, h)) if (w, h) == (width, height)) {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let texture = texture_2d(&self.ctx.device, "depth raster", (width, height), DEPTH_FORMAT, usage);
            self.depth = Some((texture.create_view(&Default::default()), width, height));
        }
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        drop(self.begin_pass(&mut encoder, wgpu::LoadOp::Clear(1.0), None)?);
        self.submit_and_wait(encoder)
    }

    /// Uploads `triangles` (clip space) for the following draws and queries, whose
    /// ranges index them, and waits until the copy is done.
    pub fn upload(&mut self, triangles: &[[Vec4; 3]]) -> Result<(), String> {
        let floats: Vec<f32> = triangles.iter().flatten().flat_map(|v| v.to_array()).collect();
        let bytes: &[u8] = bytemuck::cast_slice(&floats);
        let size = (bytes.len() as u64).max(VERTEX_BYTES);
        if !matches!(self.vertices, Some((_, capacity)) if capacity >= size) {
            let buffer = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("depth raster vertices"),
                size,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.vertices = Some((buffer, size));
        }
        let (buffer, _) = self.vertices.as_ref().expect("allocated above");
        self.ctx.queue.write_buffer(buffer, 0, bytes);
        self.submit_and_wait(self.ctx.device.create_command_encoder(&Default::default()))
    }

    /// Draws the uploaded triangles `triangles` (depth test LESS, depth write,
    /// two-sided) and waits until the GPU has finished.
    pub fn draw(&mut self, triangles: Range<u32>) -> Result<(), String> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = self.begin_pass(&mut encoder, wgpu::LoadOp::Load, None)?;
            pass.set_pipeline(&self.draw);
            pass.draw(triangles.start * 3..triangles.end * 3, 0..1);
        }
        self.submit_and_wait(encoder)
    }

    /// Runs one occlusion query (depth test LESS, no depth write, back faces culled)
    /// per range of uploaded triangles, in one render pass, and returns each one's
    /// count of passing samples once read back.
    pub fn queries(&mut self, groups: &[Range<u32>]) -> Result<Vec<u64>, String> {
        let pipeline = self.query.clone();
        self.run_queries(&pipeline, groups)
    }

    /// Runs one occlusion query (depth test EQUAL, no depth write, two-sided) per
    /// range of uploaded triangles, in one render pass, and returns each one's
    /// count of passing samples once read back: after a [`Self::draw`] of the same
    /// triangles, a group's samples that no other triangle hides (the same
    /// vertices give the same depths), an object's visible samples.
    pub fn queries_at_equal_depth(&mut self, groups: &[Range<u32>]) -> Result<Vec<u64>, String> {
        let pipeline = self.equal_query.clone();
        self.run_queries(&pipeline, groups)
    }

    /// Draws each range of uploaded triangles in `groups` by its own draw call in
    /// one render pass (depth test LESS, no depth write, two-sided), and waits
    /// until the GPU has finished: what a shadow volume's stencil pass rasterizes
    /// and tests, without the stencil (nothing is written).
    pub fn draw_tested(&mut self, groups: &[Range<u32>]) -> Result<(), String> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = self.begin_pass(&mut encoder, wgpu::LoadOp::Load, None)?;
            pass.set_pipeline(&self.tested);
            for g in groups {
                pass.draw(g.start * 3..g.end * 3, 0..1);
            }
        }
        self.submit_and_wait(encoder)
    }

    /// One occlusion query per group drawn by `pipeline`, batched in query sets.
    fn run_queries(&mut self, pipeline: &wgpu::RenderPipeline, groups: &[Range<u32>]) -> Result<Vec<u64>, String> {
        let mut values = Vec::with_capacity(groups.len());
        for batch in groups.chunks(QUERIES_PER_SET as usize) {
            let set = self.queries.set(&self.ctx, 0).clone();
            let readback = self.queries.readback(&self.ctx);
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut pass = self.begin_pass(&mut encoder, wgpu::LoadOp::Load, Some(&set))?;
                pass.set_pipeline(pipeline);
                for (i, g) in batch.iter().enumerate() {
                    pass.begin_occlusion_query(i as u32);
                    pass.draw(g.start * 3..g.end * 3, 0..1);
                    pass.end_occlusion_query();
                }
            }
            let bytes = encode_resolve(&mut encoder, &set, 0, batch.len() as u32, &readback);
            self.ctx.queue.submit([encoder.finish()]);
            Mapping::start(&readback.staging, bytes).wait(&self.ctx)?;
            values.extend(read_values(&readback, bytes)?);
            self.queries.recycle(readback);
        }
        Ok(values)
    }

    /// A depth-only render pass over the depth buffer, with the vertices bound.
    fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        load: wgpu::LoadOp<f32>,
        occlusion_query_set: Option<&'e wgpu::QuerySet>,
    ) -> Result<wgpu::RenderPass<'e>, String> {
        let (view, _, _) = self.depth.as_ref().ok_or("the depth buffer is made by clear, which was not called")?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth raster"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set,
            multiview_mask: None,
        });
        if let Some((buffer, _)) = &self.vertices {
            pass.set_vertex_buffer(0, buffer.slice(..));
        }
        Ok(pass)
    }

    /// Submits `encoder`'s commands and blocks until the GPU has executed them.
    fn submit_and_wait(&self, encoder: wgpu::CommandEncoder) -> Result<(), String> {
        let index = self.ctx.queue.submit([encoder.finish()]);
        self.ctx
            .device
            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
            .map_err(|e| format!("waiting for the GPU failed: {e}"))?;
        match self.ctx.failure() {
            Some(failure) => Err(failure),
            None => Ok(()),
        }
    }
}
