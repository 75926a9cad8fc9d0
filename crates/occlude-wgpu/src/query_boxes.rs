//! What occlusion queries rasterize on the GPU, shared by [`WgpuBackend`]
//! and the embedding (module `embed`): the padded boxes of a submission as
//! rows of a storage buffer (`QueryBox` in `shader.wgsl`), the corner
//! indices drawn once per box, and the camera uniform whose depth bias keeps
//! geometry on a box face from hiding the box
//! ([`QUERY_DEPTH_BIAS`](occlude_core::query_box::QUERY_DEPTH_BIAS)).
//!
//! [`WgpuBackend`]: crate::WgpuBackend

use occlude_core::query_box::BOX_TRIANGLES;
use occlude_core::Aabb;
use std::ops::Range;
use wgpu::util::DeviceExt;

/// Bytes of one query box in the box buffer (min, a slot, max, padding), as
/// `QueryBox` in `shader.wgsl` and `Box` in `cull.wgsl`.
pub(crate) const BOX_BYTES: u64 = 32;

/// Corner indices of one box's 12 triangles: the index count of a box draw.
pub(crate) const BOX_INDEX_COUNT: u32 = (BOX_TRIANGLES.len() * 3) as u32;

/// Floats of the camera uniform, `Camera` in `shader.wgsl`: the
/// view-projection matrix (16) and the query depth bias (padded to a vec4).
const CAMERA_UNIFORM_FLOATS: usize = 16 + 4;

/// The box buffer's first size: room for a few boxes; it grows to the next
/// power of two of what a submission needs.
const INITIAL_BOX_BUFFER_BYTES: u64 = 8 * BOX_BYTES;

/// The camera uniform buffer (`Camera` in `shader.wgsl`).
pub(crate) fn camera_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("camera"),
        size: (CAMERA_UNIFORM_FLOATS * std::mem::size_of::<f32>()) as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Writes `view_projection` and the query boxes' depth `bias` (subtracted
/// as `z - bias * w`: positive where smaller depth is nearer) into `buffer`.
pub(crate) fn write_camera(queue: &wgpu::Queue, buffer: &wgpu::Buffer, view_projection: &glam::Mat4, bias: f32) {
    let mut uniform = [0f32; CAMERA_UNIFORM_FLOATS];
    uniform[..16].copy_from_slice(&view_projection.to_cols_array());
    uniform[16] = bias;
    queue.write_buffer(buffer, 0, bytemuck::cast_slice(&uniform));
}

/// The index buffer of [`BOX_TRIANGLES`]' corners, drawn once per query box.
pub(crate) fn box_index_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    let corners: Vec<u32> = BOX_TRIANGLES.iter().flatten().map(|&c| u32::from(c)).collect();
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("box corners"),
        contents: bytemuck::cast_slice(&corners),
        usage: wgpu::BufferUsages::INDEX,
    })
}

/// The query boxes recorded for the next submission and the storage buffer
/// they are uploaded to.
pub(crate) struct BoxRows {
    /// The storage buffer (binding 2 of group 0 in `shader.wgsl`).
    pub buffer: wgpu::Buffer,
    rows: Vec<[f32; 8]>,
}

impl BoxRows {
    /// An empty set with a small buffer.
    pub fn new(device: &wgpu::Device) -> Self {
        Self { buffer: box_buffer(device, INITIAL_BOX_BUFFER_BYTES), rows: Vec::new() }
    }

    /// Adds `boxes` (already padded), each carrying `id` in its slot word,
    /// and returns their rows: the instance range of their draw.
    pub fn push(&mut self, boxes: &[Aabb], id: f32) -> Range<u32> {
        let first = self.rows.len() as u32;
        self.rows.extend(boxes.iter().map(|b| {
            let (lo, hi) = (b.min, b.max);
            [lo.x, lo.y, lo.z, id, hi.x, hi.y, hi.z, 0.0]
        }));
        first..self.rows.len() as u32
    }

    /// Writes the recorded rows to the buffer, replacing it by a larger one
    /// when they do not fit; true when it was replaced (bind groups naming
    /// it must be made again).
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> bool {
        if self.rows.is_empty() {
            return false;
        }
        let bytes = self.rows.len() as u64 * BOX_BYTES;
        let grown = bytes > self.buffer.size();
        if grown {
            self.buffer = box_buffer(device, bytes.next_power_of_two());
        }
        queue.write_buffer(&self.buffer, 0, bytemuck::cast_slice(&self.rows));
        grown
    }

    /// Forgets the rows (after their submission).
    pub fn clear(&mut self) {
        self.rows.clear();
    }
}

fn box_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("query boxes"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
