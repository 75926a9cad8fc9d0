//! The hierarchical item buffer (Engelhardt and Dachsbacher, "Granular
//! Visibility Queries on the GPU", I3D 2009, section 3.2; layout and CPU
//! counting in [`occlude_core::item_buffer`]) on the GPU, in one submission:
//!
//! 1. the item pass, a render pass drawing each object's instances with one
//!    instanced draw (depth test less, depth writes on, into the backend's
//!    depth texture), each fragment writing its item ID (slot and screen
//!    tile) into an `R32Uint` item image;
//! 2. the histogram, a compute pass with one thread per pixel, visited in a
//!    scrambled order (the paper's reordering: neighbouring pixels, which
//!    often hold the same ID, go to different threads), adding one to its
//!    ID's bin with an atomic;
//! 3. the reduction, a compute pass with one thread per bin adding its count
//!    to its slot's, object's and tile's totals (the paper's mip levels,
//!    summed directly);
//!
//! then the bins and totals are read back.

use crate::context::GpuContext;
use crate::culling::workgroups;
use crate::pipelines::{
    bind_group, build_pipeline, compute_pipeline, layout_entry, texture_2d, Targets, Variant, DRAW,
};
use crate::readback::{take_bytes, Mapping};
use crate::scene_buffers::GpuScene;
use crate::target::RenderTarget;
use occlude_core::rng::Rng;
use occlude_core::{ItemCounts, ItemLayout, NO_ITEM};
use wgpu::util::DeviceExt;

/// Format of the item image: one 32-bit ID per pixel.
const ITEM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The item pass's pipelines, and the item image and pixel order of the
/// backend's size, made on first use.
pub(crate) struct ItemPass {
    render: wgpu::RenderPipeline,
    /// Group 0 of the item pass.
    group: wgpu::BindGroupLayout,
    histogram: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    items: wgpu::TextureView,
    order: wgpu::Buffer,
}

impl ItemPass {
    /// The pipelines of `gpu`, an item image of `target`'s size and its
    /// pixels' scrambled order.
    pub fn new(gpu: &GpuScene, target: &RenderTarget) -> Self {
        let device = &gpu.ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("item buffer shaders"),
            source: wgpu::ShaderSource::Wgsl(include_str!("item_buffer.wgsl").into()),
        });
        let (vertex, fragment) = (wgpu::ShaderStages::VERTEX, wgpu::ShaderStages::FRAGMENT);
        let storage_read = wgpu::BufferBindingType::Storage { read_only: true };
        // Bindings as in item_buffer.wgsl.
        let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("item pass"),
            entries: &[
                layout_entry(0, vertex, wgpu::BufferBindingType::Uniform),
                layout_entry(1, vertex, storage_read),
                layout_entry(2, vertex, storage_read),
                layout_entry(3, fragment, wgpu::BufferBindingType::Uniform),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("item pass"),
            bind_group_layouts: &[Some(&group)],
            immediate_size: 0,
        });
        let variant = Variant { label: "item pass", vertex_entry: "vs_item", fragment_entry: "fs_item", ..DRAW };
        let render = build_pipeline(device, Some(&layout), &module, Targets::scene(ITEM_FORMAT), variant);
        let items = texture_2d(
            device,
            "item image",
            (target.width, target.height),
            ITEM_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let order = scrambled(target.width * target.height);
        Self {
            histogram: compute_pipeline(device, &module, "cs_histogram"),
            reduce: compute_pipeline(device, &module, "cs_reduce"),
            render,
            group,
            items: items.create_view(&Default::default()),
            order: storage(&gpu.ctx, "item pixel order", &order, wgpu::BufferUsages::empty()),
        }
    }

    /// Runs the item pass of `layout` with the camera uniform `camera`
    /// (`Camera` of `shader.wgsl`, already written) into `target`'s depth,
    /// counts it and reads the counts back (blocking).
    pub fn run(
        &self,
        gpu: &GpuScene,
        target: &RenderTarget,
        camera: &wgpu::Buffer,
        layout: &ItemLayout,
    ) -> Result<ItemCounts, String> {
        let ctx = &gpu.ctx;
        let slots = layout.slots().len() as u32;
        let objects = layout.objects() as u32;
        let (bins, tiles) = (layout.bins() as u32, layout.tiles());
        let pixels = target.width * target.height;
        let info = [target.width, target.height, layout.level(), pixels, bins, slots, slots + objects, 0];
        let mut slot_object = vec![0u32; slots as usize];
        for o in 0..layout.objects() {
            for s in layout.object_slots(o) {
                slot_object[s as usize] = o as u32;
            }
        }
        let none = wgpu::BufferUsages::empty();
        let info = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("item pass"),
            contents: bytemuck::cast_slice(&info),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let slot_buffer = storage(ctx, "item slots", layout.slots(), none);
        let slot_object = storage(ctx, "item slot objects", &slot_object, none);
        let bin_buffer = storage(ctx, "item histogram", &vec![0; bins as usize], wgpu::BufferUsages::COPY_SRC);
        let total_words = (slots + objects + tiles) as usize;
        let totals = storage(ctx, "item totals", &vec![0; total_words], wgpu::BufferUsages::COPY_SRC);
        let (bin_bytes, total_bytes) = (u64::from(bins) * 4, total_words as u64 * 4);
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("item counts read-back"),
            size: (bin_bytes + total_bytes).max(4),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("item pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.items,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r: f64::from(NO_ITEM), g: 0.0, b: 0.0, a: 0.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let group = bind_group(
                &ctx.device,
                "item pass",
                &self.group,
                &[
                    (0, camera.as_entire_binding()),
                    (1, gpu.transforms.as_entire_binding()),
                    (2, slot_buffer.as_entire_binding()),
                    (3, info.as_entire_binding()),
                ],
            );
            pass.set_pipeline(&self.render);
            pass.set_bind_group(0, &group, &[]);
            pass.set_vertex_buffer(0, gpu.vertices.slice(..));
            pass.set_index_buffer(gpu.indices.slice(..), wgpu::IndexFormat::Uint32);
            for o in 0..layout.objects() {
                let mesh = gpu.meshes[layout.object_mesh(o) as usize];
                pass.draw_indexed(
                    mesh.first_index..mesh.first_index + mesh.index_count,
                    mesh.base_vertex,
                    layout.object_slots(o),
                );
            }
        }
        let histogram = bind_group(
            &ctx.device,
            "item pass",
            &self.histogram.get_bind_group_layout(0),
            &[
                (3, info.as_entire_binding()),
                (4, wgpu::BindingResource::TextureView(&self.items)),
                (5, self.order.as_entire_binding()),
                (6, bin_buffer.as_entire_binding()),
            ],
        );
        let reduce = bind_group(
            &ctx.device,
            "item pass",
            &self.reduce.get_bind_group_layout(0),
            &[
                (3, info.as_entire_binding()),
                (6, bin_buffer.as_entire_binding()),
                (7, slot_object.as_entire_binding()),
                (8, totals.as_entire_binding()),
            ],
        );
        for (pipeline, group, threads) in [(&self.histogram, &histogram, pixels), (&self.reduce, &reduce, bins)] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("item counts"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            let (x, y) = workgroups(threads);
            pass.dispatch_workgroups(x, y, 1);
        }
        encoder.copy_buffer_to_buffer(&bin_buffer, 0, &staging, 0, bin_bytes);
        encoder.copy_buffer_to_buffer(&totals, 0, &staging, bin_bytes, total_bytes);
        ctx.queue.submit([encoder.finish()]);
        let size = bin_bytes + total_bytes;
        Mapping::start(&staging, size.max(4)).wait(ctx)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&take_bytes(&staging, size.max(4))?);
        let total = |range: std::ops::Range<u32>| -> Vec<u64> {
            words[(bins + range.start) as usize..(bins + range.end) as usize].iter().map(|&c| u64::from(c)).collect()
        };
        Ok(ItemCounts {
            bins: words[..bins as usize].to_vec(),
            instances: total(0..slots),
            objects: total(slots..slots + objects),
            tiles: total(slots + objects..slots + objects + tiles),
        })
    }
}

/// `0..n` in a fixed pseudo-random order.
fn scrambled(n: u32) -> Vec<u32> {
    let mut order: Vec<u32> = (0..n).collect();
    let mut rng = Rng::new(0x17E3, 0);
    for k in (1..order.len()).rev() {
        order.swap(k, rng.below(k as u32 + 1) as usize);
    }
    order
}

/// A storage buffer holding `words` (at least one word, so that an empty
/// array binds), with `usage` besides.
fn storage(ctx: &GpuContext, label: &str, words: &[u32], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let contents: &[u32] = if words.is_empty() { &[0] } else { words };
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(contents),
        usage: wgpu::BufferUsages::STORAGE | usage,
    })
}
