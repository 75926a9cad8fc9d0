//! A backend's off-screen render target: colour and depth textures, the
//! depth image read back for the correctness rule and the colour image read
//! back for screenshots.

use crate::context::GpuContext;
use crate::pipelines::{texture_2d, DEPTH_FORMAT};
use crate::readback::{take_bytes, Mapping};
use crate::scene_buffers::COLOR_FORMAT;

/// Colour and depth textures of one size.
pub(crate) struct RenderTarget {
    pub width: u32,
    pub height: u32,
    pub color_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
    color: wgpu::Texture,
    pub depth: wgpu::Texture,
}

impl RenderTarget {
    /// A target of `width` x `height` pixels.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        // Sampled too: the viewer draws the colour image to its window.
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING;
        let texture = |label: &str, format| texture_2d(&ctx.device, label, (width, height), format, usage);
        let color = texture("colour", COLOR_FORMAT);
        let depth = texture("depth", DEPTH_FORMAT);
        Self {
            width,
            height,
            color_view: color.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            color,
            depth,
        }
    }

    /// The colour image as RGBA8, row 0 at the top, read back after all
    /// submitted work (blocking).
    pub fn read_color(&self, ctx: &GpuContext) -> Result<Vec<u8>, String> {
        self.read_texture(ctx, &self.color, wgpu::TextureAspect::All)
    }

    /// The depth image, row 0 at the top, read back into `out` (replacing
    /// what it held) after all submitted work (blocking; used outside the
    /// frame's clock).
    pub fn read_depth(&self, ctx: &GpuContext, out: &mut Vec<f32>) -> Result<(), String> {
        let bytes = self.read_texture(ctx, &self.depth, wgpu::TextureAspect::DepthOnly)?;
        out.clear();
        out.extend(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])));
        Ok(())
    }

    /// The pixels of `texture` (4 bytes each, as both formats have), rows
    /// packed, read back after all submitted work (blocking).
    fn read_texture(
        &self,
        ctx: &GpuContext,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<Vec<u8>, String> {
        let row_bytes = self.width * 4;
        let padded_row = row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let size = u64::from(padded_row) * u64::from(self.height);
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image read-back"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        ctx.queue.submit([encoder.finish()]);
        Mapping::start(&buffer, size).wait(ctx)?;
        let bytes = take_bytes(&buffer, size)?;
        Ok(bytes.chunks_exact(padded_row as usize).flat_map(|row| &row[..row_bytes as usize]).copied().collect())
    }
}
