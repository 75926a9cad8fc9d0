//! The scene model: indexed triangle meshes shared by instances.
//!
//! Meshes never change once added; instances move, hide and show again
//! ([`Scene::apply`], module [`crate::motion`]). Meshes are shared behind
//! an [`Arc`], so that a backend keeping its own copy of the instances (as
//! a GPU keeps its own copy of the transforms) clones a scene cheaply.

use crate::geometry::Aabb;
use crate::path::CameraPath;
use crate::query_box::BOX_TRIANGLES;
use glam::{Mat4, Vec3, Vec4};
use std::sync::Arc;
use thiserror::Error;

/// An indexed triangle mesh in its own (object) space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Three indices per triangle, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Box of `positions`.
    pub bounds: Aabb,
}

impl Mesh {
    /// A mesh with its bounds computed.
    pub fn new(positions: Vec<Vec3>, indices: Vec<u32>) -> Self {
        let bounds = Aabb::from_points(&positions);
        Self { positions, indices, bounds }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// One placed copy of a mesh: the unit the methods draw (one draw call each).
#[derive(Clone, Debug)]
pub struct Instance {
    /// Index into [`Scene::meshes`].
    pub mesh: u32,
    /// Object-to-world transform.
    pub transform: Mat4,
    /// Material id; drawing a different material than the previous draw is a
    /// state change.
    pub material: u32,
    /// World-space box of the transformed mesh (hidden or not).
    pub bounds: Aabb,
    /// Whether the instance is part of the scene now: a hidden instance
    /// ([`crate::motion::InstanceChange::Hide`]) is drawn by no backend,
    /// counted in no statistic and lies in no node box.
    pub enabled: bool,
}

impl Instance {
    /// The box culling sees: [`Instance::bounds`], or the empty box while
    /// the instance is hidden.
    pub fn culling_bounds(&self) -> Aabb {
        if self.enabled {
            self.bounds
        } else {
            Aabb::EMPTY
        }
    }
}

/// Errors found by [`Scene::validate`].
#[derive(Debug, Error, PartialEq)]
pub enum SceneError {
    /// The scene has no instance or no triangle.
    #[error("scene '{0}' is empty: it has no triangles to render")]
    Empty(String),
    /// A mesh has a position that is NaN or infinite.
    #[error("mesh {mesh} has a non-finite vertex position at index {vertex}")]
    NonFiniteVertex {
        /// Mesh index.
        mesh: usize,
        /// Vertex index.
        vertex: usize,
    },
    /// A mesh index points past its vertices.
    #[error("mesh {mesh} has index {index} but only {vertices} vertices")]
    IndexOutOfRange {
        /// Mesh index.
        mesh: usize,
        /// The bad index.
        index: u32,
        /// Vertices the mesh has.
        vertices: usize,
    },
    /// A mesh's index count is not a multiple of three.
    #[error("mesh {mesh} has {count} indices, not a multiple of 3")]
    PartialTriangle {
        /// Mesh index.
        mesh: usize,
        /// Its index count.
        count: usize,
    },
    /// An instance refers to a mesh that does not exist.
    #[error("instance {instance} refers to mesh {mesh}, but the scene has {meshes} meshes")]
    MissingMesh {
        /// Instance index.
        instance: usize,
        /// The mesh it names.
        mesh: u32,
        /// Meshes the scene has.
        meshes: usize,
    },
    /// An instance transform is not finite.
    #[error("instance {0} has a non-finite transform")]
    NonFiniteTransform(usize),
    /// [`Scene::view_distance`] is not a finite positive distance.
    #[error("the view distance {0} is not a finite positive distance")]
    ViewDistance(f32),
    /// A box given to [`Scene::from_bounds`] is not finite or has a
    /// minimum above its maximum.
    #[error("instance {0}'s bounds are not a finite box with min <= max")]
    BadBounds(usize),
    /// [`Scene::with_triangle_counts`] got a count list whose length is not
    /// the number of instances.
    #[error("{given} triangle counts for {instances} instances")]
    TriangleCounts {
        /// Counts given.
        given: usize,
        /// Instances in the scene.
        instances: usize,
    },
}

/// A complete scene: meshes, their instances and a default walkthrough.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Short name (`city`, a file name, ...).
    pub name: String,
    /// Shared geometry, fixed once added ([`Scene::add_mesh`]).
    pub meshes: Vec<Arc<Mesh>>,
    /// Placed objects.
    pub instances: Vec<Instance>,
    /// Number of distinct materials (ids are `0..material_count`).
    pub material_count: u32,
    /// The scene's default walkthrough.
    pub path: CameraPath,
    /// Triangles each instance stands for in statistics and cost
    /// estimates, where that is not its mesh's count: a scene of boxes
    /// standing for a renderer's own geometry
    /// ([`Scene::with_triangle_counts`]). Empty: every instance counts its
    /// mesh's triangles ([`Scene::instance_triangles`]).
    pub triangle_counts: Vec<u32>,
    /// How far the walkthrough's cameras see: their far clipping distance.
    /// `None`: beyond the whole scene from anywhere in it. A generator sets
    /// it where a paper's scene statistics call for a shorter view
    /// (`occlude_scenes::Inputs`).
    pub view_distance: Option<f32>,
    /// How many times [`Scene::apply`] changed the instances.
    revision: u64,
}

impl Scene {
    /// An empty scene called `name`, with no walkthrough: meshes and
    /// instances are added with [`Scene::add_mesh`] and
    /// [`Scene::add_instance`].
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            meshes: Vec::new(),
            instances: Vec::new(),
            material_count: 0,
            path: Default::default(),
            triangle_counts: Vec::new(),
            view_distance: None,
            revision: 0,
        }
    }

    /// How many times [`Scene::apply`] has changed the instances: equal
    /// revisions of one scene mean equal poses.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Counts one change of the instances ([`crate::motion`]).
    pub(crate) fn bump_revision(&mut self) {
        self.revision += 1;
    }

    /// Takes the revision of the original this is a copy of.
    pub(crate) fn set_revision(&mut self, revision: u64) {
        self.revision = revision;
    }

    /// A scene of boxes only, for culling geometry that a renderer keeps
    /// itself: instance `i` is `bounds[i]`, drawn (by [`Scene::push_clip_triangles`]
    /// and the software backends) as that box's 12 triangles, material 0. Culling
    /// needs no more than the boxes: queries and the hierarchy read
    /// [`Instance::bounds`], kept exactly as given. Each instance counts 12
    /// triangles in statistics and cost estimates, unless
    /// [`Scene::with_triangle_counts`] gives its real count. An empty list
    /// or a bad box is an error.
    pub fn from_bounds(name: impl Into<String>, bounds: &[Aabb]) -> Result<Self, SceneError> {
        let mut scene = Scene::new(name);
        let corners = Aabb::new(Vec3::ZERO, Vec3::ONE).corners().to_vec();
        let indices = BOX_TRIANGLES.iter().flatten().map(|&c| u32::from(c)).collect();
        let cube = scene.add_mesh(Mesh::new(corners, indices));
        for (i, b) in bounds.iter().enumerate() {
            if !(b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all()) {
                return Err(SceneError::BadBounds(i));
            }
            let transform = Self::box_transform(b);
            scene.instances.push(Instance { mesh: cube, transform, material: 0, bounds: *b, enabled: true });
        }
        scene.material_count = 1;
        scene.validate()?;
        Ok(scene)
    }

    /// The transform that makes [`Scene::from_bounds`]' unit cube the box
    /// `b`.
    pub fn box_transform(b: &Aabb) -> Mat4 {
        Mat4::from_translation(b.min) * Mat4::from_scale(b.max - b.min)
    }

    /// Appends the clip-space triangles of instance `i` seen through
    /// `view_projection` to `triangles` (`clip`: scratch for its vertices),
    /// as every CPU-side rasterization of the scene computes them.
    pub fn push_clip_triangles(
        &self,
        i: u32,
        view_projection: &Mat4,
        clip: &mut Vec<Vec4>,
        triangles: &mut Vec<[Vec4; 3]>,
    ) {
        let indices = self.clip_vertices(i, view_projection, clip);
        triangles
            .extend(indices.chunks_exact(3).map(|t| [clip[t[0] as usize], clip[t[1] as usize], clip[t[2] as usize]]));
    }

    /// Writes the clip-space vertices of instance `i` seen through
    /// `view_projection` to `clip` (replacing what it held) and returns its
    /// mesh's triangles, three indices into them each: the triangles of
    /// [`Self::push_clip_triangles`], for a rasterizer that projects each
    /// vertex once.
    pub fn clip_vertices(&self, i: u32, view_projection: &Mat4, clip: &mut Vec<Vec4>) -> &[u32] {
        let inst = &self.instances[i as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let mvp = *view_projection * inst.transform;
        clip.clear();
        clip.extend(mesh.positions.iter().map(|p| mvp * p.extend(1.0)));
        &mesh.indices
    }

    /// Adds a mesh and returns its index.
    pub fn add_mesh(&mut self, mesh: Mesh) -> u32 {
        self.meshes.push(Arc::new(mesh));
        (self.meshes.len() - 1) as u32
    }

    /// Places mesh `mesh` with `transform` and `material`, computing its world box.
    pub fn add_instance(&mut self, mesh: u32, transform: Mat4, material: u32) {
        let bounds = self.meshes[mesh as usize].bounds.transformed(&transform);
        self.material_count = self.material_count.max(material + 1);
        self.instances.push(Instance { mesh, transform, material, bounds, enabled: true });
    }

    /// The scene with instance `i` counting `counts[i]` triangles in
    /// statistics and cost estimates instead of its mesh's (see
    /// [`Scene::triangle_counts`]): what a renderer gives for a scene of
    /// boxes ([`Scene::from_bounds`]) standing for its own meshes, so that
    /// frame statistics and the methods' cost decisions (CHC++'s tight
    /// bounds, NOHC's query costs) see its real geometry. The scene's
    /// triangles as drawn (by the software backends) do not change. A
    /// list of the wrong length is an error.
    pub fn with_triangle_counts(mut self, counts: &[u32]) -> Result<Self, SceneError> {
        if counts.len() != self.instances.len() {
            return Err(SceneError::TriangleCounts { given: counts.len(), instances: self.instances.len() });
        }
        self.triangle_counts = counts.to_vec();
        self.validate()?;
        Ok(self)
    }

    /// Triangles instance `i` counts in statistics and cost estimates:
    /// [`Scene::triangle_counts`]' entry where given, else its mesh's; 0
    /// while it is hidden.
    pub fn instance_triangles(&self, i: usize) -> u64 {
        if !self.instances[i].enabled {
            return 0;
        }
        match self.triangle_counts.get(i) {
            Some(&n) => u64::from(n),
            None => self.meshes[self.instances[i].mesh as usize].triangle_count() as u64,
        }
    }

    /// Triangles over all shown instances (what view-frustum culling would
    /// draw with everything in view), as [`Scene::instance_triangles`]
    /// counts them.
    pub fn triangle_count(&self) -> usize {
        (0..self.instances.len()).map(|i| self.instance_triangles(i) as usize).sum()
    }

    /// Triangles stored once per mesh (memory footprint).
    pub fn unique_triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangle_count()).sum()
    }

    /// Box of all instances, hidden ones included (where they would be).
    pub fn bounds(&self) -> Aabb {
        self.instances.iter().fold(Aabb::EMPTY, |b, i| b.union(&i.bounds))
    }

    /// Checks everything a renderer relies on, so that bad input gets a clear
    /// error instead of a panic or a silent wrong image.
    pub fn validate(&self) -> Result<(), SceneError> {
        for (m, mesh) in self.meshes.iter().enumerate() {
            if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
                return Err(SceneError::NonFiniteVertex { mesh: m, vertex: v });
            }
            if mesh.indices.len() % 3 != 0 {
                return Err(SceneError::PartialTriangle { mesh: m, count: mesh.indices.len() });
            }
            if let Some(&index) = mesh.indices.iter().find(|&&i| i as usize >= mesh.positions.len()) {
                return Err(SceneError::IndexOutOfRange { mesh: m, index, vertices: mesh.positions.len() });
            }
        }
        for (i, inst) in self.instances.iter().enumerate() {
            if inst.mesh as usize >= self.meshes.len() {
                return Err(SceneError::MissingMesh { instance: i, mesh: inst.mesh, meshes: self.meshes.len() });
            }
            if !inst.transform.is_finite() {
                return Err(SceneError::NonFiniteTransform(i));
            }
        }
        if !self.triangle_counts.is_empty() && self.triangle_counts.len() != self.instances.len() {
            let (given, instances) = (self.triangle_counts.len(), self.instances.len());
            return Err(SceneError::TriangleCounts { given, instances });
        }
        if let Some(d) = self.view_distance.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(SceneError::ViewDistance(d));
        }
        if self.triangle_count() == 0 {
            return Err(SceneError::Empty(self.name.clone()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle_scene(p: Vec3, indices: Vec<u32>) -> Scene {
        let mut s = Scene::new("t");
        let m = s.add_mesh(Mesh::new(vec![Vec3::ZERO, Vec3::X, p], indices));
        s.add_instance(m, Mat4::IDENTITY, 0);
        s
    }

    #[test]
    fn validate_reports_bad_input() {
        assert_eq!(triangle_scene(Vec3::Y, vec![0, 1, 2]).validate(), Ok(()));
        assert_eq!(
            triangle_scene(Vec3::NAN, vec![0, 1, 2]).validate(),
            Err(SceneError::NonFiniteVertex { mesh: 0, vertex: 2 })
        );
        assert_eq!(
            triangle_scene(Vec3::Y, vec![0, 1, 7]).validate(),
            Err(SceneError::IndexOutOfRange { mesh: 0, index: 7, vertices: 3 })
        );
        assert_eq!(triangle_scene(Vec3::Y, vec![]).validate(), Err(SceneError::Empty("t".into())));
        for (d, ok) in [(50.0, true), (0.0, false), (-1.0, false), (f32::INFINITY, false), (f32::NAN, false)] {
            let scene = Scene { view_distance: Some(d), ..triangle_scene(Vec3::Y, vec![0, 1, 2]) };
            assert_eq!(scene.validate().is_ok(), ok, "view distance {d}");
        }
    }

    #[test]
    fn scenes_from_bounds_keep_the_boxes_and_refuse_bad_ones() {
        let boxes = [Aabb::new(Vec3::new(-1.5, 0.1, 3.0), Vec3::new(2.25, 0.7, 3.0)), Aabb::new(Vec3::ONE, Vec3::ONE)];
        let scene = Scene::from_bounds("boxes", &boxes).unwrap();
        assert_eq!(scene.instances.len(), 2);
        assert_eq!(scene.triangle_count(), 24);
        for (inst, b) in scene.instances.iter().zip(&boxes) {
            assert_eq!(inst.bounds, *b);
            // The drawn box is the given one, up to rounding of the transform.
            let drawn = scene.meshes[inst.mesh as usize].bounds.transformed(&inst.transform);
            assert!((drawn.min - b.min).abs().max_element() < 1e-6 && (drawn.max - b.max).abs().max_element() < 1e-6);
        }
        let inverted = Aabb::new(Vec3::ONE, Vec3::ZERO);
        assert_eq!(Scene::from_bounds("b", &[boxes[0], inverted]).unwrap_err(), SceneError::BadBounds(1));
        let infinite = Aabb::new(Vec3::ZERO, Vec3::splat(f32::INFINITY));
        assert_eq!(Scene::from_bounds("b", &[infinite]).unwrap_err(), SceneError::BadBounds(0));
        assert_eq!(Scene::from_bounds("b", &[]).unwrap_err(), SceneError::Empty("b".into()));
        let counted = Scene::from_bounds("b", &boxes).unwrap().with_triangle_counts(&[100, 7]).unwrap();
        assert_eq!((counted.instance_triangles(0), counted.instance_triangles(1)), (100, 7));
        assert_eq!(counted.triangle_count(), 107);
        assert_eq!(counted.meshes[0].triangle_count(), 12, "the boxes drawn stay boxes");
        let short = Scene::from_bounds("b", &boxes).unwrap().with_triangle_counts(&[3]);
        assert_eq!(short.unwrap_err(), SceneError::TriangleCounts { given: 1, instances: 2 });
        let none = Scene::from_bounds("b", &boxes).unwrap().with_triangle_counts(&[0, 0]);
        assert_eq!(none.unwrap_err(), SceneError::Empty("b".into()));
    }
}
