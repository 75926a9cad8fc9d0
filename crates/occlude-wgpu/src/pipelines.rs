//! The render pipelines: drawing instances, rasterizing query boxes, the
//! oracle's depth-equal test of instances, and for GPU-resident culling the
//! batched box tests and the list draws.

/// Depth format of every render target: 32-bit float, the same values the
/// soft rasterizer stores.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Bytes of one vertex (a position).
const VERTEX_STRIDE: u64 = 12;

/// The compute pipeline of `entry` in `module`, its layout derived from
/// the bindings the entry point uses.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A bind group called `label` of `resources` at their bindings in `layout`.
pub(crate) fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .iter()
        .map(|(binding, resource)| wgpu::BindGroupEntry { binding: *binding, resource: resource.clone() })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

/// A `width` x `height` 2D texture of one mip level and sample.
pub(crate) fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// Pipelines and bind-group layouts for one colour format.
pub(crate) struct Pipelines {
    /// Group 0: camera uniform, instance transforms, query boxes.
    pub frame_layout: wgpu::BindGroupLayout,
    /// Group 1: one material's colour; switching it is the state change the
    /// CHC++ paper counts.
    pub material_layout: wgpu::BindGroupLayout,
    /// Instances, depth test less, depth writes on, shaded colour.
    pub draw: wgpu::RenderPipeline,
    /// Query boxes: front faces only, depth test less, no writes.
    pub query: wgpu::RenderPipeline,
    /// Instances again, depth test equal, no writes: which instances own a
    /// pixel of the final image (`opt`'s oracle).
    pub oracle: wgpu::RenderPipeline,
    module: wgpu::ShaderModule,
    color_format: wgpu::TextureFormat,
}

/// The render pipelines of GPU-resident culling.
pub(crate) struct CullingPipelines {
    /// Group 1 of box tests: the flags their fragments set.
    pub flags_layout: wgpu::BindGroupLayout,
    /// Group 1 of list draws: every instance's colour.
    pub colors_layout: wgpu::BindGroupLayout,
    /// Group 1 of counted queries: their counts.
    pub counts_layout: wgpu::BindGroupLayout,
    /// Box tests: the query pipeline, its fragments setting the box's flag
    /// after the depth test.
    pub test: wgpu::RenderPipeline,
    /// List draws: the draw pipeline, the colour read per instance (one
    /// multi-draw has one bind group).
    pub list: wgpu::RenderPipeline,
    /// Counted queries (`--queries hib`): the query pipeline, its fragments
    /// adding to their query's count after the depth test.
    pub count: wgpu::RenderPipeline,
}

/// How one pipeline differs from the others.
pub(crate) struct Variant<'a> {
    pub label: &'a str,
    pub vertex_entry: &'a str,
    pub fragment_entry: &'a str,
    /// Module of the fragment entry, when not the scene shaders': the
    /// culling fragments (`cull_fragments.wgsl`), which write storage, so
    /// their stage is kept even without a colour target.
    pub fragment_module: Option<&'a wgpu::ShaderModule>,
    pub instance_vertices: bool,
    pub depth_write: bool,
    pub compare: wgpu::CompareFunction,
    pub cull_back: bool,
    pub color: bool,
}

/// Instances, depth test less, depth writes on, shaded colour.
pub(crate) const DRAW: Variant<'static> = Variant {
    label: "draw",
    vertex_entry: "vs_instance",
    fragment_entry: "fs_shaded",
    fragment_module: None,
    instance_vertices: true,
    depth_write: true,
    compare: wgpu::CompareFunction::Less,
    cull_back: false,
    color: true,
};

/// Query boxes: front faces only, depth test less, no writes.
pub(crate) const QUERY: Variant<'static> = Variant {
    label: "query boxes",
    vertex_entry: "vs_query_box",
    fragment_entry: "fs_none",
    fragment_module: None,
    instance_vertices: false,
    depth_write: false,
    compare: wgpu::CompareFunction::Less,
    cull_back: true,
    color: false,
};

impl Pipelines {
    /// Builds the pipelines for colour target `color_format`.
    pub fn new(device: &wgpu::Device, color_format: wgpu::TextureFormat) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("occlude shaders"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let vertex = wgpu::ShaderStages::VERTEX;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[
                layout_entry(0, vertex, wgpu::BufferBindingType::Uniform),
                layout_entry(1, vertex, wgpu::BufferBindingType::Storage { read_only: true }),
                layout_entry(2, vertex, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[layout_entry(0, wgpu::ShaderStages::FRAGMENT, wgpu::BufferBindingType::Uniform)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("occlude"),
            bind_group_layouts: &[Some(&frame_layout), Some(&material_layout)],
            immediate_size: 0,
        });
        let build = |v: Variant| build_pipeline(device, Some(&layout), &module, Targets::scene(color_format), v);
        let draw = build(DRAW);
        let query = build(QUERY);
        let oracle = build(Variant {
            label: "oracle",
            fragment_entry: "fs_none",
            depth_write: false,
            compare: wgpu::CompareFunction::Equal,
            color: false,
            ..DRAW
        });
        Self { frame_layout, material_layout, draw, query, oracle, module, color_format }
    }

    /// The pipelines of GPU-resident culling, whose box-test fragments are
    /// `fs_test_box` of `cull_module`. Only for a device with forced early
    /// depth tests.
    pub fn culling(&self, device: &wgpu::Device, cull_module: &wgpu::ShaderModule) -> CullingPipelines {
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let group1 = |label, binding, read_only| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &[layout_entry(binding, fragment, wgpu::BufferBindingType::Storage { read_only })],
            })
        };
        // Bindings as in shader.wgsl and cull.wgsl.
        let flags_layout = group1("box-test flags", 0, false);
        let colors_layout = group1("instance colours", 1, true);
        let counts_layout = group1("query counts", 2, false);
        let build = |group1: &wgpu::BindGroupLayout, v: Variant| {
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(v.label),
                bind_group_layouts: &[Some(&self.frame_layout), Some(group1)],
                immediate_size: 0,
            });
            build_pipeline(device, Some(&layout), &self.module, Targets::scene(self.color_format), v)
        };
        let test = build(
            &flags_layout,
            Variant { label: "box tests", fragment_entry: "fs_test_box", fragment_module: Some(cull_module), ..QUERY },
        );
        let list = build(&colors_layout, Variant { label: "list draws", fragment_entry: "fs_listed", ..DRAW });
        let count = build(
            &counts_layout,
            Variant {
                label: "counted queries",
                fragment_entry: "fs_count_box",
                fragment_module: Some(cull_module),
                ..QUERY
            },
        );
        CullingPipelines { flags_layout, colors_layout, counts_layout, test, list, count }
    }
}

/// A bind-group layout entry of a buffer.
pub(crate) fn layout_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// The attachment formats a render pipeline draws into.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Targets {
    /// The colour attachment's format, if the pass has one.
    pub color: Option<wgpu::TextureFormat>,
    /// The depth attachment's format.
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel of both.
    pub samples: u32,
}

impl Targets {
    /// A colour target of `color` and this crate's depth format.
    pub fn scene(color: wgpu::TextureFormat) -> Self {
        Self { color: Some(color), depth: DEPTH_FORMAT, samples: 1 }
    }
}

/// A render pipeline of `module` (and `v.fragment_module`) as `v` says,
/// drawing into `targets`; without `layout`, its layout is derived from
/// the bindings its entry points use.
pub(crate) fn build_pipeline(
    device: &wgpu::Device,
    layout: Option<&wgpu::PipelineLayout>,
    module: &wgpu::ShaderModule,
    targets: Targets,
    v: Variant,
) -> wgpu::RenderPipeline {
    let positions = wgpu::VertexBufferLayout {
        array_stride: VERTEX_STRIDE,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3],
    };
    let buffers = if v.instance_vertices { vec![Some(positions)] } else { Vec::new() };
    let write_mask = if v.color { wgpu::ColorWrites::ALL } else { wgpu::ColorWrites::empty() };
    let color_targets = &[targets.color.map(|format| wgpu::ColorTargetState { format, blend: None, write_mask })];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(v.label),
        layout,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(v.vertex_entry),
            compilation_options: Default::default(),
            buffers: &buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: v.cull_back.then_some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: targets.depth,
            depth_write_enabled: Some(v.depth_write),
            depth_compare: Some(v.compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: targets.samples, ..Default::default() },
        // Without a colour target, a depth-only pipeline (no fragment stage),
        // unless its fragments write storage; their colour output is then
        // ignored.
        fragment: (targets.color.is_some() || v.fragment_module.is_some()).then(|| wgpu::FragmentState {
            module: v.fragment_module.unwrap_or(module),
            entry_point: Some(v.fragment_entry),
            compilation_options: Default::default(),
            targets: if targets.color.is_some() { color_targets } else { &[] },
        }),
        multiview_mask: None,
        cache: None,
    })
}
