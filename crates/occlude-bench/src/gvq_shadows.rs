//! `occlude bench --paper gvq`, Table 1: shadow-volume culling (Engelhardt
//! and Dachsbacher, section 4.1, "Shadow Volume Culling").
//!
//! The scene is Table 2's (`occlude_scenes::scattered`: 100 to 500
//! randomly placed tori of 606 triangles, the paper's triangle count; the
//! paper does not say what its objects are) with a point light above it
//! ([`light_position`]: a quarter turn about the box's vertical axis over
//! the walkthrough, so that every frame's light view differs), seen by the
//! camera circling it. Each frame renders shadows by the shadow-volume
//! algorithm [Crow 1977]: the scene's depth, every unculled object's
//! shadow volume into the stencil, the scene lit where the stencil allows.
//!
//! **What is queried.** The paper: "we determined the visibility of each
//! object with respect to the light source ... Shadow volumes are excluded
//! from rendering if an object is fully in shadow." So the query is each
//! object's visible pixels in the light's view of every object
//! ([`light_camera`], the paper's 512 x 512 query target unless told
//! otherwise), and an object with none has its volume culled. Why that
//! changes no shadow: a point the culled object shadows lies behind it on
//! a ray from the light, and that ray meets the object at a point which,
//! the object being hidden from the light, lies behind another object on
//! the same ray; so the point is in that object's shadow too, and the
//! stencil (zero or not) is unchanged. This holds exactly for the light's
//! pixel centres; between them an object the query image misses (a sliver
//! narrower than a pixel) can be culled though its shadow shows, which is
//! the paper's criterion's own approximation. The test
//! `culled_volumes_change_no_shadow` ray-casts every camera pixel's shadow
//! against all objects and against the unculled ones only and finds them
//! equal.
//!
//! **Methods** (the paper's columns): `none` (every volume; "nc"),
//! `sat-conservative` and `sat-approximate` (the summed-area-table counts of
//! Table 2's region sets, `occlude_soft::sat`; the paper's Table 1 does not
//! say which mode; approximate sets can count a lit object 0 and cull its
//! volume, a wrong shadow, reported as `lit_culled`), `hib` (one
//! hierarchical item-buffer pass, one tile: exact counts,
//! `SoftBackend::item_buffer`), and `hardware` (the paper's "pred.": a
//! depth pass of every object, then one occlusion query per object of its
//! own triangles against it with depth test *equal*, each object's volume
//! drawn by its own draw predicated on its query).
//!
//! **Cost** (`frame_ms`, the soft backend's simulated clock,
//! [`SimFrame`], with the GPU model's costs; no parameter added):
//! - every method: the camera's depth pass and lit pass, each one
//!   instanced draw of every object's triangles and their fragments;
//! - a shadow volume ([`ShadowVolume`]) is the object's silhouette edges
//!   seen from the light as quads (2 triangles each) plus its two caps (the
//!   triangles facing the light, and those moved away from the light past
//!   the scene's box): `2 x silhouette edges + 2 x lit faces` triangles,
//!   and its fragments in the camera's view (before the depth test, both
//!   faces: the stencil pass draws both);
//! - `none`, `sat-*`, `hib`: the volumes are one instanced draw through the
//!   extruding geometry shader, which reads every object's 606 triangles
//!   and outputs the volumes of the objects it keeps; the visibility tests
//!   read texels (`gpu_hiz_texel_ns`): one bin per object (`hib`), four per
//!   region-set lookup (`sat-*`);
//! - `sat-*`: the query pass (every object into the colour target), the
//!   region sets' CPU time as measured (`occlude_core::gvq::plan`), two
//!   prefix-sum dispatches over the pixels;
//! - `hib`: the item pass and one histogram dispatch over the pixels;
//! - `hardware`: the depth pass from the light, one query per object
//!   (`cpu_query_us`, `gpu_query_box_us`, its 606 triangles, its fragments
//!   at `gpu_query_fragment_ns`), and a draw call per object whose
//!   predicate passed (606 triangles in, the volume out); a failed
//!   predicate costs the CPU its draw call and the GPU nothing. No query
//!   latency: predicates are evaluated on the GPU.
//!
//! The camera image is `--resolution` (the paper renders 1600 x 1050); the
//! shadow volumes' fragments are counted by the soft rasterizer, exactly.

use crate::config::{BenchConfig, NEAR_PLANE};
use crate::error::Result;
use crate::progress::Progress;
use crate::published::PublishedTable;
use crate::runner::far_plane;
use crate::sim_gpu::SimFrame;
use glam::{Mat4, Vec3, Vec4};
use occlude_core::gvq::{RegionMode, RegionPlan, SatConfig};
use occlude_core::{Camera, ItemLayout, Mesh, Sampling, Scene};
use occlude_scenes::scattered::scattered;
use occlude_soft::raster::{Command, CommandKind, DepthBuffer, DepthTest, Rasterizer};
use occlude_soft::sat::SoftSat;
use occlude_soft::{GpuModel, SoftBackend};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt::Write;
use std::ops::Range;

/// Frames of Table 1 at most per object count, spread over the
/// walkthrough: each frame rasterizes every shadow volume and plans both
/// region modes in the light's view. On the loaded 2-vCPU development VM
/// `--paper gvq --frames 24` (Table 1 on 24 frames, Table 2 on 24) took
/// 355 s; the default run with 8 took 283 s (`docs/benchmarks.md`).
pub const FRAMES: usize = 8;

/// A way of deciding which shadow volumes to draw (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Every volume.
    None,
    /// Summed-area-table counts of region sets of this mode.
    Sat(RegionMode),
    /// Hierarchical item-buffer counts.
    Hib,
    /// One occlusion query (predicate) per object.
    Hardware,
}

/// Table 1's methods, in the order of its rows.
pub const METHODS: [Method; 5] = [
    Method::None,
    Method::Sat(RegionMode::Conservative),
    Method::Sat(RegionMode::Approximate),
    Method::Hib,
    Method::Hardware,
];

impl Method {
    /// The row's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Sat(RegionMode::Conservative) => "sat-conservative",
            Self::Sat(RegionMode::Approximate) => "sat-approximate",
            Self::Hib => "hib",
            Self::Hardware => "hardware",
        }
    }

    /// The paper's column as `published.toml` names it.
    fn published(self) -> &'static str {
        match self {
            Self::Sat(_) => "sat",
            other => other.name(),
        }
    }
}

/// One row of Table 1: per-frame means over the frames.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShadowRow {
    /// Objects in the scene.
    pub objects: u32,
    /// Culling method ([`METHODS`]).
    pub method: String,
    /// The backend that ran it: `soft` (simulated clock) or `wgpu`
    /// (measured on the device, [`crate::gvq_shadows_gpu`]).
    #[serde(default)]
    pub backend: String,
    /// Frame time, ms: the soft backend's simulated clock, or the wgpu
    /// backend's measured wall-clock time.
    pub frame_ms: f64,
    /// Objects per frame whose volume's decision differs from the soft
    /// backend's by the same method (0 on the soft backend).
    #[serde(default)]
    pub differing_from_soft: f64,
    /// Shadow volumes drawn.
    pub volumes: f64,
    /// Objects with a pixel in the light's view (what an exact test draws).
    pub lit: f64,
    /// Lit objects whose volume was culled (wrong shadows; only
    /// approximate region sets can).
    pub lit_culled: f64,
    /// Shadow-volume triangles drawn.
    pub volume_triangles: f64,
    /// Shadow-volume fragments drawn (camera view).
    pub volume_fragments: f64,
    /// The paper's frame time on the NVIDIA 280GTX (1000 / its fps), ms.
    pub published_frame_ms: Option<f64>,
    /// The paper's frames per second, NVIDIA 280GTX.
    pub published_fps_gtx280: Option<f64>,
    /// The paper's frames per second, ATI HD4870X2.
    pub published_fps_hd4870x2: Option<f64>,
    /// Frames averaged.
    pub frames: usize,
}

/// The point light at `t` (0 to 1 over the walkthrough): above the centre
/// of `scene`'s box by 0.9 of its diagonal and 0.3 of it aside, turning a
/// quarter turn about the vertical.
pub fn light_position(scene: &Scene, t: f32) -> Vec3 {
    let bounds = scene.bounds();
    let a = std::f32::consts::FRAC_PI_2 * t;
    bounds.center() + bounds.extent().length() * Vec3::new(0.3 * a.cos(), 0.9, 0.3 * a.sin())
}

/// The light's view from `light` of the sphere around `scene`'s box (every
/// object inside it), on an image of `aspect`.
pub fn light_camera(scene: &Scene, light: Vec3, aspect: f32) -> Camera {
    let bounds = scene.bounds();
    let (centre, radius) = (bounds.center(), 0.5 * bounds.extent().length());
    let distance = light.distance(centre);
    let half = (radius / distance).clamp(0.0, 1.0).asin();
    let half_y = if aspect < 1.0 { (half.tan() / aspect).atan() } else { half };
    Camera {
        position: light,
        target: centre,
        up: Vec3::Z,
        fov_y_deg: 2.0 * half_y.to_degrees(),
        aspect,
        near: (distance - radius).max(NEAR_PLANE),
        far: distance + radius,
        matrices: None,
    }
}

/// A mesh's edges, each with the triangles on it and its vertices in the
/// order of each (an edge of a closed mesh has two).
struct MeshEdges {
    /// Per edge, `(triangle, first, second)` for every triangle on it.
    edges: Vec<Vec<(u32, u32, u32)>>,
}

impl MeshEdges {
    fn new(mesh: &Mesh) -> Self {
        let mut at: HashMap<(u32, u32), usize> = HashMap::new();
        let mut edges: Vec<Vec<(u32, u32, u32)>> = Vec::new();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = *at.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    edges.push(Vec::new());
                    edges.len() - 1
                });
                edges[e].push((t as u32, a, b));
            }
        }
        Self { edges }
    }
}

/// One object's shadow volume from a point light, in world space.
pub struct ShadowVolume {
    /// Its triangles: the caps, then two per silhouette edge.
    pub triangles: Vec<[Vec3; 3]>,
    /// Triangles of the object facing the light.
    pub lit_faces: u32,
    /// Silhouette edges: an edge with a triangle facing the light and one
    /// facing away, or with only one triangle, facing the light.
    pub silhouette_edges: u32,
}

impl ShadowVolume {
    /// Instance `i`'s volume from `light`, its far cap `extrude` away from
    /// the light (`edges`: its mesh's).
    fn new(scene: &Scene, i: usize, edges: &MeshEdges, light: Vec3, extrude: f32) -> Self {
        let inst = &scene.instances[i];
        let mesh = &scene.meshes[inst.mesh as usize];
        let p: Vec<Vec3> = mesh.positions.iter().map(|&v| inst.transform.transform_point3(v)).collect();
        let far = |v: Vec3| v + (v - light).normalize_or_zero() * extrude;
        let tris: Vec<[u32; 3]> = mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let facing: Vec<bool> = tris
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
                (b - a).cross(c - a).dot(light - a) > 0.0
            })
            .collect();
        let mut triangles = Vec::new();
        for &[a, b, c] in tris.iter().zip(&facing).filter(|(_, &f)| f).map(|(t, _)| t) {
            let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
            triangles.push([a, b, c]);
            triangles.push([far(a), far(c), far(b)]);
        }
        let lit_faces = triangles.len() as u32 / 2;
        let mut silhouette_edges = 0;
        for on in &edges.edges {
            let lit = on.iter().find(|(t, _, _)| facing[*t as usize]);
            let dark = on.iter().any(|(t, _, _)| !facing[*t as usize]);
            if let Some(&(_, a, b)) = lit.filter(|_| dark || on.len() == 1) {
                let (a, b) = (p[a as usize], p[b as usize]);
                triangles.push([a, b, far(b)]);
                triangles.push([a, far(b), far(a)]);
                silhouette_edges += 1;
            }
        }
        Self { triangles, lit_faces, silhouette_edges }
    }
}

/// Clip-space triangles of world triangles.
fn clip(vp: &Mat4, tris: &[[Vec3; 3]], into: &mut Vec<[Vec4; 3]>) {
    into.extend(tris.iter().map(|t| t.map(|p| *vp * p.extend(1.0))));
}

/// Every object's triangles seen through `vp`, and each object's range.
fn object_triangles(scene: &Scene, vp: &Mat4) -> (Vec<[Vec4; 3]>, Vec<Range<u32>>) {
    let (mut triangles, mut scratch, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..scene.instances.len() {
        let start = triangles.len() as u32;
        scene.push_clip_triangles(i as u32, vp, &mut scratch, &mut triangles);
        ranges.push(start..triangles.len() as u32);
    }
    (triangles, ranges)
}

/// What one frame's passes found, from which every method's culling and
/// cost follow, and the clip-space triangles they drew (which the wgpu
/// backend's rows, [`crate::gvq_shadows_gpu`], draw again on the device).
pub(super) struct FramePasses {
    /// Pixels of the light's view.
    light_pixels: u64,
    /// Per object, its fragments in the light's view.
    light_fragments: Vec<u64>,
    /// Per object, its exact visible pixels from the light (the owner
    /// image, `SoftSat`).
    exact: Vec<u64>,
    /// Per region mode (conservative, approximate): per object its
    /// summed-area-table count, the lookups and the plan's CPU ms.
    sat: Vec<(Vec<u64>, u64, f64)>,
    /// Per region mode, the plan (region sets and colouring) counted.
    pub(super) plans: Vec<RegionPlan>,
    /// Per object, its count in the item buffer.
    hib: Vec<u64>,
    /// Per object, its occlusion query's count.
    hardware: Vec<u64>,
    /// Triangles per object.
    object_triangles: Vec<u64>,
    /// Fragments of every object in the camera's view.
    camera_fragments: u64,
    /// Per object, its shadow volume's triangles and camera-view fragments.
    volumes: Vec<(u64, u64)>,
    /// Every object's triangles in the light's clip space.
    pub(super) light_triangles: Vec<[Vec4; 3]>,
    /// Per object, its range of `light_triangles`.
    pub(super) light_ranges: Vec<Range<u32>>,
    /// In the camera's clip space, every object's triangles
    /// (`camera_objects`), then every object's shadow volume's.
    pub(super) camera_triangles: Vec<[Vec4; 3]>,
    /// The objects' range of `camera_triangles`.
    pub(super) camera_objects: Range<u32>,
    /// Per object, its volume's range of `camera_triangles`.
    pub(super) volume_ranges: Vec<Range<u32>>,
}

/// The per-scene state of Table 1's passes, reused frame after frame.
struct Passes<'s> {
    scene: &'s Scene,
    edges: Vec<MeshEdges>,
    sat: SoftSat,
    hib: SoftBackend,
    layout: ItemLayout,
    rasterizer: Rasterizer,
    light_depth: DepthBuffer,
    camera_depth: DepthBuffer,
    /// How far the far caps lie from their silhouettes.
    extrude: f32,
}

/// The region sets of the two SAT methods.
pub(super) fn sat_configs() -> [SatConfig; 2] {
    [RegionMode::Conservative, RegionMode::Approximate].map(|mode| SatConfig { mode, ..SatConfig::default() })
}

impl<'s> Passes<'s> {
    /// Passes over `scene` with a light view of `light_size` and a camera
    /// view of `camera_size` pixels.
    fn new(scene: &'s Scene, light_size: (u32, u32), camera_size: (u32, u32), model: &GpuModel) -> Self {
        let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
        Self {
            scene,
            edges: scene.meshes.iter().map(|m| MeshEdges::new(m)).collect(),
            sat: SoftSat::new(light_size.0, light_size.1),
            hib: SoftBackend::new(scene, light_size.0, light_size.1, model.clone()),
            layout: ItemLayout::new(scene, &all, 0).expect("one tile: one bin per object"),
            rasterizer: Rasterizer::new(),
            light_depth: DepthBuffer::new(light_size.0, light_size.1),
            camera_depth: DepthBuffer::new(camera_size.0, camera_size.1),
            extrude: scene.bounds().extent().length(),
        }
    }

    /// Every object's volume from `light`.
    fn volumes(&self, light: Vec3) -> Vec<ShadowVolume> {
        (0..self.scene.instances.len())
            .map(|i| {
                let edges = &self.edges[self.scene.instances[i].mesh as usize];
                ShadowVolume::new(self.scene, i, edges, light, self.extrude)
            })
            .collect()
    }

    /// One frame: the light's view from `light` (its camera `light_cam`)
    /// and `camera`'s view of the objects and their volumes.
    fn frame(&mut self, light: Vec3, light_cam: &Camera, camera: &Camera) -> FramePasses {
        let n = self.scene.instances.len();
        let frames = self.sat.query(self.scene, light_cam, &sat_configs());
        let exact = frames[0].exact.clone();
        let (sat, plans) = frames
            .into_iter()
            .map(|f| {
                let t = f.plan.timings;
                let cpu_ms = t.overlap_ms + t.colouring_ms + t.split_merge_ms;
                ((f.counts, u64::from(f.plan.lookups), cpu_ms), f.plan)
            })
            .unzip();

        let items = self.hib.item_buffer(light_cam, &self.layout);
        let mut hib = vec![0u64; n];
        for (slot, &instance) in self.layout.slots().iter().enumerate() {
            hib[instance as usize] = items.instances[slot];
        }

        let (light_triangles, light_ranges) = object_triangles(self.scene, &light_cam.view_projection());
        let draw = |r: &Range<u32>| Command { kind: CommandKind::Draw, triangles: r.clone(), cull_back: false };
        let query = |r: &Range<u32>| Command {
            kind: CommandKind::Query(DepthTest::Equal),
            triangles: r.clone(),
            cull_back: false,
        };
        let commands: Vec<Command> = light_ranges.iter().map(draw).chain(light_ranges.iter().map(query)).collect();
        self.light_depth.clear();
        let results = self.rasterizer.execute(&mut self.light_depth, &light_triangles, &commands);
        let light_fragments = results[..n].iter().map(|r| r.fragments).collect();
        let hardware = results[n..].iter().map(|r| r.passed).collect();
        let per_object = light_ranges.iter().map(|r| u64::from(r.end - r.start)).collect();

        let vp = camera.view_projection();
        let (mut triangles, _) = object_triangles(self.scene, &vp);
        let camera_objects = 0..triangles.len() as u32;
        let volumes = self.volumes(light);
        let mut commands =
            vec![Command { kind: CommandKind::Draw, triangles: camera_objects.clone(), cull_back: false }];
        for v in &volumes {
            let start = triangles.len() as u32;
            clip(&vp, &v.triangles, &mut triangles);
            commands.push(Command {
                kind: CommandKind::Query(DepthTest::Less),
                triangles: start..triangles.len() as u32,
                cull_back: false,
            });
        }
        self.camera_depth.clear();
        let results = self.rasterizer.execute(&mut self.camera_depth, &triangles, &commands);
        let volumes = volumes.iter().zip(&results[1..]).map(|(v, r)| (v.triangles.len() as u64, r.fragments)).collect();
        let volume_ranges = commands[1..].iter().map(|c| c.triangles.clone()).collect();
        FramePasses {
            light_pixels: u64::from(self.light_depth.width()) * u64::from(self.light_depth.height()),
            light_fragments,
            exact,
            sat,
            hib,
            hardware,
            object_triangles: per_object,
            camera_fragments: results[0].fragments,
            volumes,
            plans,
            light_triangles,
            light_ranges,
            camera_triangles: triangles,
            camera_objects,
            volume_ranges,
        }
    }
}

/// Per object, whether its count keeps its volume (a visible pixel).
pub(super) fn keep(counts: &[u64]) -> Vec<bool> {
    counts.iter().map(|&c| c > 0).collect()
}

impl Method {
    /// Per object of `p`, whether this method draws its volume on the soft
    /// backend.
    pub(super) fn drawn(self, p: &FramePasses) -> Vec<bool> {
        match self {
            Self::None => vec![true; p.volumes.len()],
            Self::Sat(mode) => keep(&p.sat[usize::from(mode == RegionMode::Approximate)].0),
            Self::Hib => keep(&p.hib),
            Self::Hardware => keep(&p.hardware),
        }
    }

    /// This method's frame of `p`: its simulated time, ms, and per object
    /// whether its volume is drawn (module documentation).
    fn frame(self, p: &FramePasses, model: &GpuModel) -> (f64, Vec<bool>) {
        let all_triangles: u64 = p.object_triangles.iter().sum();
        let light_fragments: u64 = p.light_fragments.iter().sum();
        let drawn = self.drawn(p);
        let mut f = SimFrame::new(model);
        f.draw(all_triangles, p.camera_fragments);
        match self {
            Self::Hardware => {
                f.draw(all_triangles, light_fragments);
                for (&t, &frags) in p.object_triangles.iter().zip(&p.light_fragments) {
                    f.cpu_work(model.cpu_query_us);
                    f.gpu(model.draw_us(model.gpu_query_box_us, t) + frags as f64 * model.gpu_query_fragment_ns * 1e-3);
                }
                for ((&d, &(t, frags)), &input) in drawn.iter().zip(&p.volumes).zip(&p.object_triangles) {
                    if d {
                        f.draw(input + t, frags);
                    } else {
                        f.cpu_work(model.cpu_draw_call_us);
                    }
                }
            }
            gs => {
                let reads = match gs {
                    Self::Sat(mode) => {
                        let (_, lookups, cpu_ms) = &p.sat[usize::from(mode == RegionMode::Approximate)];
                        f.cpu_work(cpu_ms * 1e3);
                        f.draw(all_triangles, light_fragments);
                        f.dispatch(p.light_pixels);
                        f.dispatch(p.light_pixels);
                        4 * lookups
                    }
                    Self::Hib => {
                        f.draw(all_triangles, light_fragments);
                        f.dispatch(p.light_pixels);
                        p.hib.len() as u64
                    }
                    _ => 0,
                };
                f.texel_reads(reads);
                let (t, frags) =
                    p.volumes.iter().zip(&drawn).filter(|(_, &d)| d).fold((0, 0), |(t, g), (v, _)| (t + v.0, g + v.1));
                f.draw(all_triangles + t, frags);
            }
        }
        f.draw(all_triangles, p.camera_fragments);
        (f.ms(), drawn)
    }
}

/// Sums of one method's frames.
#[derive(Default)]
struct Sums {
    frame_ms: f64,
    volumes: f64,
    lit: f64,
    lit_culled: f64,
    volume_triangles: f64,
    volume_fragments: f64,
    differing: f64,
}

/// One method's frame on a backend: its time, ms, per object whether its
/// volume is drawn, and how many of those decisions differ from the soft
/// backend's.
pub(super) struct MethodFrame {
    /// Frame time, ms.
    pub ms: f64,
    /// Per object, whether its volume is drawn.
    pub drawn: Vec<bool>,
    /// Objects whose decision differs from the soft backend's.
    pub differing: u32,
}

/// Table 1 over scenes of `counts` objects with `base`'s seed, frames (at
/// most [`FRAMES`]), resolution and GPU model, beside `published`, on the
/// soft backend's simulated clock.
pub fn table_1(
    base: &BenchConfig,
    counts: &[u32],
    published: Option<&PublishedTable>,
    progress: &dyn Progress,
) -> Vec<ShadowRow> {
    let mut rows = Vec::new();
    for &objects in counts {
        let scene = scattered(objects, base.seed);
        let soft = |_: &Camera, p: &FramePasses| -> Result<Vec<MethodFrame>> {
            Ok(METHODS
                .iter()
                .map(|m| {
                    let (ms, drawn) = m.frame(p, &base.gpu_model);
                    MethodFrame { ms, drawn, differing: 0 }
                })
                .collect())
        };
        rows.extend(scene_rows(base, &scene, "soft", published, progress, soft).expect("the soft rows cannot fail"));
    }
    rows
}

/// Table 1's rows of `scene` on `backend`: per frame (at most [`FRAMES`]
/// of `base`'s) the soft backend's passes ([`Passes`]), then `methods`,
/// given the light's camera and those passes, answers every method of
/// [`METHODS`] in order; rows of the means, beside `published`.
pub(super) fn scene_rows(
    base: &BenchConfig,
    scene: &Scene,
    backend: &str,
    published: Option<&PublishedTable>,
    progress: &dyn Progress,
    mut methods: impl FnMut(&Camera, &FramePasses) -> Result<Vec<MethodFrame>>,
) -> Result<Vec<ShadowRow>> {
    let (w, h) = base.resolution;
    let aspect = w as f32 / h as f32;
    let objects = scene.instances.len() as u32;
    let cameras =
        scene.path.sample_with(Sampling::Spread(base.frames.min(FRAMES)), aspect, NEAR_PLANE, far_plane(scene));
    progress.message(&format!("gvq: Table 1, {objects} objects"));
    progress.add_steps(cameras.len() as u64);
    let mut passes = Passes::new(scene, (w, h), (w, h), &base.gpu_model);
    let mut sums: Vec<Sums> = METHODS.iter().map(|_| Sums::default()).collect();
    for (k, camera) in cameras.iter().enumerate() {
        let light = light_position(scene, k as f32 / (cameras.len() - 1).max(1) as f32);
        let light_cam = light_camera(scene, light, aspect);
        let p = passes.frame(light, &light_cam, camera);
        let lit = keep(&p.exact);
        let lit_count = lit.iter().filter(|&&l| l).count() as f64;
        for (m, sum) in methods(&light_cam, &p)?.into_iter().zip(&mut sums) {
            sum.frame_ms += m.ms;
            sum.lit += lit_count;
            sum.differing += f64::from(m.differing);
            for ((&d, &l), &(t, frags)) in m.drawn.iter().zip(&lit).zip(&p.volumes) {
                if d {
                    sum.volumes += 1.0;
                    sum.volume_triangles += t as f64;
                    sum.volume_fragments += frags as f64;
                } else if l {
                    sum.lit_culled += 1.0;
                }
            }
        }
        progress.advance(1);
    }
    let frames = cameras.len().max(1) as f64;
    Ok(METHODS
        .iter()
        .zip(&sums)
        .map(|(method, s)| {
            let p = published
                .and_then(|t| t.rows.iter().find(|r| r.objects == Some(objects) && r.method == method.published()));
            ShadowRow {
                objects,
                method: method.name().to_string(),
                backend: backend.to_string(),
                frame_ms: s.frame_ms / frames,
                differing_from_soft: s.differing / frames,
                volumes: s.volumes / frames,
                lit: s.lit / frames,
                lit_culled: s.lit_culled / frames,
                volume_triangles: s.volume_triangles / frames,
                volume_fragments: s.volume_fragments / frames,
                published_frame_ms: p.and_then(|r| r.fps_gtx280).map(|fps| 1000.0 / fps),
                published_fps_gtx280: p.and_then(|r| r.fps_gtx280),
                published_fps_hd4870x2: p.and_then(|r| r.fps_hd4870x2),
                frames: cameras.len(),
            }
        })
        .collect())
}

/// Table 1's printed form, its frame times those of `clock` (which
/// backend, and how timed).
pub fn print(rows: &[ShadowRow], width: u32, height: u32, clock: &str) -> String {
    let frames = rows.first().map_or(0, |r| r.frames);
    let mut text = format!(
        "Granular visibility queries — Table 1: shadow-volume culling, per frame ({width}x{height} light and camera \
         views, {frames} frames, {clock}; paper's ms and fps on NVIDIA 280GTX / ATI HD4870X2 beside)\n\
         objects  method             frame ms  (paper ms)  volumes     lit  lit culled  volume tris  volume frags  \
         differ from soft  (paper fps)\n"
    );
    for r in rows {
        let paper_ms = r.published_frame_ms.map_or_else(|| "-".into(), |v| format!("{v:.2}"));
        let fps = match (r.published_fps_gtx280, r.published_fps_hd4870x2) {
            (Some(a), Some(b)) => format!("{a} / {b}"),
            _ => "-".into(),
        };
        let _ = writeln!(
            text,
            "{:>7}  {:<17} {:>9.3} {:>11} {:>8.1} {:>7.1} {:>11.1} {:>12.0} {:>13.0} {:>17.1}  {}",
            r.objects,
            r.method,
            r.frame_ms,
            paper_ms,
            r.volumes,
            r.lit,
            r.lit_culled,
            r.volume_triangles,
            r.volume_fragments,
            r.differing_from_soft,
            fps
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::published;
    use glam::DVec3;
    use occlude_core::Aabb;

    /// The distance along `dir` from `origin` at which the ray meets `tri`
    /// (Möller-Trumbore, in f64), if it does at a positive distance.
    fn ray_triangle(origin: DVec3, dir: DVec3, tri: &[Vec3; 3]) -> Option<f64> {
        let [a, b, c] = tri.map(|p| p.as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let q = dir.cross(e2);
        let det = e1.dot(q);
        if det.abs() < 1e-12 {
            return None;
        }
        let s = (origin - a) / det;
        let u = s.dot(q);
        let r = s.cross(e1);
        let v = dir.dot(r);
        let t = e2.dot(r);
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
    }

    /// Whether the ray meets `b` before `limit`.
    fn ray_box(origin: DVec3, dir: DVec3, b: &Aabb, limit: f64) -> bool {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (mut t0, mut t1) = (0.0f64, limit);
        for k in 0..3 {
            let (a, c) = ((lo[k] - origin[k]) / dir[k], (hi[k] - origin[k]) / dir[k]);
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
        t0 <= t1
    }

    /// Every object's world triangles.
    fn world_triangles(scene: &Scene) -> Vec<Vec<[Vec3; 3]>> {
        scene
            .instances
            .iter()
            .map(|inst| {
                let m = &scene.meshes[inst.mesh as usize];
                m.indices
                    .chunks_exact(3)
                    .map(|t| [0, 1, 2].map(|k| inst.transform.transform_point3(m.positions[t[k] as usize])))
                    .collect()
            })
            .collect()
    }

    /// The nearest object and distance the ray meets before `limit`, of the
    /// objects `among` keeps.
    fn nearest(
        scene: &Scene,
        tris: &[Vec<[Vec3; 3]>],
        origin: DVec3,
        dir: DVec3,
        limit: f64,
        among: impl Fn(usize) -> bool,
    ) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, inst) in scene.instances.iter().enumerate() {
            if !among(i) || !ray_box(origin, dir, &inst.bounds.expanded(0.0, 1e-3), limit) {
                continue;
            }
            for t in tris[i].iter().filter_map(|tri| ray_triangle(origin, dir, tri)) {
                if t < limit && best.is_none_or(|(_, b)| t < b) {
                    best = Some((i, t));
                }
            }
        }
        best
    }

    /// Per camera pixel (row-major): `None` where it sees no object, else
    /// whether its point is in the shadow of an object `casts` keeps, by
    /// ray casting (the point moved a millimetre towards the light).
    fn shadow_mask(
        scene: &Scene,
        tris: &[Vec<[Vec3; 3]>],
        camera: &Camera,
        (w, h): (u32, u32),
        light: Vec3,
        casts: impl Fn(usize) -> bool,
    ) -> Vec<Option<bool>> {
        let inverse = camera.view_projection().inverse();
        let origin = camera.position.as_dvec3();
        let light = light.as_dvec3();
        (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                let ndc =
                    Vec3::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0, 1.0);
                let dir = (inverse.project_point3(ndc).as_dvec3() - origin).normalize();
                let (_, t) = nearest(scene, tris, origin, dir, f64::INFINITY, |_| true)?;
                let to_light = light - (origin + dir * t);
                let start = origin + dir * t + to_light.normalize() * 1e-3;
                let span = (light - start).length();
                Some(nearest(scene, tris, start, (light - start) / span, span, &casts).is_some())
            })
            .collect()
    }

    /// The small case: 200 objects, light and camera views of 128 and 40
    /// pixels a side, two frames of the walkthrough.
    fn small_frames(scene: &Scene) -> Vec<(Vec3, Camera, FramePasses)> {
        let model = GpuModel::modern();
        let mut passes = Passes::new(scene, (128, 128), (40, 40), &model);
        let cameras = scene.path.sample_with(Sampling::Spread(2), 1.0, NEAR_PLANE, far_plane(scene));
        cameras
            .into_iter()
            .enumerate()
            .map(|(k, camera)| {
                let light = light_position(scene, k as f32);
                let p = passes.frame(light, &light_camera(scene, light, 1.0), &camera);
                (light, camera, p)
            })
            .collect()
    }

    #[test]
    fn exact_methods_cull_the_same_volumes_and_sat_errs_only_its_way() {
        let scene = scattered(200, 1);
        let model = GpuModel::modern();
        for (_, _, p) in small_frames(&scene) {
            let hidden: Vec<bool> = p.exact.iter().map(|&c| c == 0).collect();
            assert!(hidden.iter().any(|&h| h), "no object hidden from the light: nothing to cull");
            let culled = |m: Method| {
                let drawn = m.frame(&p, &model).1;
                assert_eq!(drawn, m.drawn(&p), "{m:?}: the frame's decisions are the method's");
                drawn.iter().map(|&d| !d).collect::<Vec<bool>>()
            };
            assert!(culled(Method::None).iter().all(|&c| !c), "none culled a volume");
            assert_eq!(culled(Method::Hib), hidden, "item buffer");
            assert_eq!(culled(Method::Hardware), hidden, "occlusion queries");
            let (cons, approx) =
                (culled(Method::Sat(RegionMode::Conservative)), culled(Method::Sat(RegionMode::Approximate)));
            for i in 0..hidden.len() {
                assert!(!cons[i] || hidden[i], "conservative region sets culled lit object {i}");
                assert!(approx[i] || !hidden[i], "approximate region sets drew hidden object {i}");
            }
            assert!(cons.iter().any(|&c| c), "conservative region sets culled nothing");
        }
    }

    #[test]
    fn culled_volumes_change_no_shadow() {
        let scene = scattered(200, 1);
        let tris = world_triangles(&scene);
        let (mut culled_shadows, mut shadowed) = (0, 0);
        for (light, camera, p) in small_frames(&scene) {
            let drawn = Method::Hib.frame(&p, &GpuModel::modern()).1;
            let all = shadow_mask(&scene, &tris, &camera, (40, 40), light, |_| true);
            let kept = shadow_mask(&scene, &tris, &camera, (40, 40), light, |i| drawn[i]);
            let only_culled = shadow_mask(&scene, &tris, &camera, (40, 40), light, |i| !drawn[i]);
            let differing = all.iter().zip(&kept).filter(|(a, k)| a != k).count();
            assert_eq!(differing, 0, "pixels whose shadow changes without the culled volumes");
            // The check sees a wrong culling: half the kept volumes dropped
            // changes shadows.
            let halved = shadow_mask(&scene, &tris, &camera, (40, 40), light, |i| drawn[i] && i % 2 == 0);
            assert!(all.iter().zip(&halved).any(|(a, h)| a != h), "dropping lit objects' volumes changed nothing");
            culled_shadows += only_culled.iter().filter(|s| **s == Some(true)).count();
            shadowed += all.iter().filter(|s| **s == Some(true)).count();
        }
        assert!(shadowed > 0 && culled_shadows > 0, "no culled object shadows a visible pixel: {culled_shadows}");
    }

    #[test]
    fn a_volume_has_two_caps_and_a_quad_per_silhouette_edge() {
        let scene = scattered(3, 1);
        let light = light_position(&scene, 0.0);
        let edges = MeshEdges::new(&scene.meshes[0]);
        assert!(edges.edges.iter().all(|e| e.len() == 2), "the torus is closed");
        for i in 0..3 {
            let v = ShadowVolume::new(&scene, i, &edges, light, 100.0);
            assert!(v.lit_faces > 0 && v.lit_faces < 606 && v.silhouette_edges >= 3, "{i}");
            assert_eq!(v.triangles.len() as u32, 2 * v.lit_faces + 2 * v.silhouette_edges);
            // A closed mesh's silhouette is closed loops: every vertex on
            // it has an even number of silhouette edges.
            let mut ends: HashMap<[u32; 3], u32> = HashMap::new();
            for t in &v.triangles[2 * v.lit_faces as usize..].iter().step_by(2).collect::<Vec<_>>() {
                for p in [t[0], t[1]] {
                    *ends.entry(p.to_array().map(f32::to_bits)).or_default() += 1;
                }
            }
            assert!(ends.values().all(|&n| n % 2 == 0), "{i}: open silhouette");
        }
    }

    #[test]
    fn table_1_has_every_method_beside_the_papers_figures() {
        let base = BenchConfig { frames: 2, resolution: (48, 48), ..BenchConfig::default() };
        let rows = table_1(&base, &[100, 500], published::table("gvq", "Table 1"), &());
        assert_eq!(rows.len(), 2 * METHODS.len());
        let find = |n: u32, m: &str| rows.iter().find(|r| r.objects == n && r.method == m).unwrap();
        assert_eq!(
            (find(100, "none").published_fps_gtx280, find(100, "none").published_fps_hd4870x2),
            (Some(53.0), Some(100.0))
        );
        assert_eq!(find(500, "hib").published_fps_gtx280, Some(31.0));
        assert_eq!(find(500, "sat-approximate").published_fps_hd4870x2, Some(29.0));
        assert_eq!(find(100, "hardware").published_frame_ms, Some(1000.0 / 217.0));
        for r in &rows {
            assert!(r.frame_ms.is_finite() && r.frame_ms > 0.0 && r.frames == 2, "{r:?}");
            assert!(r.volumes >= r.lit - r.lit_culled - 1e-9, "{r:?}: a lit volume missing");
        }
        for n in [100, 500] {
            assert_eq!(find(n, "none").volumes, f64::from(n), "none draws every volume");
            assert_eq!(find(n, "none").lit_culled, 0.0);
        }
        assert!(find(500, "hib").volumes < 500.0, "the item buffer culled nothing of 500 objects");
        let json = serde_json::to_value(&rows[0]).unwrap();
        for key in ["objects", "method", "frame_ms", "published_frame_ms"] {
            assert!(json.get(key).is_some(), "{key}");
        }
        assert!(rows.iter().all(|r| r.backend == "soft" && r.differing_from_soft == 0.0));
        assert!(print(&rows, 48, 48, "soft backend").contains("Table 1"));
    }
}
