//! The CHC paper's Figure 4 view (key V): every query box of the frame drawn
//! over the image as an opaque outline, green where the query found it
//! visible, red where it was occluded, yellow where the method never read
//! the answer; occluded and unread boxes are also filled, translucent. No
//! depth test: occluded boxes are hidden behind geometry, and showing them is
//! the point. (Visible boxes get no faces: the queries of a visible node's
//! ancestors are visible too, and their nested faces would tint the whole
//! image.) The GPU-driven methods' batched box tests are drawn the same
//! way, green or red: all of them, or one batch at a time (key L), which for
//! `ioc` is one level of the hierarchy (the IOC poster's Figure 4).

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

/// Each box of `queries` with its query's outcome.
pub fn of_queries(queries: &[RecordedQuery]) -> impl Iterator<Item = (&Aabb, QueryOutcome)> {
    queries.iter().flat_map(|q| q.boxes.iter().map(move |b| (b, q.outcome())))
}

/// Each box of `tests` with its outcome: visible where its flag was set,
/// else occluded (a box test's result is always read, on the device).
pub fn of_box_tests<'a>(
    tests: impl IntoIterator<Item = &'a RecordedBoxTest>,
) -> impl Iterator<Item = (&'a Aabb, QueryOutcome)> {
    tests.into_iter().flat_map(|t| {
        let outcome = |&v: &bool| if v { QueryOutcome::Visible } else { QueryOutcome::Occluded };
        t.boxes.iter().zip(t.visible.iter().map(outcome))
    })
}

/// The geometry of `boxes`, each coloured by its outcome.
pub fn geometry<'a>(boxes: impl IntoIterator<Item = (&'a Aabb, QueryOutcome)>) -> BoxGeometry {
    let mut out = BoxGeometry::default();
    for (aabb, outcome) in boxes {
        let [r, g, b] = outcome_color(outcome);
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
    /// first, outlines over them.
    pub fn draw(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        camera: &Camera,
        geometry: &BoxGeometry,
    ) {
        if geometry.edges.is_empty() {
            return;
        }
        queue.write_buffer(&self.camera, 0, bytemuck::cast_slice(&camera.view_projection().to_cols_array()));
        let upload = |vertices: &[BoxVertex]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("box vertices"),
                contents: bytemuck::cast_slice(vertices),
                usage: wgpu::BufferUsages::VERTEX,
            })
        };
        let (faces, edges) = (upload(&geometry.faces), upload(&geometry.edges));
        let mut pass = draw_over(encoder, target, "query boxes");
        pass.set_bind_group(0, &self.group, &[]);
        for (pipeline, buffer, count) in
            [(&self.faces, &faces, geometry.faces.len()), (&self.edges, &edges, geometry.edges.len())]
        {
            pass.set_pipeline(pipeline);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..count as u32, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn every_box_gets_its_faces_and_edges_in_its_outcome_colour() {
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let queries = [
            RecordedQuery { boxes: vec![unit, unit], result: Some(7) },
            RecordedQuery { boxes: vec![unit], result: Some(0) },
            RecordedQuery { boxes: vec![unit], result: None },
        ];
        let g = geometry(of_queries(&queries));
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
            RecordedBoxTest { boxes: vec![unit, unit], visible: vec![true, false] },
            RecordedBoxTest { boxes: vec![unit], visible: vec![false] },
        ];
        let outcomes: Vec<_> = of_box_tests(&tests).map(|(_, o)| o).collect();
        use QueryOutcome::{Occluded, Visible};
        assert_eq!(outcomes, [Visible, Occluded, Occluded]);
        let g = geometry(of_box_tests(&tests[1..]));
        assert_eq!((g.faces.len(), g.edges.len()), (36, 24));
    }
}
