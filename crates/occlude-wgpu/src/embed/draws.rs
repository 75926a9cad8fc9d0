//! How a [`GpuCuller`](super::GpuCuller)'s renderer draws its visible
//! lists: per instance a mesh and a draw group ([`Draws`]), and per list
//! one indirect command per (group, mesh) pair, written on the GPU
//! (`draws.wgsl`). A group is drawn with one multi-draw, whatever the
//! number of meshes; the culling passes do not grow with it either.

use super::passes::ComputePass;
use super::EmbedError;
use crate::context::GpuContext;
use crate::culling::{bind_group, storage_init};
use crate::pipelines::compute_pipeline;
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// The device features [`GpuCuller`](super::GpuCuller)'s draws use where
/// the device has them: `INDIRECT_FIRST_INSTANCE`, which several meshes or
/// draw groups need ([`Draws::Meshes`]), and `MULTI_DRAW_INDIRECT_COUNT`,
/// with which a group's multi-draw skips its meshes without visible
/// instances on the GPU (without it, their commands draw no instance).
pub const DRAW_FEATURES: wgpu::Features =
    wgpu::Features::INDIRECT_FIRST_INSTANCE.union(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT);

/// How the renderer draws one mesh: an indirect draw whose instance count
/// occlude fills in with the number of that mesh's visible instances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IndirectDraw {
    /// `draw_indexed_indirect` of this mesh range
    /// (`DrawIndexedIndirectArgs`).
    Indexed {
        /// Indices per instance.
        index_count: u32,
        /// First index in the renderer's index buffer.
        first_index: u32,
        /// Added to each index.
        base_vertex: i32,
    },
    /// `draw_indirect` of this vertex range (`DrawIndirectArgs`).
    NonIndexed {
        /// Vertices per instance.
        vertex_count: u32,
        /// First vertex.
        first_vertex: u32,
    },
}

impl IndirectDraw {
    /// The command's words: instance count 0, first instance `first`.
    fn words(self, first: u32) -> Vec<u32> {
        match self {
            Self::Indexed { index_count, first_index, base_vertex } => {
                vec![index_count, 0, first_index, base_vertex as u32, first]
            }
            Self::NonIndexed { vertex_count, first_vertex } => vec![vertex_count, 0, first_vertex, first],
        }
    }
}

/// The mesh and the draw group of one instance ([`Draws::Meshes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceDraw {
    /// Index into [`Draws::Meshes`]' meshes.
    pub mesh: u32,
    /// The renderer's bucket of instances drawn together: a pipeline or a
    /// material. Groups are numbered from 0; [`VisibleList::draw_group`]
    /// draws one.
    pub group: u32,
}

/// What each instance draws.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Draws {
    /// Every instance draws this mesh, in group 0.
    One(IndirectDraw),
    /// Instance `i` draws `meshes[instances[i].mesh]` in group
    /// `instances[i].group`. The meshes are all indexed or all not. With
    /// more than one (group, mesh) pair the device needs
    /// `INDIRECT_FIRST_INSTANCE`: each pair's command starts at its own
    /// place in the list.
    Meshes {
        /// The scene's meshes.
        meshes: Vec<IndirectDraw>,
        /// One per instance, in the order of the boxes.
        instances: Vec<InstanceDraw>,
    },
}

impl From<IndirectDraw> for Draws {
    fn from(draw: IndirectDraw) -> Self {
        Draws::One(draw)
    }
}

/// The buckets of [`Draws`]: one per (group, mesh) pair that some
/// instance has, in the order of groups, then meshes.
struct Buckets {
    /// Each instance's bucket.
    of_instance: Vec<u32>,
    /// Each bucket's command, instance count 0, first instance the
    /// bucket's first slot in the sorted list.
    commands: Vec<u32>,
    /// Each bucket's group.
    group: Vec<u32>,
    /// Per group: its first bucket and its number of buckets.
    groups: Vec<(u32, u32)>,
    /// Words per command.
    stride: u32,
}

impl Buckets {
    /// The buckets of `n` instances drawn as `draws` says; draws that do
    /// not fit the instances are an [`EmbedError::Draws`].
    fn new(draws: &Draws, n: usize) -> Result<Self, EmbedError> {
        let (meshes, keys): (&[IndirectDraw], Vec<(u32, u32)>) = match draws {
            Draws::One(draw) => (std::slice::from_ref(draw), vec![(0, 0); n]),
            Draws::Meshes { meshes, instances } => {
                if instances.len() != n {
                    return Err(EmbedError::Draws(format!("{} instance draws for {n} boxes", instances.len())));
                }
                if let Some((i, d)) = instances.iter().enumerate().find(|(_, d)| d.mesh as usize >= meshes.len()) {
                    return Err(EmbedError::Draws(format!(
                        "instance {i} draws mesh {}, but there are {} meshes",
                        d.mesh,
                        meshes.len()
                    )));
                }
                (meshes, instances.iter().map(|d| (d.group, d.mesh)).collect())
            }
        };
        let indexed = matches!(meshes.first(), Some(IndirectDraw::Indexed { .. }));
        if meshes.iter().any(|m| matches!(m, IndirectDraw::Indexed { .. }) != indexed) {
            return Err(EmbedError::Draws("the meshes mix indexed and non-indexed draws".into()));
        }
        let mut sizes = BTreeMap::new();
        keys.iter().for_each(|&key| *sizes.entry(key).or_insert(0u32) += 1);
        let bucket_of: BTreeMap<(u32, u32), u32> = sizes.keys().zip(0..).map(|(&key, b)| (key, b)).collect();
        let group_count = sizes.keys().map(|&(g, _)| g + 1).max().unwrap_or(1);
        let mut groups = vec![(0, 0); group_count as usize];
        let (mut commands, mut group, mut first) = (Vec::new(), Vec::new(), 0);
        for (&(g, mesh), &size) in &sizes {
            let entry = &mut groups[g as usize];
            if entry.1 == 0 {
                entry.0 = group.len() as u32;
            }
            entry.1 += 1;
            commands.extend(meshes[mesh as usize].words(first));
            group.push(g);
            first += size;
        }
        Ok(Self {
            of_instance: keys.iter().map(|key| bucket_of[key]).collect(),
            commands,
            group,
            groups,
            stride: if indexed { 5 } else { 4 },
        })
    }

    fn count(&self) -> u32 {
        self.group.len() as u32
    }
}

/// The buffers and pipelines shared by both lists' commands, made once.
pub(super) struct DrawTables {
    sort: wgpu::ComputePipeline,
    pack: wgpu::ComputePipeline,
    layout: wgpu::Buffer,
    of_instance: wgpu::Buffer,
    bucket_group: wgpu::Buffer,
    group_first: wgpu::Buffer,
    /// The commands as each frame starts (`COPY_SRC`).
    template: wgpu::Buffer,
    groups: Arc<[(u32, u32)]>,
    stride: u32,
    buckets: u32,
    /// Whether the device has `MULTI_DRAW_INDIRECT_COUNT`: groups are
    /// drawn from their packed commands and counts; otherwise from every
    /// bucket's command, empty ones included.
    count_draws: bool,
}

impl DrawTables {
    /// The tables for `n` instances drawn as `draws` says. Draws that do
    /// not fit, or several buckets on a device without
    /// `INDIRECT_FIRST_INSTANCE`, are an error.
    pub(super) fn new(ctx: &GpuContext, draws: &Draws, n: u32) -> Result<Self, EmbedError> {
        let buckets = Buckets::new(draws, n as usize)?;
        let features = ctx.device.features();
        if buckets.count() > 1 && !features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE) {
            return Err(EmbedError::Adapter(
                "the device lacks the feature INDIRECT_FIRST_INSTANCE, which drawing several meshes or groups from \
                 one culler needs (each mesh's command starts at its own place in the list; request it when \
                 creating the device)"
                    .into(),
            ));
        }
        let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("occlude draw commands"),
            source: wgpu::ShaderSource::Wgsl(include_str!("draws.wgsl").into()),
        });
        let group_first: Vec<u32> = buckets.groups.iter().map(|&(first, _)| first).collect();
        let words =
            |label, data: &[u32]| storage_init(ctx, label, bytemuck::cast_slice(data), wgpu::BufferUsages::empty());
        Ok(Self {
            sort: compute_pipeline(&ctx.device, &module, "cs_sort_list"),
            pack: compute_pipeline(&ctx.device, &module, "cs_pack_commands"),
            layout: ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("draw command layout"),
                contents: bytemuck::cast_slice(&[buckets.stride, buckets.count(), 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            of_instance: words("instance buckets", &buckets.of_instance),
            bucket_group: words("bucket groups", &buckets.group),
            group_first: words("group starts", &group_first),
            template: ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("draw command template"),
                contents: bytemuck::cast_slice(&buckets.commands),
                usage: wgpu::BufferUsages::COPY_SRC,
            }),
            buckets: buckets.count(),
            stride: buckets.stride,
            groups: buckets.groups.into(),
            count_draws: features.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
        })
    }

    /// The renderer's list number `index`, sorted from `compacted` (a list
    /// of `cull.wgsl`'s compaction, of capacity `n`).
    pub(super) fn list(&self, ctx: &GpuContext, compacted: &wgpu::Buffer, n: u32, index: usize) -> VisibleList {
        let usage = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST;
        let commands_bytes = 4 * (self.stride * self.buckets) as usize;
        let commands = storage_init(ctx, "visible draws", &vec![0; commands_bytes], usage);
        let packed = storage_init(ctx, "visible draws packed", &vec![0; commands_bytes], usage);
        let group_counts = storage_init(ctx, "visible draw counts", &vec![0; 4 * self.groups.len()], usage);
        let mut header = vec![0, n];
        header.resize(2 + n as usize, 0);
        let sorted = storage_init(ctx, "visible instances", bytemuck::cast_slice(&header), wgpu::BufferUsages::empty());
        let sort = bind_group(
            ctx,
            "visible list sort",
            &self.sort.get_bind_group_layout(0),
            &[(0, compacted), (1, &self.of_instance), (2, &commands), (3, &sorted), (4, &self.layout)],
        );
        let pack = bind_group(
            ctx,
            "visible draws pack",
            &self.pack.get_bind_group_layout(0),
            &[
                (2, &commands),
                (4, &self.layout),
                (5, &self.bucket_group),
                (6, &group_counts),
                (7, &self.group_first),
                (8, &packed),
            ],
        );
        VisibleList {
            ids: sorted,
            commands,
            packed,
            group_counts,
            groups: self.groups.clone(),
            stride: self.stride,
            buckets: self.buckets,
            count_draws: self.count_draws,
            passes: [sort, pack],
            group: None,
            index,
        }
    }

    /// Records the start of a frame's commands for `list`: every bucket
    /// empty, no command packed.
    pub(super) fn reset(&self, encoder: &mut wgpu::CommandEncoder, list: &VisibleList) {
        encoder.copy_buffer_to_buffer(&self.template, 0, &list.commands, 0, self.template.size());
        encoder.clear_buffer(&list.group_counts, 0, None);
    }

    /// Records `list`'s commands into `pass`, after its compaction: the
    /// list's `n` possible entries sorted into buckets, then (with counts)
    /// the non-empty buckets packed.
    pub(super) fn dispatch(&self, pass: &mut ComputePass<'_>, list: &VisibleList, n: u32) {
        let [sort, pack] = &list.passes;
        pass.dispatch(&self.sort, sort, n);
        if self.count_draws {
            pass.dispatch(&self.pack, pack, self.buckets);
        }
    }
}

/// One of the frame's two lists of visible instances, kept for the
/// culler's life (the buffers never change, so bind groups over them can be
/// made once).
///
/// `ids` holds the instances, bucket by bucket (a bucket per draw group and
/// mesh), which the renderer's vertex shader binds as a read-only storage
/// buffer:
///
/// ```wgsl
/// struct VisibleList { count: u32, capacity: u32, ids: array<u32> }
/// @group(1) @binding(0) var<storage, read> visible: VisibleList;
/// // in the vertex shader: let instance = visible.ids[instance_index];
/// ```
///
/// `indirect` holds one command per bucket, its instance count the
/// bucket's visible instances and its first instance the bucket's place in
/// `ids`. [`VisibleList::draw`] draws every bucket,
/// [`VisibleList::draw_group`] one group's.
///
/// The renderer binds `ids` itself, in a bind group of its own, or has
/// occlude make each list's bind group for its pipeline with
/// [`GpuCuller::with_list_pipeline`](super::GpuCuller::with_list_pipeline),
/// which [`VisibleList::draw`] then sets before drawing.
pub struct VisibleList {
    ids: wgpu::Buffer,
    commands: wgpu::Buffer,
    /// Per group, its non-empty buckets' commands, counted in
    /// `group_counts` (with `MULTI_DRAW_INDIRECT_COUNT`).
    packed: wgpu::Buffer,
    group_counts: wgpu::Buffer,
    /// Per group: its first bucket and its number of buckets.
    groups: Arc<[(u32, u32)]>,
    /// Words per command: 5 for indexed draws, 4 for others.
    stride: u32,
    buckets: u32,
    count_draws: bool,
    /// The sort's and the pack's bind groups.
    passes: [wgpu::BindGroup; 2],
    /// The renderer's group index and the bind group holding the list
    /// there.
    pub(super) group: Option<(u32, wgpu::BindGroup)>,
    index: usize,
}

impl VisibleList {
    /// The list: count, capacity, then the ids (`STORAGE` usage).
    pub fn ids(&self) -> &wgpu::Buffer {
        &self.ids
    }

    /// The list's draw commands, one per bucket (`INDIRECT` usage).
    pub fn indirect(&self) -> &wgpu::Buffer {
        &self.commands
    }

    /// 0 for the early pass's list (last frame's visible instances still
    /// in view), 1 for the late pass's (the instances found visible now
    /// that the early pass did not draw); also its place in
    /// [`GpuCuller::lists`](super::GpuCuller::lists).
    pub fn index(&self) -> usize {
        self.index
    }

    /// The number of draw groups ([`InstanceDraw::group`]; 1 for
    /// [`Draws::One`]).
    pub fn group_count(&self) -> u32 {
        self.groups.len() as u32
    }

    /// Records the whole list's draws in `pass`, every group alike: its
    /// bind group set at the renderer's group index, when
    /// [`GpuCuller::with_list_pipeline`](super::GpuCuller::with_list_pipeline)
    /// made one, then one multi-draw of every bucket's command (a bucket
    /// without visible instances draws nothing). The renderer's pipeline,
    /// its other bind groups and its vertex and index buffers must be set
    /// before.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.set_group(pass);
        self.multi_draw(pass, 0, self.buckets);
    }

    /// Records the draws of group `group`'s instances in `pass`, as
    /// [`VisibleList::draw`] does for all: with `MULTI_DRAW_INDIRECT_COUNT`
    /// one multi-draw of the group's non-empty buckets, counted on the GPU;
    /// without it one multi-draw of all the group's buckets. Set the
    /// group's pipeline first. A group no instance has draws nothing.
    pub fn draw_group(&self, pass: &mut wgpu::RenderPass<'_>, group: u32) {
        let Some(&(first, buckets)) = self.groups.get(group as usize) else { return };
        if buckets == 0 {
            return;
        }
        self.set_group(pass);
        if !self.count_draws {
            return self.multi_draw(pass, first, buckets);
        }
        let offset = self.offset(first);
        let count_offset = 4 * u64::from(group);
        if self.indexed() {
            pass.multi_draw_indexed_indirect_count(&self.packed, offset, &self.group_counts, count_offset, buckets);
        } else {
            pass.multi_draw_indirect_count(&self.packed, offset, &self.group_counts, count_offset, buckets);
        }
    }

    fn set_group(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some((index, group)) = &self.group {
            pass.set_bind_group(*index, group, &[]);
        }
    }

    /// One multi-draw of `count` bucket commands from bucket `first`.
    fn multi_draw(&self, pass: &mut wgpu::RenderPass<'_>, first: u32, count: u32) {
        let offset = self.offset(first);
        match (self.indexed(), count) {
            (true, 1) => pass.draw_indexed_indirect(&self.commands, offset),
            (false, 1) => pass.draw_indirect(&self.commands, offset),
            (true, _) => pass.multi_draw_indexed_indirect(&self.commands, offset, count),
            (false, _) => pass.multi_draw_indirect(&self.commands, offset, count),
        }
    }

    /// Whether the commands are `DrawIndexedIndirectArgs`.
    fn indexed(&self) -> bool {
        self.stride == 5
    }

    /// The byte offset of bucket `bucket`'s command.
    fn offset(&self, bucket: u32) -> u64 {
        4 * u64::from(bucket * self.stride)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(first_index: u32) -> IndirectDraw {
        IndirectDraw::Indexed { index_count: 3, first_index, base_vertex: 0 }
    }

    #[test]
    fn buckets_follow_groups_then_meshes_and_place_each_in_the_list() {
        let instances =
            [(1, 0), (0, 1), (1, 0), (0, 0), (2, 1)].map(|(mesh, group)| InstanceDraw { mesh, group }).to_vec();
        let draws = Draws::Meshes { meshes: vec![mesh(0), mesh(3), mesh(6)], instances };
        let b = Buckets::new(&draws, 5).unwrap();
        // Buckets: (group 0, mesh 0) 1 instance, (0, 1) 2, (1, 0) 1, (1, 2) 1.
        assert_eq!(b.of_instance, vec![1, 2, 1, 0, 3]);
        assert_eq!(b.group, vec![0, 0, 1, 1]);
        assert_eq!(b.groups, vec![(0, 2), (2, 2)]);
        let firsts: Vec<u32> = b.commands.chunks(5).map(|c| c[4]).collect();
        assert_eq!(firsts, vec![0, 1, 3, 4]);
        let first_indices: Vec<u32> = b.commands.chunks(5).map(|c| c[2]).collect();
        assert_eq!(first_indices, vec![0, 3, 0, 6]);
    }

    #[test]
    fn draws_that_do_not_fit_the_instances_are_refused() {
        let one = |mesh| vec![InstanceDraw { mesh, group: 0 }];
        let too_few = Draws::Meshes { meshes: vec![mesh(0)], instances: one(0) };
        assert!(matches!(Buckets::new(&too_few, 2), Err(EmbedError::Draws(_))));
        let unknown = Draws::Meshes { meshes: vec![mesh(0)], instances: one(1) };
        assert!(matches!(Buckets::new(&unknown, 1), Err(EmbedError::Draws(_))));
        let mixed = Draws::Meshes {
            meshes: vec![mesh(0), IndirectDraw::NonIndexed { vertex_count: 3, first_vertex: 0 }],
            instances: one(0),
        };
        assert!(matches!(Buckets::new(&mixed, 1), Err(EmbedError::Draws(_))));
    }

    #[test]
    fn one_mesh_is_one_bucket_starting_the_list() {
        let b = Buckets::new(&Draws::One(mesh(9)), 4).unwrap();
        assert_eq!((b.count(), b.of_instance, b.commands), (1, vec![0; 4], vec![3, 0, 9, 0, 0]));
    }
}
