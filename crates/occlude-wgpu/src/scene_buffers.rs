//! A scene's geometry on the GPU, uploaded once per run and shared by every
//! method's backend: one vertex and one index pool, instance transforms in a
//! storage buffer (an instance is drawn with `first_instance` = its index),
//! and one bind group per material.

use crate::context::{GpuContext, GpuError};
use crate::culling::CullingScene;
use crate::pipelines::Pipelines;
use crate::query_boxes::box_index_buffer;
use occlude_core::rng::mix64;
use occlude_core::Scene;
use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};
use wgpu::util::DeviceExt;

/// Colour target format of the backend's off-screen render target (what a
/// viewer drawing over [`crate::WgpuBackend::color_view`] must render to).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Where a mesh lies in the index and vertex pools.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshRange {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
}

/// A scene uploaded to the GPU with the pipelines that draw it.
pub struct GpuScene {
    pub(crate) ctx: Arc<GpuContext>,
    pub(crate) pipelines: Pipelines,
    pub(crate) vertices: wgpu::Buffer,
    pub(crate) indices: wgpu::Buffer,
    pub(crate) transforms: wgpu::Buffer,
    /// The corner indices of a box's triangles, drawn once per query box
    /// (`query_boxes::box_index_buffer`).
    pub(crate) box_indices: wgpu::Buffer,
    pub(crate) meshes: Vec<MeshRange>,
    /// Per instance, its material's bind group in `material_groups`.
    pub(crate) instance_material: Vec<u32>,
    pub(crate) material_groups: Vec<wgpu::BindGroup>,
    /// GPU-resident culling's pipelines and per-instance data, built when a
    /// backend first uses it.
    culling: OnceLock<Arc<CullingScene>>,
}

/// The transform an instance is drawn with: its own, or all zeros while it
/// is hidden (every vertex at the clip-space origin with `w` = 0, which
/// the rasterizer clips away).
fn drawn_transform(instance: &occlude_core::Instance) -> [f32; 16] {
    if instance.enabled {
        instance.transform.to_cols_array()
    } else {
        [0.0; 16]
    }
}

/// Bytes between two materials' colours in the material buffer (the
/// uniform-offset alignment every adapter accepts).
const MATERIAL_STRIDE: u64 = 256;

impl GpuScene {
    /// Uploads `scene`; fails with [`GpuError::TooLarge`] when a pool would
    /// exceed the adapter's buffer limits.
    pub fn new(ctx: Arc<GpuContext>, scene: &Scene) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let pipelines = Pipelines::new(device, COLOR_FORMAT);
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut meshes = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            let base_vertex = i32::try_from(positions.len()).map_err(|_| too_large(&ctx, "over 2^31 vertices"))?;
            meshes.push(MeshRange {
                first_index: indices.len() as u32,
                index_count: mesh.indices.len() as u32,
                base_vertex,
            });
            positions.extend(mesh.positions.iter().map(|p| p.to_array()));
            indices.extend_from_slice(&mesh.indices);
        }
        let transforms: Vec<[f32; 16]> = scene.instances.iter().map(drawn_transform).collect();
        let limits = device.limits();
        for (name, bytes) in [
            ("vertex pool", positions.len() as u64 * 12),
            ("index pool", indices.len() as u64 * 4),
            ("instance transforms", transforms.len() as u64 * 64),
        ] {
            if bytes > limits.max_buffer_size
                || (name == "instance transforms" && bytes > limits.max_storage_buffer_binding_size)
            {
                return Err(too_large(&ctx, &format!("its {name} needs {bytes} bytes, more than the adapter allows")));
            }
        }
        let upload = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            // A zero-sized binding is invalid: an empty pool still gets 16 bytes.
            let padded;
            let contents = if contents.is_empty() {
                padded = [0u8; 16];
                &padded[..]
            } else {
                contents
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let vertices = upload("vertices", bytemuck::cast_slice(&positions), wgpu::BufferUsages::VERTEX);
        let index_buffer = upload("indices", bytemuck::cast_slice(&indices), wgpu::BufferUsages::INDEX);
        let transform_buffer = upload(
            "transforms",
            bytemuck::cast_slice(&transforms),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let box_indices = box_index_buffer(device);

        let (instance_material, material_groups) = material_groups(&ctx, &pipelines, scene);
        Ok(Self {
            ctx,
            pipelines,
            vertices,
            indices: index_buffer,
            transforms: transform_buffer,
            box_indices,
            meshes,
            instance_material,
            material_groups,
            culling: OnceLock::new(),
        })
    }

    /// Writes the transforms of the `changed` instances of `scene` (the
    /// scene this was uploaded from, after it moved): one queue write each.
    pub(crate) fn write_transforms(&self, scene: &Scene, changed: &[u32]) {
        for &i in changed {
            let t = drawn_transform(&scene.instances[i as usize]);
            self.ctx.queue.write_buffer(&self.transforms, u64::from(i) * 64, bytemuck::cast_slice(&t));
        }
    }

    /// GPU-resident culling's shared part for `scene` (the scene this was
    /// uploaded from), built on first use; the device must have what culling
    /// needs ([`GpuContext::gpu_culling_support`]).
    pub(crate) fn culling(&self, scene: &Scene) -> Arc<CullingScene> {
        Arc::clone(self.culling.get_or_init(|| Arc::new(CullingScene::new(self, scene))))
    }

    /// The device this scene lives on.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }
}

/// One bind group per distinct material id (dense, in id order), each with a
/// colour derived from the id, and every instance's group.
fn material_groups(ctx: &GpuContext, pipelines: &Pipelines, scene: &Scene) -> (Vec<u32>, Vec<wgpu::BindGroup>) {
    let ids: BTreeMap<u32, u32> = scene
        .instances
        .iter()
        .map(|i| i.material)
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .zip(0..)
        .collect();
    let count = ids.len().max(1) as u64;
    let mut bytes = vec![0u8; (count * MATERIAL_STRIDE) as usize];
    for (&id, &slot) in &ids {
        let at = slot as usize * MATERIAL_STRIDE as usize;
        bytes[at..at + 16].copy_from_slice(bytemuck::cast_slice(&material_color(id)));
    }
    let buffer = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("materials"),
        contents: &bytes,
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let groups = (0..count)
        .map(|slot| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("material"),
                layout: &pipelines.material_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &buffer,
                        offset: slot * MATERIAL_STRIDE,
                        size: wgpu::BufferSize::new(16),
                    }),
                }],
            })
        })
        .collect();
    let per_instance = scene.instances.iter().map(|i| ids[&i.material]).collect();
    (per_instance, groups)
}

/// The colour of material `id`, derived from the id.
pub(crate) fn material_color(id: u32) -> [f32; 4] {
    let h = mix64(u64::from(id));
    let channel = |shift: u32| 0.3 + 0.7 * ((h >> shift) & 0xff) as f32 / 255.0;
    [channel(0), channel(8), channel(16), 1.0]
}

fn too_large(ctx: &GpuContext, reason: &str) -> GpuError {
    GpuError::TooLarge { adapter: ctx.info.name.clone(), reason: reason.to_string() }
}
