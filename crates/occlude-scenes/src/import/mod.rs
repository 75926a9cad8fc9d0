//! Import of real models: glTF 2.0 (`.gltf` with external, percent-encoded
//! or data-URI buffers, `.glb`; sparse accessors) and Wavefront OBJ (`.obj`
//! with its `.mtl`).
//!
//! Both formats become the same [`Scene`]: one occlude [`Mesh`] per glTF
//! primitive or OBJ object (split spatially when large, see [`ImportOptions`]),
//! one [`occlude_core::Instance`] per placement with its world transform, and
//! one material id per material of the file. Units: glTF is y-up metres by
//! specification; OBJ has no units, so it is assumed y-up metres as well.
//! Imported files have no walkthrough, so one is made (see [`AutoPath`]).
//!
//! Every byte range, index and number read from a file is checked before use:
//! bad input gives a [`LoadError`] naming the file and the problem, never a
//! panic, and nothing is allocated from a size a file claims, only from the
//! bytes it really has (the one exception, sparse glTF accessors on a base of
//! zeros, is capped per file). The files a model refers to (glTF buffers,
//! OBJ material libraries) are read only inside the model's folder, only
//! when they are regular files, and only up to the size declared (a glTF
//! buffer's `byteLength`) or [`MAX_MATERIAL_BYTES`]; OBJ face indices are
//! checked before `tobj` reads them. Placed meshes must stay within
//! [`MAX_COORDINATE`] of the origin; meshes without triangles are left out.
//! Both importers are fuzzed (`fuzz/` at the workspace root).

mod autopath;
mod gltf;
mod gltf_animation;
mod obj;
mod obj_indices;
mod referenced;
mod split;
use crate::{generate_moving, GenerateError, OwnMotion, SceneAnimation, Size, SCENE_NAMES};
use glam::{Mat4, Vec3};
use occlude_core::{Mesh, Scene, SceneError};
use std::io;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Farthest a placed mesh may reach from the origin along any axis, metres.
/// Paths, cameras and hierarchies square distances in 32-bit floats, which
/// overflow from about 1e19; 1e9 m (beyond the Moon's orbit) leaves room
/// for any real model, even in millimetres or geocentric coordinates.
pub const MAX_COORDINATE: f32 = 1e9;

/// The largest model file read, bytes (4 GiB; a GLB's header cannot
/// address more).
pub const MAX_MODEL_BYTES: u64 = 4 << 30;

/// The largest OBJ material library (`.mtl`) read, bytes.
pub const MAX_MATERIAL_BYTES: u64 = 64 << 20;

/// The file extensions [`load`] imports, lower case, without the dot.
pub const MODEL_EXTENSIONS: [&str; 3] = ["gltf", "glb", "obj"];

/// How imported scenes get their walkthrough.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AutoPath {
    /// A circle around the model, outside its bounds, looking at its centre:
    /// works for every model.
    #[default]
    Orbit,
    /// A walk at eye height through the free space of the model (for
    /// buildings); falls back to [`AutoPath::Orbit`] with a warning where too
    /// little free space is found.
    Walk,
}

impl AutoPath {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AutoPath::Orbit => "orbit",
            AutoPath::Walk => "walk",
        }
    }
}

impl std::str::FromStr for AutoPath {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        [AutoPath::Orbit, AutoPath::Walk]
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown automatic path '{s}': expected walk or orbit"))
    }
}

/// Options of an import.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImportOptions {
    /// A mesh with more triangles than this is split spatially into several
    /// meshes, so that culling has objects to work with (a scanned building
    /// is often one huge mesh). 0 never splits.
    pub split_triangles: usize,
    /// How the walkthrough is made.
    pub auto_path: AutoPath,
}

impl ImportOptions {
    /// Default of [`ImportOptions::split_triangles`].
    pub const DEFAULT_SPLIT_TRIANGLES: usize = 10_000;
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self { split_triangles: Self::DEFAULT_SPLIT_TRIANGLES, auto_path: AutoPath::default() }
    }
}

/// Why a scene could not be loaded. Every variant about a file names it.
#[derive(Debug, Error)]
pub enum LoadError {
    /// Neither a procedural scene name nor a file with a model extension.
    #[error(
        "unknown scene '{name}': expected a procedural scene ({scenes}) or a model file ending in .gltf, .glb or .obj",
        scenes = SCENE_NAMES.join(", ")
    )]
    UnknownScene {
        /// The name or path given.
        name: String,
    },
    /// A procedural scene could not be generated.
    #[error(transparent)]
    Generate(#[from] GenerateError),
    /// The model file cannot be read.
    #[error("cannot read {}: {reason}", path.display())]
    Io {
        /// The model file.
        path: PathBuf,
        /// What the system said.
        reason: io::Error,
    },
    /// A file the model refers to (a glTF buffer) cannot be read: it is
    /// missing, or not a regular file.
    #[error("{}: cannot read its buffer file {}: {reason}", path.display(), file.display())]
    MissingFile {
        /// The model file.
        path: PathBuf,
        /// The file it refers to.
        file: PathBuf,
        /// What the system said.
        reason: io::Error,
    },
    /// The file is not a well-formed file of its format (bad JSON or OBJ
    /// syntax, a truncated GLB, a header whose sizes do not match the file).
    #[error("{} is not a valid {format} file: {problem}", path.display())]
    Malformed {
        /// The model file.
        path: PathBuf,
        /// `glTF`, `GLB` or `OBJ`.
        format: &'static str,
        /// What is wrong.
        problem: String,
    },
    /// The file is well formed but its data is not usable (a byte range
    /// outside its buffer, an index past the vertices, a non-finite position
    /// or transform, a node hierarchy that is not a tree, a buffer or
    /// material file outside the model's folder).
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The model file.
        path: PathBuf,
        /// What is wrong, naming the mesh, accessor or node.
        problem: String,
    },
    /// The file holds no triangle to render.
    #[error("{}: the model has no triangles to render", path.display())]
    Empty {
        /// The model file.
        path: PathBuf,
    },
}

impl LoadError {
    /// True when the error is in what the user gave (a name, a file), false
    /// when it is a bug of a procedural generator: the command line exits
    /// with 2 for the former and 1 for the latter.
    pub fn is_input_error(&self) -> bool {
        !matches!(self, LoadError::Generate(GenerateError::Invalid(_)))
    }
}

/// The format of a model file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// glTF 2.0 JSON (`.gltf`).
    Gltf,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
    /// Wavefront OBJ (`.obj`).
    Obj,
}

/// What a `--scene` argument names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneSource {
    /// One of [`SCENE_NAMES`].
    Procedural(String),
    /// A model file that exists.
    File {
        /// Its path.
        path: PathBuf,
        /// Its format, from the extension.
        format: ModelFormat,
    },
}

impl SceneSource {
    /// Tells what `name_or_path` names: a procedural scene, or an existing
    /// file with one of [`MODEL_EXTENSIONS`] (any case). Checks only the name
    /// and that the file exists, so a command line can reject a typo before
    /// any work starts.
    pub fn resolve(name_or_path: &str) -> Result<Self, LoadError> {
        if SCENE_NAMES.contains(&name_or_path) {
            return Ok(SceneSource::Procedural(name_or_path.to_string()));
        }
        let path = PathBuf::from(name_or_path);
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let format = match extension.as_deref() {
            Some("gltf") => ModelFormat::Gltf,
            Some("glb") => ModelFormat::Glb,
            Some("obj") => ModelFormat::Obj,
            _ => return Err(LoadError::UnknownScene { name: name_or_path.to_string() }),
        };
        std::fs::metadata(&path).map_err(|reason| LoadError::Io { path: path.clone(), reason })?;
        Ok(SceneSource::File { path, format })
    }
}

/// An imported scene with the warnings of its import.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The scene, valid, with an automatic walkthrough.
    pub scene: Scene,
    /// Things skipped or assumed (non-triangle primitives, a missing `.mtl`,
    /// a walk that fell back to an orbit), one sentence each naming the file.
    pub warnings: Vec<String>,
    /// The file's node animations, when they move any instance (glTF only).
    pub animation: Option<SceneAnimation>,
}

/// Loads `name_or_path`: the procedural scene of that name (from `size` and
/// `seed`), or else the model file it names (`size` and `seed` are then
/// unused). Import warnings are printed to stderr; use [`import`] to get them
/// as values instead. The scene's own motion is left out; [`load_moving`]
/// keeps it.
pub fn load(name_or_path: &str, size: Size, seed: u64, options: &ImportOptions) -> Result<Scene, LoadError> {
    Ok(load_moving(name_or_path, size, seed, options)?.0)
}

/// [`load`], with the scene's own motion: a generated scene's script
/// ([`generate_moving`]) or a model's node animations when it has any that
/// move an instance (OBJ files have none).
pub fn load_moving(
    name_or_path: &str,
    size: Size,
    seed: u64,
    options: &ImportOptions,
) -> Result<(Scene, Option<OwnMotion>), LoadError> {
    match SceneSource::resolve(name_or_path)? {
        SceneSource::Procedural(name) => {
            let (scene, motion) = generate_moving(&name, size, seed)?;
            Ok((scene, motion.map(OwnMotion::Scripted)))
        }
        SceneSource::File { path, format } => {
            let imported = import(&path, format, options)?;
            for warning in &imported.warnings {
                eprintln!("warning: {warning}");
            }
            Ok((imported.scene, imported.animation.map(OwnMotion::Animation)))
        }
    }
}

/// Imports the model file `path` of `format`, checked by
/// [`Scene::validate`], with its automatic walkthrough.
pub fn import(path: &Path, format: ModelFormat, options: &ImportOptions) -> Result<Imported, LoadError> {
    let bytes = occlude_core::input_file::read(path, MAX_MODEL_BYTES)
        .map_err(|reason| LoadError::Io { path: path.to_path_buf(), reason })?;
    import_bytes(path, &bytes, format, options)
}

/// Imports a model of `format` held in memory as if it were the file `path`:
/// errors and the scene name come from `path`, and the files the model refers
/// to (glTF buffers, OBJ materials) are looked for beside it. For models that
/// are not files (generated in memory, fuzzing); [`import`] reads the file
/// and calls this.
pub fn import_bytes(
    path: &Path,
    bytes: &[u8],
    format: ModelFormat,
    options: &ImportOptions,
) -> Result<Imported, LoadError> {
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let mut builder =
        Builder { path: path.to_path_buf(), scene: Scene::new(name.as_str()), options: *options, warnings: vec![] };
    let animation = match format {
        ModelFormat::Gltf | ModelFormat::Glb => gltf::import(&mut builder, bytes, format == ModelFormat::Glb)?,
        ModelFormat::Obj => {
            obj::import(&mut builder, bytes)?;
            None
        }
    };
    builder.finish(animation)
}

/// Collects meshes and instances while a file is read, and finishes the scene.
pub(crate) struct Builder {
    /// The file being imported (for errors and warnings).
    path: PathBuf,
    scene: Scene,
    options: ImportOptions,
    warnings: Vec<String>,
}

impl Builder {
    /// Error `problem` about the file being imported.
    fn invalid(&self, problem: impl Into<String>) -> LoadError {
        LoadError::Invalid { path: self.path.clone(), problem: problem.into() }
    }

    /// Error: the file `what` refers to (`buffer 2`) was refused or cannot
    /// be read.
    fn refused(&self, what: &str, refused: referenced::Refused) -> LoadError {
        match refused {
            referenced::Refused::Reference(why) => self.invalid(format!("{what}: {why}")),
            referenced::Refused::Unreadable(file, reason) => {
                LoadError::MissingFile { path: self.path.clone(), file, reason }
            }
        }
    }

    /// Error: the file is not well-formed `format`.
    fn malformed(&self, format: &'static str, problem: impl Into<String>) -> LoadError {
        LoadError::Malformed { path: self.path.clone(), format, problem: problem.into() }
    }

    /// Records a warning about the file being imported.
    fn warn(&mut self, warning: impl std::fmt::Display) {
        let warning = format!("{}: {warning}", self.path.display());
        self.warnings.push(warning);
    }

    /// Adds the triangles `indices` over `positions` as one or more meshes
    /// (split when larger than [`ImportOptions::split_triangles`]) and
    /// returns their indices (none without triangles). `what` names the
    /// source (`mesh 2 primitive 0`) in errors about non-finite positions or
    /// indices out of range.
    fn add_geometry(&mut self, what: &str, positions: Vec<Vec3>, indices: Vec<u32>) -> Result<Vec<u32>, LoadError> {
        if let Some((v, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(self.invalid(format!("{what}: vertex {v} has a non-finite position {p}")));
        }
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(
                self.invalid(format!("{what}: index {i} is out of range: there are {} vertices", positions.len()))
            );
        }
        if indices.is_empty() {
            // Nothing to draw: an instance of it would have an empty box.
            return Ok(Vec::new());
        }
        let meshes = split::split(Mesh::new(positions, indices), self.options.split_triangles);
        Ok(meshes.into_iter().map(|m| self.scene.add_mesh(m)).collect())
    }

    /// Places every mesh of `meshes` with `transform` and `material`; `what`
    /// names the placement (`node 3`) in the error when a placed mesh reaches
    /// beyond [`MAX_COORDINATE`].
    fn place(&mut self, what: &str, meshes: &[u32], transform: Mat4, material: u32) -> Result<(), LoadError> {
        for &mesh in meshes {
            self.scene.add_instance(mesh, transform, material);
            let bounds = self.scene.instances.last().map(|i| i.bounds).unwrap_or_default();
            let reach = bounds.min.abs().max(bounds.max.abs()).max_element();
            if !(bounds.is_finite() && reach <= MAX_COORDINATE) {
                return Err(self.invalid(format!(
                    "{what}: its world box reaches {reach:e} m from the origin, beyond the {MAX_COORDINATE:e} m \
                     that 32-bit rendering handles"
                )));
            }
        }
        Ok(())
    }

    /// Validates the scene and gives it its walkthrough; `animation` is the
    /// file's.
    fn finish(mut self, animation: Option<SceneAnimation>) -> Result<Imported, LoadError> {
        match self.scene.validate() {
            Ok(()) => {}
            Err(SceneError::Empty(_)) => return Err(LoadError::Empty { path: self.path }),
            Err(e) => return Err(self.invalid(e.to_string())),
        }
        self.scene.path = match self.options.auto_path {
            AutoPath::Orbit => autopath::orbit(&self.scene.bounds()),
            AutoPath::Walk => match autopath::walk(&self.scene) {
                Ok(path) => path,
                Err(why) => {
                    self.warn(format_args!("no walk through the model ({why}); orbiting it instead"));
                    autopath::orbit(&self.scene.bounds())
                }
            },
        };
        Ok(Imported { scene: self.scene, warnings: self.warnings, animation })
    }
}
