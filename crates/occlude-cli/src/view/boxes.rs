//! The CHC paper's Figure 4 view (key V): every query box of the frame drawn
//! over the image as an opaque outline, green where the query found it
//! visible, red where it was occluded, yellow where the method never read
//! the answer; occluded and unread boxes are also filled, translucent. No
//! depth test: occluded boxes are hidden behind geometry, and showing them is
//! the point. (Visible boxes get no faces: the queries of a visible node's
//! ancestors are visible too, and their nested faces would tint the whole
//! image.) The GPU-driven methods' batched box tests are drawn the same
//! way, green or red: all of them, or one batch at a time (key L), which for
//! `ioc` is one level of the hierarchy (the IOC poster's Figure 2).
//!
//! Coloured by pyramid level (key Z), the boxes of tests against a depth
//! pyramid (`hiz`'s late pass) take the colour of the level each was tested
//! at ([`LEVEL_COLOURS`], the level `RecordedBoxTest::levels` records from
//! `depth_pyramid`'s own selection); hidden ones are still filled, and
//! boxes tested at no level (at the eye, off screen, or by a
//! full-resolution test or query) are grey.

use super::present::draw_over;
use occlude_core::query_box::BOX_TRIANGLES;
use occlude_core::recording::{QueryOutcome, RecordedBoxTest, RecordedQuery};
use occlude_core::{Aabb, Camera};
use wgpu::util::DeviceExt;

/// Outline colour of a box whose query found visible pixels.
pub const VISIBLE: [f32; 3] = [0.0, 1.0, 0.0];
/// Outline colour of a box whose query found none.
pub const OCCLUDED: [f32; 3] = [1.0, 0.0, 0.0];
/// Outline colour of a box whose result the method never read.
pub const UNREAD: [f32; 3] = [1.0, 1.0, 0.0];

/// The colours of pyramid levels 0, 1, ...; the last one also for every
/// coarser level. Named for the overlay's legend.
pub const LEVEL_COLOURS: [(&str, [f32; 3]); 8] = [
    ("blue", [0.0, 0.0, 1.0]),
    ("cyan", [0.0, 1.0, 1.0]),
    ("green", [0.0, 1.0, 0.0]),
    ("yellow", [1.0, 1.0, 0.0]),
    ("orange", [1.0, 0.5, 0.0]),
    ("red", [1.0, 0.0, 0.0]),
    ("magenta", [1.0, 0.0, 1.0]),
    ("white", [1.0, 1.0, 1.0]),
];

/// Colour of a box tested at no pyramid level, when colouring by level.
pub const NO_LEVEL: [f32; 3] = [0.5, 0.5, 0.5];

/// What the boxes' colours show.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Colouring {
    /// The outcome: [`VISIBLE`], [`OCCLUDED`] or [`UNREAD`].
    #[default]
    Outcome,
    /// The pyramid level the box was tested at ([`level_colour`]).
    PyramidLevel,
}

/// A box to draw: its outcome and, for a pyramid test, the level it was
/// tested at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShownBox<'a> {
    /// The box, as the method gave it.
    pub aabb: &'a Aabb,
    /// What its query or test found.
    pub outcome: QueryOutcome,
    /// The pyramid level it was tested at, if any.
    pub level: Option<u32>,
}

/// Opacity of the faces of occluded and unread boxes (outlines are opaque).
const FACE_ALPHA: f32 = 0.08;

/// One vertex: a world position and a colour with alpha.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BoxVertex {
    /// World position.
    pub position: [f32; 3],
    /// RGBA colour.
    pub color: [f32; 4],
}

/// The triangles of the boxes' faces and the line segments of their edges.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoxGeometry {
    /// Triangle list, 36 vertices per occluded or unread box.
    pub faces: Vec<BoxVertex>,
    /// Line list, 24 vertices per box (its 12 edges).
    pub edges: Vec<BoxVertex>,
}

/// The colour of a box with this outcome.
pub fn outcome_color(outcome: QueryOutcome) -> [f32; 3] {
    match outcome {
        QueryOutcome::Visible => VISIBLE,
        QueryOutcome::Occluded => OCCLUDED,
        QueryOutcome::Unread => UNREAD,
    }
}

/// The colour of pyramid level `level` ([`LEVEL_COLOURS`]).
pub fn level_colour(level: u32) -> [f32; 3] {
    LEVEL_COLOURS[(level as usize).min(LEVEL_COLOURS.len() - 1)].1
}

/// Each box of `queries` with its query's outcome.
pub fn of_queries(queries: &[RecordedQuery]) -> impl Iterator<Item = ShownBox<'_>> {
    queries.iter().flat_map(|q| q.boxes.iter().map(move |aabb| ShownBox { aabb, outcome: q.outcome(), level: None }))
}

/// Each box of `tests` with its outcome (visible where its flag was set,
/// else occluded: a box test's result is always read, on the device) and
/// its pyramid level.
pub fn of_box_tests<'a>(tests: impl IntoIterator<Item = &'a RecordedBoxTest>) -> impl Iterator<Item = ShownBox<'a>> {
    tests.into_iter().flat_map(|t| {
        let outcome = |v: bool| if v { QueryOutcome::Visible } else { QueryOutcome::Occluded };
        let levels = t.levels.iter().copied().chain(std::iter::repeat(None));
        t.boxes.iter().zip(&t.visible).zip(levels).map(move |((aabb, &v), level)| ShownBox {
            aabb,
            outcome: outcome(v),
            level,
        })
    })
}

/// The geometry of `boxes`, each coloured as `colouring` says; occluded and
/// unread boxes also get faces.
pub fn geometry<'a>(boxes: impl IntoIterator<Item = ShownBox<'a>>, colouring: Colouring) -> BoxGeometry {
    let mut out = BoxGeometry::default();
    for ShownBox { aabb, outcome, level } in boxes {
        let [r, g, b] = match colouring {
            Colouring::Outcome => outcome_color(outcome),
            Colouring::PyramidLevel => level.map_or(NO_LEVEL, level_colour),
        };
        let corners = aabb.corners();
        let vertex = |c: u8, a: f32| BoxVertex { position: corners[c as usize].to_array(), color: [r, g, b, a] };
        if outcome != QueryOutcome::Visible {
            out.faces.extend(BOX_TRIANGLES.iter().flatten().map(|&c| vertex(c, FACE_ALPHA)));
        }
        // The 12 edges join corners whose indices differ in one bit.
        for c in 0..8u8 {
            for bit in [1u8, 2, 4].into_iter().filter(|bit| c & bit == 0) {
                out.edges.extend([vertex(c, 1.0), vertex(c | bit, 1.0)]);
            }
        }
    }
    out
}

/// Pipelines that draw box geometry into a target of one format.
pub struct BoxRenderer {
    faces: wgpu::RenderPipeline,
    edges: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl BoxRenderer {
    /// Pipelines for targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("boxes"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("boxes camera"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("boxes"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("boxes"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("boxes"),
            source: wgpu::ShaderSource::Wgsl(include_str!("boxes.wgsl").into()),
        });
        let pipeline = |topology| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("boxes"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_box"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<BoxVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
                    })],
                },
                primitive: wgpu::PrimitiveState { topology, ..Default::default() },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_box"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            faces: pipeline(wgpu::PrimitiveTopology::TriangleList),
            edges: pipeline(wgpu::PrimitiveTopology::LineList),
            camera,
            group,
        }
    }

    /// Encodes drawing `geometry` seen by `camera` over `target`: faces
    /// first, outlines over them. Either may be empty (a frame where every
    /// box is visible has no faces): only a part with vertices is uploaded
    /// and drawn, as a vertex buffer may not be empty.
    pub fn draw(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        camera: &Camera,
        geometry: &BoxGeometry,
    ) {
        let parts: Vec<_> = [(&self.faces, &geometry.faces), (&self.edges, &geometry.edges)]
            .into_iter()
            .filter(|(_, vertices)| !vertices.is_empty())
            .map(|(pipeline, vertices)| {
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("box vertices"),
                    contents: bytemuck::cast_slice(vertices),
                    usage: wgpu::BufferUsages::VERTEX,
                });
                (pipeline, buffer, vertices.len() as u32)
            })
            .collect();
        if parts.is_empty() {
            return;
        }
        queue.write_buffer(&self.camera, 0, bytemuck::cast_slice(&camera.view_projection().to_cols_array()));
        let mut pass = draw_over(encoder, target, "query boxes");
        pass.set_bind_group(0, &self.group, &[]);
        for (pipeline, buffer, count) in &parts {
            pass.set_pipeline(pipeline);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..*count, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Drawing never binds an empty vertex buffer: a frame whose boxes are
    /// all visible (outlines, no faces) and one without boxes draw on a real
    /// device (lavapipe will do) without wgpu's validation failing. Skipped
    /// without an adapter unless `OCCLUDE_REQUIRE_GPU=1`.
    #[test]
    fn boxes_draw_whichever_of_faces_and_outlines_is_empty() {
        let ctx = match occlude_wgpu::GpuContext::new() {
            Ok(ctx) => ctx,
            Err(e) if std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("no adapter: {e}"),
            Err(e) => return eprintln!("skipping: no GPU adapter ({e})"),
        };
        let format = wgpu::TextureFormat::Rgba8Unorm;
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("boxes test"),
            size: wgpu::Extent3d { width: 16, height: 16, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let target = texture.create_view(&Default::default());
        let renderer = BoxRenderer::new(&ctx.device, format);
        let eye = occlude_core::Keyframe {
            time: 0.0,
            position: Vec3::new(0.5, 0.5, 5.0),
            target: Vec3::ZERO,
            fov_y_deg: 60.0,
        };
        let camera = eye.camera(1.0, 0.1, 100.0);
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let shown = |outcome| ShownBox { aabb: &unit, outcome, level: None };
        for boxes in [vec![shown(QueryOutcome::Visible)], vec![], vec![shown(QueryOutcome::Occluded)]] {
            let geometry = geometry(boxes, Colouring::Outcome);
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            renderer.draw(&ctx.device, &ctx.queue, &mut encoder, &target, &camera, &geometry);
            ctx.queue.submit([encoder.finish()]);
            ctx.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
            let failure = ctx.failure();
            assert!(failure.is_none(), "{} faces, {} edges: {failure:?}", geometry.faces.len(), geometry.edges.len());
        }
    }

    #[test]
    fn every_box_gets_its_faces_and_edges_in_its_outcome_colour() {
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let queries = [
            RecordedQuery { boxes: vec![unit, unit], result: Some(7) },
            RecordedQuery { boxes: vec![unit], result: Some(0) },
            RecordedQuery { boxes: vec![unit], result: None },
        ];
        let g = geometry(of_queries(&queries), Colouring::Outcome);
        assert_eq!((g.faces.len(), g.edges.len()), (2 * 36, 4 * 24), "faces of the occluded and unread boxes");
        let rgb = |v: &BoxVertex| [v.color[0], v.color[1], v.color[2]];
        assert!(g.edges[..48].iter().all(|v| rgb(v) == VISIBLE && v.color[3] == 1.0));
        assert!(g.edges[48..72].iter().all(|v| rgb(v) == OCCLUDED));
        assert!(g.edges[72..].iter().all(|v| rgb(v) == UNREAD));
        assert!(g.faces.iter().all(|v| v.color[3] < 1.0), "faces are translucent");
        assert!(g.faces[..36].iter().all(|v| v.color[..3] == OCCLUDED));
        // Each edge is one unit long and runs along one axis.
        for pair in g.edges.chunks_exact(2) {
            let d = Vec3::from(pair[1].position) - Vec3::from(pair[0].position);
            assert_eq!(d.abs().element_sum(), 1.0, "{pair:?}");
        }
    }

    #[test]
    fn box_tests_are_visible_or_occluded_box_by_box() {
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let tests = [
            RecordedBoxTest { boxes: vec![unit, unit], visible: vec![true, false], levels: vec![None; 2] },
            RecordedBoxTest { boxes: vec![unit], visible: vec![false], levels: vec![None] },
        ];
        let outcomes: Vec<_> = of_box_tests(&tests).map(|b| b.outcome).collect();
        use QueryOutcome::{Occluded, Visible};
        assert_eq!(outcomes, [Visible, Occluded, Occluded]);
        let g = geometry(of_box_tests(&tests[1..]), Colouring::Outcome);
        assert_eq!((g.faces.len(), g.edges.len()), (36, 24));
    }

    /// Coloured by level, each box of a pyramid test takes its level's
    /// colour (levels past the palette the last one, none grey) and the
    /// hidden ones keep their faces.
    #[test]
    fn pyramid_boxes_take_the_colour_of_their_level() {
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let levels = vec![Some(0), Some(3), Some(9), None];
        let tests = [RecordedBoxTest { boxes: vec![unit; 4], visible: vec![true, false, true, true], levels }];
        let g = geometry(of_box_tests(&tests), Colouring::PyramidLevel);
        let colours: Vec<[f32; 3]> =
            g.edges.chunks_exact(24).map(|e| [e[0].color[0], e[0].color[1], e[0].color[2]]).collect();
        assert_eq!(colours, [LEVEL_COLOURS[0].1, LEVEL_COLOURS[3].1, LEVEL_COLOURS[7].1, NO_LEVEL]);
        assert_eq!(g.faces.len(), 36, "the hidden box's faces");
        assert!(g.faces.iter().all(|v| v.color[..3] == LEVEL_COLOURS[3].1));
        // The outcome colours ignore the levels.
        let g = geometry(of_box_tests(&tests), Colouring::Outcome);
        assert!(g.edges[..24].iter().all(|v| v.color[..3] == VISIBLE));
    }
}
