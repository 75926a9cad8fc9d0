//! Drawing images with the GPU: [`Blit`] draws a texture over a rectangle of
//! a render target (the whole window, or the overlay's corner of the
//! frame), and [`Presenter`] owns the window's surface and copies the
//! finished frame to it.

use anyhow::{Context, Result};

/// A pipeline layout and sampler for drawing a texture over a rectangle;
/// pipelines are made per target format.
pub struct Blit {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    sampler: wgpu::Sampler,
}

impl Blit {
    /// The shared parts, made once per device.
    pub fn new(device: &wgpu::Device) -> Self {
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: fragment,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: fragment,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("blit"),
            source: wgpu::ShaderSource::Wgsl(include_str!("present.wgsl").into()),
        });
        // Linear: exact where image and rectangle have the same size (every
        // sample falls on a texel centre), smooth where they do not.
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("blit"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self { layout, pipeline_layout, module, sampler }
    }

    /// A pipeline drawing into targets of `format`; with `blend` the image
    /// is blended over the target by its alpha, otherwise it replaces it.
    pub fn pipeline(&self, device: &wgpu::Device, format: wgpu::TextureFormat, blend: bool) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.module,
                entry_point: Some("vs_cover"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &self.module,
                entry_point: Some("fs_image"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// The bind group that makes `image` the texture drawn.
    pub fn bind(&self, device: &wgpu::Device, image: &wgpu::TextureView) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit image"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(image) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
            ],
        })
    }
}

/// Where in a target an image is drawn: `x`, `y`, width, height in pixels
/// (the whole target when `None`).
pub type Rect = Option<[u32; 4]>;

/// Begins a pass that draws over `target`, keeping its pixels (no depth):
/// the viewer's layers over the method's frame.
pub fn draw_over<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Encodes drawing `image` (bound by [`Blit::bind`]) with `pipeline` over
/// `rect` of `target`, keeping the target's other pixels.
pub fn draw_image(
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    image: &wgpu::BindGroup,
    rect: Rect,
) {
    let mut pass = draw_over(encoder, target, "blit");
    if let Some([x, y, w, h]) = rect {
        pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
    }
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, image, &[]);
    pass.draw(0..3, 0..1);
}

/// The window's surface, configured for its size, and the pipeline that
/// copies a frame to it.
pub struct Presenter {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The format frames are drawn in: the surface's without sRGB encoding,
    /// so that the backend's colours reach the screen unchanged.
    view_format: wgpu::TextureFormat,
    pipeline: wgpu::RenderPipeline,
}

impl Presenter {
    /// Configures `surface` for `adapter`'s device at `width` x `height`.
    pub fn new(
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        blit: &Blit,
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let mut config = surface
            .get_default_config(adapter, width.max(1), height.max(1))
            .with_context(|| format!("the GPU adapter '{}' cannot draw to this window", adapter.get_info().name))?;
        let view_format = config.format.remove_srgb_suffix();
        if view_format != config.format {
            config.view_formats.push(view_format);
        }
        // Paced by the display; wgpu picks a mode every surface has.
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(device, &config);
        let pipeline = blit.pipeline(device, view_format, false);
        Ok(Self { surface, config, view_format, pipeline })
    }

    /// Follows a window resize (a zero size is ignored: the window is
    /// minimized and nothing is drawn).
    pub fn resize(&mut self, device: &wgpu::Device, (width, height): (u32, u32)) {
        if width > 0 && height > 0 && (width, height) != (self.config.width, self.config.height) {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(device, &self.config);
        }
    }

    /// Draws `frame` (bound by [`Blit::bind`]) over the whole window and
    /// shows it. A frame the surface cannot take now (window hidden, being
    /// resized) is skipped; a lost surface is reconfigured.
    pub fn present(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, frame: &wgpu::BindGroup) {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(device, &self.config);
                return;
            }
            _ => return,
        };
        let view = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor { format: Some(self.view_format), ..Default::default() });
        let mut encoder = device.create_command_encoder(&Default::default());
        draw_image(&mut encoder, &view, &self.pipeline, frame, None);
        queue.submit([encoder.finish()]);
        queue.present(texture);
    }
}
