//! glTF 2.0 node animations (specification section 3.11, "Animations", and
//! appendix C, "Animation Sampler Interpolation Modes"): translation,
//! rotation and scale channels with `STEP`, `LINEAR` and `CUBICSPLINE`
//! samplers, read into a [`SceneAnimation`]. Key times and values are read
//! through the importer's checked accessor reading. `weights` channels,
//! skins and morph targets are not played (warnings say so).

use super::gltf::{expect_f32, float, read_accessor, Buffers};
use super::{Builder, LoadError, MAX_COORDINATE};
use crate::animation::{Channel, Interpolation, Node, Parent, Pose, Property, SceneAnimation};
use glam::{Mat4, Quat, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::{Interpolation as GltfInterpolation, Property as GltfProperty};
use gltf::json::validation::Checked;
use gltf::Document;

/// A node as the import reached it, in the order it did (each after its
/// parent).
pub(super) struct Visit {
    /// Its index in the file.
    pub node: usize,
    /// Its parent's index, none for a root.
    pub parent: Option<usize>,
    /// Its parent's world transform.
    pub parent_world: Mat4,
}

/// `animation 2 'walk'`: how errors name an animation.
fn named(index: usize, name: Option<&str>) -> String {
    match name {
        Some(name) => format!("animation {index} '{name}'"),
        None => format!("animation {index}"),
    }
}

/// Checks what the `gltf` crate's document API would look up without
/// checking (1.4.1 unwraps them): every channel's sampler, target node and
/// path, every sampler's accessors and interpolation. Runs before the
/// document is built.
pub(super) fn check_references(root: &gltf::json::Root) -> Result<(), String> {
    for (a, animation) in root.animations.iter().enumerate() {
        let what = named(a, animation.name.as_deref());
        for (c, channel) in animation.channels.iter().enumerate() {
            let (sampler, node) = (channel.sampler.value(), channel.target.node.value());
            if sampler >= animation.samplers.len() {
                return Err(format!(
                    "{what}: channel {c} uses sampler {sampler}, which does not exist: there are {} samplers",
                    animation.samplers.len()
                ));
            }
            if node >= root.nodes.len() {
                return Err(format!(
                    "{what}: channel {c} targets node {node}, which does not exist: there are {} nodes",
                    root.nodes.len()
                ));
            }
            if !matches!(channel.target.path, Checked::Valid(_)) {
                return Err(format!(
                    "{what}: channel {c} animates an unknown path: expected translation, rotation, scale or weights"
                ));
            }
        }
        for (s, sampler) in animation.samplers.iter().enumerate() {
            for (role, accessor) in [("input", sampler.input.value()), ("output", sampler.output.value())] {
                if accessor >= root.accessors.len() {
                    return Err(format!(
                        "{what}: sampler {s}'s {role} accessor {accessor} does not exist: there are {} accessors",
                        root.accessors.len()
                    ));
                }
            }
            if !matches!(sampler.interpolation, Checked::Valid(_)) {
                return Err(format!(
                    "{what}: sampler {s} has an unknown interpolation: expected LINEAR, STEP or CUBICSPLINE"
                ));
            }
        }
    }
    Ok(())
}

/// Warns that skins and morph targets stay in their rest pose, where the
/// file has any.
pub(super) fn warn_unplayed(builder: &mut Builder, root: &gltf::json::Root) {
    let morphs =
        root.meshes.iter().flat_map(|m| &m.primitives).any(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty()));
    if !root.skins.is_empty() || morphs {
        builder.warn(
            "its skins and morph targets are not played: those meshes stay in their rest pose, and their boxes \
             would not bound them where a renderer deforms them",
        );
    }
}

/// Reads every animation of `document`. `visits` are the nodes the import
/// reached, `instances` the instances it placed with their nodes. None when
/// no animation moves an instance.
pub(super) fn read(
    builder: &mut Builder,
    document: &Document,
    buffers: &Buffers,
    visits: &[Visit],
    instances: &[(u32, usize)],
) -> Result<Option<SceneAnimation>, LoadError> {
    let mut channels: Vec<Vec<Channel>> = vec![Vec::new(); document.nodes().len()];
    let mut duration = 0.0f32;
    let mut weights = false;
    for animation in document.animations() {
        let what = named(animation.index(), animation.name());
        for channel in animation.channels() {
            let target = channel.target();
            let property = match target.property() {
                GltfProperty::Translation => Property::Translation,
                GltfProperty::Rotation => Property::Rotation,
                GltfProperty::Scale => Property::Scale,
                GltfProperty::MorphTargetWeights => {
                    weights = true;
                    continue;
                }
            };
            let node = target.node();
            let channel = read_channel(&channel, property, buffers)
                .map_err(|e| builder.invalid(format!("{what}: channel {}: {e}", channel.index())))?;
            if let gltf::scene::Transform::Matrix { .. } = node.transform() {
                return Err(builder.invalid(format!(
                    "{what}: animates node {}, which has a matrix: glTF animates only nodes with translation, \
                     rotation and scale",
                    node.index()
                )));
            }
            duration = duration.max(channel.end());
            channels[node.index()].push(channel);
        }
    }
    if weights {
        builder.warn("its morph target weights channels are ignored: morph targets stay in their rest pose");
    }
    let mut slots: Vec<Option<usize>> = vec![None; document.nodes().len()];
    let mut nodes = Vec::new();
    for visit in visits {
        let parent = visit.parent.and_then(|p| slots[p]);
        let own = std::mem::take(&mut channels[visit.node]);
        if parent.is_none() && own.is_empty() {
            continue;
        }
        let node = document.nodes().nth(visit.node).expect("a visited node exists");
        let pose = if own.is_empty() {
            Pose::Still(Mat4::from_cols_array_2d(&node.transform().matrix()))
        } else {
            let (t, r, s) = node.transform().decomposed();
            Pose::Animated { rest: (t.into(), Quat::from_array(r), s.into()), channels: own }
        };
        slots[visit.node] = Some(nodes.len());
        nodes.push(Node { parent: parent.map_or(Parent::Fixed(visit.parent_world), Parent::Moving), pose });
    }
    let moved: Vec<(u32, usize)> =
        instances.iter().filter_map(|&(instance, node)| slots[node].map(|slot| (instance, slot))).collect();
    Ok((!moved.is_empty()).then(|| SceneAnimation::new(nodes, moved, duration)))
}

/// The keys of `channel` animating `property`, checked: float key times,
/// finite and strictly increasing; as many values as keys (three per key
/// for cubic splines), of the accessor type the property needs, finite, and
/// within [`MAX_COORDINATE`]; rotation keys of unit length.
fn read_channel(channel: &gltf::animation::Channel, property: Property, buffers: &Buffers) -> Result<Channel, String> {
    let sampler = channel.sampler();
    let interpolation = match sampler.interpolation() {
        GltfInterpolation::Step => Interpolation::Step,
        GltfInterpolation::Linear => Interpolation::Linear,
        GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let (input, output) = (sampler.input(), sampler.output());
    expect_f32(&input, Dimensions::Scalar, "its key time accessor")?;
    let keys = input.count();
    let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    if keys == 0 {
        return Err("it has no keys".into());
    }
    if keys.checked_mul(per_key) != Some(output.count()) {
        return Err(format!(
            "{keys} key times but {} values; {interpolation:?} needs {per_key} per key",
            output.count()
        ));
    }
    let times = read_accessor(&input, buffers, 0.0, float)?;
    if let Some(k) = times.iter().position(|t| !t.is_finite()) {
        return Err(format!("key time {k} is not finite"));
    }
    if let Some(k) = times.windows(2).position(|w| w[0] >= w[1]) {
        return Err(format!(
            "key time {} ({}) does not increase on the one before ({})",
            k + 1,
            times[k + 1],
            times[k]
        ));
    }
    let mut values = read_values(&output, property, buffers)?;
    if let Some(v) = values.iter().position(|v| !v.is_finite()) {
        return Err(format!("value {v} is not finite"));
    }
    if let Some(v) = values.iter().position(|v| v.abs().max_element() > MAX_COORDINATE) {
        return Err(format!("value {v} is beyond {MAX_COORDINATE:e}"));
    }
    if property == Property::Rotation && interpolation != Interpolation::CubicSpline {
        for (k, value) in values.iter_mut().enumerate() {
            *value = value.try_normalize().ok_or_else(|| format!("rotation {k} is not a quaternion: it is zero"))?;
        }
    }
    Ok(Channel { property, interpolation, times, values })
}

/// The values of `output` for `property`: float vectors for translation and
/// scale; float or normalized integer quaternions for rotation (glTF 2.0,
/// section 3.11: rotations may be normalized bytes or shorts).
fn read_values(output: &gltf::Accessor, property: Property, buffers: &Buffers) -> Result<Vec<Vec4>, String> {
    let vec3 = |e: &[u8]| Vec4::new(float(e), float(&e[4..]), float(&e[8..]), 0.0);
    match (property, output.dimensions(), output.data_type(), output.normalized()) {
        (Property::Translation | Property::Scale, Dimensions::Vec3, DataType::F32, _) => {
            read_accessor(output, buffers, Vec4::ZERO, vec3)
        }
        (Property::Rotation, Dimensions::Vec4, DataType::F32, _) => read_accessor(output, buffers, Vec4::ZERO, |e| {
            Vec4::from_array(std::array::from_fn(|i| float(&e[4 * i..])))
        }),
        (Property::Rotation, Dimensions::Vec4, DataType::I8, true) => {
            read_accessor(output, buffers, Vec4::ZERO, quaternion::<1>(|b| (f32::from(b[0] as i8) / 127.0).max(-1.0)))
        }
        (Property::Rotation, Dimensions::Vec4, DataType::U8, true) => {
            read_accessor(output, buffers, Vec4::ZERO, quaternion::<1>(|b| f32::from(b[0]) / 255.0))
        }
        (Property::Rotation, Dimensions::Vec4, DataType::I16, true) => {
            let short = |b: &[u8]| f32::from(i16::from_le_bytes([b[0], b[1]]));
            read_accessor(output, buffers, Vec4::ZERO, quaternion::<2>(move |b| (short(b) / 32767.0).max(-1.0)))
        }
        (Property::Rotation, Dimensions::Vec4, DataType::U16, true) => {
            let short = |b: &[u8]| f32::from(u16::from_le_bytes([b[0], b[1]]));
            read_accessor(output, buffers, Vec4::ZERO, quaternion::<2>(move |b| short(b) / 65535.0))
        }
        (_, dimensions, data_type, normalized) => {
            let expected = match property {
                Property::Rotation => "F32 Vec4, or normalized I8, U8, I16 or U16 Vec4",
                Property::Translation | Property::Scale => "F32 Vec3",
            };
            let normalized = if normalized { "normalized " } else { "" };
            Err(format!(
                "its {property:?} values (accessor {}) are {normalized}{data_type:?} {dimensions:?}, not {expected}",
                output.index()
            ))
        }
    }
}

/// A decoder of quaternions of four `N`-byte components, each by
/// `component`.
fn quaternion<const N: usize>(component: impl Fn(&[u8]) -> f32) -> impl Fn(&[u8]) -> Vec4 {
    move |e| Vec4::from_array(std::array::from_fn(|i| component(&e[N * i..])))
}
