//! Procedural, deterministic test scenes with default walkthroughs.
//!
//! [`generate`] builds one of [`SCENE_NAMES`] at a [`Size`] from a seed; the
//! same `(name, size, seed)` always gives the same scene, on every machine,
//! because all randomness comes from `occlude_core`'s own [`rng::Rng`].
//!
//! The scenes stand in for those of the occlusion-culling papers (CHC 2004,
//! CHC++ 2008, IOC): a long field of Utah teapots, a city of streets and
//! buildings, a dense industrial plant, a volume of scattered figures, and
//! the IOC poster's furnished rooms and wide downtown, and a swarm of a
//! million small objects between large blocks (GPU-driven culling's scale).
//! Two scenes move by themselves ([`MOVING_SCENES`], [`generate_moving`]):
//! `traffic`, the city with vehicles driving its streets, and `crowd`, the
//! rooms with people walking and doors opening and closing.
//! Objects are instances of shared meshes (one draw call each), so even the
//! `paper` sizes with millions of triangles stay small in memory.
//!
//! [`load`] also imports real models (glTF 2.0, OBJ) by file name; see
//! [`import`](mod@import). [`export::glb`] writes a scene as a GLB file, and
//! [`building`] generates a building to be written so and imported.

#![warn(missing_docs)]

pub mod animation;
pub mod building;
mod city;
mod crowd;
pub mod export;
mod figures;
pub mod import;
pub mod motion;
pub mod newell;
mod plant;
mod rooms;
pub mod scattered;
pub use occlude_core::rng;
pub mod shapes;
mod swarm;
mod teapots;
mod traffic;
mod walk;

pub use animation::SceneAnimation;
pub use import::{load, load_moving, AutoPath, ImportOptions, LoadError};
pub use motion::{Motion, OwnMotion, SceneMotion};
use occlude_core::{Scene, SceneError};
use std::fmt;
use std::str::FromStr;
use thiserror::Error;

/// How big a generated scene is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Size {
    /// For tests: at most about 200k triangles and a few thousand instances,
    /// so a few hundred frames of several methods render in seconds on the
    /// software rasterizer.
    Small,
    /// About 1-3 million triangles: a realistic load for a GPU.
    Medium,
    /// Near the sizes of the papers' scenes (millions of triangles, tens of
    /// thousands of instances; `swarm`: a million instances), kept in memory
    /// by instancing.
    Paper,
}

impl Size {
    /// Every size, smallest first.
    pub const ALL: [Size; 3] = [Size::Small, Size::Medium, Size::Paper];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Size::Small => "small",
            Size::Medium => "medium",
            Size::Paper => "paper",
        }
    }

    /// Picks one of three values by size (keeps the per-scene tables short).
    pub(crate) fn pick<T>(self, small: T, medium: T, paper: T) -> T {
        match self {
            Size::Small => small,
            Size::Medium => medium,
            Size::Paper => paper,
        }
    }
}

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Size {
    type Err = GenerateError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Size::ALL.into_iter().find(|size| size.name() == s).ok_or_else(|| GenerateError::UnknownSize(s.to_string()))
    }
}

/// The scenes [`generate`] knows, by name: [`PAPER_SCENES`], then `swarm`,
/// then [`MOVING_SCENES`].
pub const SCENE_NAMES: [&str; 9] =
    ["teapots", "city", "plant", "figures", "rooms", "downtown", "swarm", "traffic", "crowd"];

/// The scenes standing in for the papers' (every one but `swarm`): the
/// tests that run every method on every scene iterate these. `swarm`, the
/// million-instance scene, has a small size of thousands of objects on
/// which every query method is slow; its tests are its own.
pub const PAPER_SCENES: [&str; 6] = ["teapots", "city", "plant", "figures", "rooms", "downtown"];

/// The scenes that move by themselves: [`generate_moving`] returns their
/// motion. Their tests are their own, as `swarm`'s.
pub const MOVING_SCENES: [&str; 2] = ["traffic", "crowd"];

/// Why a scene could not be generated.
#[derive(Debug, Error)]
pub enum GenerateError {
    /// The name is not one of [`SCENE_NAMES`].
    #[error("unknown scene '{0}'; the procedural scenes are: teapots, city, plant, figures, rooms, downtown, swarm, traffic, crowd")]
    UnknownScene(String),
    /// The size is not one of `small`, `medium`, `paper`.
    #[error("unknown scene size '{0}'; the sizes are: small, medium, paper")]
    UnknownSize(String),
    /// A generator produced an invalid scene (a bug in this crate).
    #[error("generated scene is invalid: {0}")]
    Invalid(#[from] SceneError),
}

/// Which inputs a generated scene takes where the papers leave them
/// unstated: the walkthrough's shape and heights, the field of view, how
/// far the cameras see.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Inputs {
    /// occlude's own: the default walkthroughs, a 60-degree field of view,
    /// a view beyond the whole scene.
    #[default]
    Own,
    /// The CHC paper's Table 1 (`--paper chc`): `teapots`, `city` and
    /// `plant` with the inputs the paper does not state set so that
    /// view-frustum culling's and stop-and-wait's triangles per frame come
    /// out near the table's at `paper` size. Calibrated from those two
    /// columns only (the scene, not any method, decides them), never from a
    /// method's time. Other scenes are built as with [`Inputs::Own`].
    ChcTable1,
}

/// Builds the scene `name` at `size` from `seed`, with its default
/// walkthrough in `scene.path`. Deterministic: the same arguments always give
/// the same meshes, instances, materials and path. A scene that moves by
/// itself is returned as it is at time 0; [`generate_moving`] also returns
/// its motion.
pub fn generate(name: &str, size: Size, seed: u64) -> Result<Scene, GenerateError> {
    Ok(generate_moving(name, size, seed)?.0)
}

/// [`generate`] with `inputs` where the papers leave them unstated.
pub fn generate_with(name: &str, size: Size, seed: u64, inputs: Inputs) -> Result<Scene, GenerateError> {
    let scene = match (name, inputs) {
        (_, Inputs::Own) => return generate(name, size, seed),
        ("teapots", _) => teapots::generate(size, seed, inputs),
        ("city", _) => city::generate(size, seed, inputs),
        ("plant", _) => plant::generate(size, seed, inputs),
        _ => return generate(name, size, seed),
    };
    scene.validate()?;
    Ok(scene)
}

/// [`generate`], and the scene's own motion for the scenes that move by
/// themselves ([`MOVING_SCENES`]; none for the others), as deterministic as
/// the scene.
pub fn generate_moving(name: &str, size: Size, seed: u64) -> Result<(Scene, Option<SceneMotion>), GenerateError> {
    let still = |scene: Scene| (scene, None);
    let moving = |(scene, motion): (Scene, SceneMotion)| (scene, Some(motion));
    let (scene, motion) = match name {
        "teapots" => still(teapots::generate(size, seed, Inputs::Own)),
        "city" => still(city::generate(size, seed, Inputs::Own)),
        "plant" => still(plant::generate(size, seed, Inputs::Own)),
        "figures" => still(figures::generate(size, seed)),
        "rooms" => still(rooms::generate(size, seed)),
        "downtown" => still(city::downtown(size, seed)),
        "swarm" => still(swarm::generate(size, seed)),
        "traffic" => moving(traffic::generate(size, seed)),
        "crowd" => moving(crowd::generate(size, seed)),
        _ => return Err(GenerateError::UnknownScene(name.to_string())),
    };
    scene.validate()?;
    Ok((scene, motion))
}

#[cfg(test)]
mod tests;
