//! glTF 2.0 import. The `gltf` crate parses and validates the JSON document;
//! GLB chunks, buffers and accessors are read here, with every byte range
//! checked against the bytes really present.

use super::gltf_animation::{self, Visit};
use super::{referenced, Builder, LoadError};
use crate::SceneAnimation;
use base64::Engine;
use glam::{Mat4, Vec3};
use gltf::accessor::sparse::IndexType;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::{Accessor, Document, Semantic};
use std::borrow::Cow;
use std::cell::Cell;
use std::collections::hash_map::{Entry, HashMap};

/// GLB chunk type of the JSON chunk (`JSON`, little endian).
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// GLB chunk type of the binary chunk (`BIN\0`, little endian).
const CHUNK_BIN: u32 = 0x004E_4942;

/// Imports glTF (`binary`: GLB) `bytes`, the file of `builder`, into it: the
/// default scene (else the first, else every root node), its node tree
/// flattened into instances with world transforms. A glTF mesh used by
/// several nodes is read once and instanced. Material ids are glTF material
/// indices; primitives without a material share the id after the last.
/// Triangle strips and fans become triangle lists; points and lines are
/// skipped with a warning. Returns the file's animations, if any moves an
/// instance (see [`gltf_animation`]).
pub(super) fn import(builder: &mut Builder, bytes: &[u8], binary: bool) -> Result<Option<SceneAnimation>, LoadError> {
    let (json, blob) = if binary { glb_chunks(builder, bytes)? } else { (bytes, None) };
    let format = if binary { "GLB" } else { "glTF" };
    let root = gltf::json::Root::from_slice(json).map_err(|e| builder.malformed(format, e.to_string()))?;
    check_position_accessors(&root).map_err(|e| builder.malformed(format, e))?;
    gltf_animation::check_references(&root).map_err(|e| builder.invalid(e))?;
    gltf_animation::warn_unplayed(builder, &root);
    let document = Document::from_json(root).map_err(|e| builder.malformed(format, e.to_string()))?;
    let buffers = load_buffers(builder, &document, blob)?;
    let default_material = document.materials().len() as u32;

    let scene = document.default_scene().or_else(|| document.scenes().next());
    let roots: Vec<gltf::Node> = match &scene {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            document.nodes().flat_map(|n| n.children()).for_each(|c| is_child[c.index()] = true);
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut visited = vec![false; document.nodes().len()];
    let mut meshes: HashMap<usize, Vec<(Vec<u32>, u32)>> = HashMap::new();
    // Every node reached, and every instance placed with its node, for the
    // animations.
    let mut visits = Vec::new();
    let mut instances = Vec::new();
    let mut stack: Vec<(gltf::Node, Option<usize>, Mat4)> =
        roots.into_iter().rev().map(|n| (n, None, Mat4::IDENTITY)).collect();
    while let Some((node, parent_node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(
                builder.invalid(format!("node {} is reached twice: the node hierarchy is not a tree", node.index()))
            );
        }
        visits.push(Visit { node: node.index(), parent: parent_node, parent_world: parent });
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(builder.invalid(format!("node {} has a non-finite transform", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            let parts = match meshes.entry(mesh.index()) {
                Entry::Occupied(entry) => entry.into_mut(),
                Entry::Vacant(entry) => entry.insert(read_mesh(builder, &mesh, &buffers, default_material)?),
            };
            let first = builder.scene.instances.len() as u32;
            for (parts, material) in parts.iter() {
                builder.place(&format!("node {}", node.index()), parts, world, *material)?;
            }
            instances.extend((first..builder.scene.instances.len() as u32).map(|i| (i, node.index())));
        }
        stack.extend(node.children().collect::<Vec<_>>().into_iter().rev().map(|c| (c, Some(node.index()), world)));
    }
    // Without a scene every node is a root or below one, unless some nodes
    // are each other's children: a cycle, which no root reaches.
    if let (None, Some(node)) = (scene, visited.iter().position(|v| !v)) {
        return Err(builder.invalid(format!(
            "node {node} is in a cycle of children (no root reaches it): the node hierarchy is not a tree"
        )));
    }
    gltf_animation::read(builder, &document, &buffers, &visits, &instances)
}

/// Checks that the POSITION accessor of every primitive exists. The `gltf`
/// crate's validation (1.4.1) looks it up without checking and panics on an
/// index past the accessors (found by fuzzing), so this runs before it.
fn check_position_accessors(root: &gltf::json::Root) -> Result<(), String> {
    let position = gltf::json::validation::Checked::Valid(Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            match primitive.attributes.get(&position) {
                Some(index) if index.value() >= root.accessors.len() => {
                    return Err(format!(
                        "mesh {m} primitive {p}: its POSITION accessor {} does not exist: there are {} accessors",
                        index.value(),
                        root.accessors.len()
                    ))
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// The JSON chunk and the optional binary chunk of GLB `bytes`.
fn glb_chunks<'b>(builder: &Builder, bytes: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>), LoadError> {
    let bad = |problem: String| builder.malformed("GLB", problem);
    let word = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    if bytes.len() < 12 {
        return Err(bad(format!("truncated: {} bytes, shorter than the 12-byte GLB header", bytes.len())));
    }
    if &bytes[..4] != b"glTF" {
        return Err(bad("it does not start with the GLB magic 'glTF'".into()));
    }
    if word(4) != 2 {
        return Err(bad(format!("GLB version {}, only version 2 is supported", word(4))));
    }
    if word(8) as usize != bytes.len() {
        return Err(bad(format!(
            "its header gives a length of {} bytes but the file has {} bytes (truncated or damaged)",
            word(8),
            bytes.len()
        )));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < bytes.len() {
        if bytes.len() - at < 8 {
            return Err(bad(format!("truncated chunk header at byte {at}")));
        }
        let length = word(at) as usize;
        let start = at + 8;
        if length > bytes.len() - start {
            return Err(bad(format!(
                "the chunk at byte {at} claims {length} bytes but only {} remain",
                bytes.len() - start
            )));
        }
        chunks.push((word(at + 4), &bytes[start..start + length]));
        at = start + length;
    }
    match chunks.as_slice() {
        [(CHUNK_JSON, json), rest @ ..] => {
            Ok((json, rest.first().filter(|(kind, _)| *kind == CHUNK_BIN).map(|(_, data)| *data)))
        }
        _ => Err(bad("the first chunk is not the JSON chunk".into())),
    }
}

/// The bytes of a file's buffers, and how many more elements accessors
/// without a buffer view may fill with zeros (see [`MAX_ZERO_ELEMENTS`]).
pub(super) struct Buffers<'b> {
    /// Per glTF buffer, its bytes.
    bytes: Vec<Cow<'b, [u8]>>,
    /// What is left of [`MAX_ZERO_ELEMENTS`].
    zeros_left: Cell<usize>,
}

/// The bytes of every buffer of `document`: the GLB binary chunk, a base64
/// data URI, or a file inside the model's folder (its URI percent-decoded,
/// resolved by [`referenced`], at most its declared length read); each at
/// least its declared length.
fn load_buffers<'b>(builder: &Builder, document: &Document, blob: Option<&'b [u8]>) -> Result<Buffers<'b>, LoadError> {
    let bytes = document
        .buffers()
        .map(|buffer| {
            let i = buffer.index();
            let data: Cow<[u8]> = match buffer.source() {
                gltf::buffer::Source::Bin => Cow::Borrowed(blob.ok_or_else(|| {
                    builder.invalid(format!("buffer {i} refers to the GLB binary chunk, which is missing"))
                })?),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| builder.invalid(format!("buffer {i}: only base64 data URIs are supported")))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| builder.invalid(format!("buffer {i}: bad base64 data URI: {e}")))?
                        .into()
                }
                gltf::buffer::Source::Uri(uri) => {
                    let relative = percent_decode(uri).map_err(|e| builder.invalid(format!("buffer {i}: {e}")))?;
                    // Only the declared bytes are read: a longer file (or a
                    // device, which `referenced` refuses anyway) cannot make
                    // the import allocate more than the model declares.
                    let (bytes, _) = referenced::read_up_to(&builder.path, &relative, buffer.length() as u64)
                        .map_err(|refused| builder.refused(&format!("buffer {i}"), refused))?;
                    bytes.into()
                }
            };
            if data.len() < buffer.length() {
                return Err(builder.invalid(format!(
                    "buffer {i} has {} bytes but declares a byteLength of {}",
                    data.len(),
                    buffer.length()
                )));
            }
            Ok(data)
        })
        .collect::<Result<_, _>>()?;
    Ok(Buffers { bytes, zeros_left: Cell::new(MAX_ZERO_ELEMENTS) })
}

/// `uri` with its percent escapes decoded (`my%20buffer.bin` is the file
/// `my buffer.bin`): glTF URIs are RFC 3986 references. An escape that is not
/// `%` and two hex digits, or bytes that are not UTF-8, are an error.
fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut at = 0;
    while at < bytes.len() {
        if bytes[at] != b'%' {
            decoded.push(bytes[at]);
            at += 1;
            continue;
        }
        let digit = |k: usize| bytes.get(at + k).and_then(|&b| (b as char).to_digit(16));
        match (digit(1), digit(2)) {
            (Some(high), Some(low)) => decoded.push((high * 16 + low) as u8),
            _ => {
                let escape = String::from_utf8_lossy(&bytes[at..bytes.len().min(at + 3)]);
                return Err(format!(
                    "its URI '{uri}' has a bad percent escape '{escape}' at byte {at}: expected '%' and two hex digits"
                ));
            }
        }
        at += 3;
    }
    String::from_utf8(decoded).map_err(|_| format!("its URI '{uri}' decodes to bytes that are not UTF-8"))
}

/// Reads every triangle primitive of `mesh` as meshes of `builder`, with its
/// material id.
fn read_mesh(
    builder: &mut Builder,
    mesh: &gltf::Mesh,
    buffers: &Buffers,
    default_material: u32,
) -> Result<Vec<(Vec<u32>, u32)>, LoadError> {
    let mut parts = Vec::new();
    for primitive in mesh.primitives() {
        let what = format!("mesh {} primitive {}", mesh.index(), primitive.index());
        let mode = primitive.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            builder.warn(format_args!("{what} draws {mode:?}, not triangles; skipped"));
            continue;
        }
        let positions = primitive
            .get(&Semantic::Positions)
            .ok_or_else(|| builder.invalid(format!("{what} has no POSITION attribute")))?;
        let positions = read_positions(&positions, buffers).map_err(|e| builder.invalid(format!("{what}: {e}")))?;
        let indices = match primitive.indices() {
            Some(accessor) => read_indices(&accessor, buffers).map_err(|e| builder.invalid(format!("{what}: {e}")))?,
            None => (0..positions.len() as u32).collect(),
        };
        let meshes = builder.add_geometry(&what, positions, triangle_list(mode, indices))?;
        parts.push((meshes, primitive.material().index().map_or(default_material, |m| m as u32)));
    }
    Ok(parts)
}

/// `indices` of a triangle list, strip or fan as a triangle list.
fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
    let corners = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..corners)
            .flat_map(|i| match i % 2 {
                0 => [indices[i], indices[i + 1], indices[i + 2]],
                _ => [indices[i + 1], indices[i], indices[i + 2]],
            })
            .collect(),
        Mode::TriangleFan => (0..corners).flat_map(|i| [indices[0], indices[i + 1], indices[i + 2]]).collect(),
        _ => {
            let mut list = indices;
            list.truncate(list.len() / 3 * 3);
            list
        }
    }
}

/// Most elements that the accessors of a file without a buffer view (sparse
/// on a base of zeros) may have together. Their counts are the only sizes
/// taken from a file without bytes behind them, so they are capped: 2^22
/// elements, 48 MiB of positions.
const MAX_ZERO_ELEMENTS: usize = 1 << 22;

/// The elements of `accessor`, each decoded by `decode` from its
/// `accessor.size()` bytes: read from its buffer view, or `zero` for each
/// where it has none, then overridden by its sparse substitutions (glTF 2.0,
/// section 3.6.2.3). Every byte range and sparse index is checked.
pub(super) fn read_accessor<T: Copy>(
    accessor: &Accessor,
    buffers: &Buffers,
    zero: T,
    decode: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, String> {
    let a = accessor.index();
    let (count, size) = (accessor.count(), accessor.size());
    let mut values: Vec<T> = match accessor.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(size);
            if stride < size {
                return Err(format!(
                    "buffer view {} has a stride of {stride} bytes, less than its {size}-byte elements",
                    view.index()
                ));
            }
            strided(&view, &buffers.bytes, accessor.offset(), count, size, stride)
                .map_err(|e| format!("accessor {a} {e}"))?
                .map(&decode)
                .collect()
        }
        None => {
            let left = buffers.zeros_left.get();
            if count > left {
                return Err(format!(
                    "accessor {a} has no buffer view and claims {count} elements of zeros; a file may fill at most \
                     {MAX_ZERO_ELEMENTS} elements without bytes behind them ({left} left)"
                ));
            }
            buffers.zeros_left.set(left - count);
            vec![zero; count]
        }
    };
    if let Some(sparse) = accessor.sparse() {
        let substitutions = sparse.count();
        if substitutions > count {
            return Err(format!("accessor {a} has a sparse count of {substitutions}, more than its {count} elements"));
        }
        let indices = sparse.indices();
        let (index_size, index): (usize, fn(&[u8]) -> u32) = match indices.index_type() {
            IndexType::U8 => (1, unsigned::<1>),
            IndexType::U16 => (2, unsigned::<2>),
            IndexType::U32 => (4, unsigned::<4>),
        };
        let indices = strided(&indices.view(), &buffers.bytes, indices.offset(), substitutions, index_size, index_size)
            .map_err(|e| format!("accessor {a}: its sparse indices {e}"))?;
        let substitutes = sparse.values();
        let substitutes = strided(&substitutes.view(), &buffers.bytes, substitutes.offset(), substitutions, size, size)
            .map_err(|e| format!("accessor {a}: its sparse values {e}"))?;
        let mut previous = None;
        for (k, (index, value)) in indices.map(index).zip(substitutes).enumerate() {
            let i = index as usize;
            if i >= count {
                return Err(format!(
                    "accessor {a}: sparse index {index} (substitution {k}) is out of range: the accessor has {count} \
                     elements"
                ));
            }
            if previous.is_some_and(|p| i <= p) {
                return Err(format!(
                    "accessor {a}: sparse index {index} (substitution {k}) does not increase on the one before; \
                     sparse indices must strictly increase"
                ));
            }
            previous = Some(i);
            values[i] = decode(value);
        }
    }
    Ok(values)
}

/// `count` elements of `size` bytes, `stride` bytes apart, from byte `offset`
/// of buffer `view`; the error says what does not fit (to follow the name of
/// what is read, "accessor 3 ...").
fn strided<'b>(
    view: &gltf::buffer::View,
    buffers: &'b [Cow<[u8]>],
    offset: usize,
    count: usize,
    size: usize,
    stride: usize,
) -> Result<impl Iterator<Item = &'b [u8]> + 'b, String> {
    let buffer = &buffers[view.buffer().index()];
    let view_bytes =
        view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end)).ok_or_else(|| {
            format!(
                "uses buffer view {} (bytes {} + {}), which lies outside buffer {} of {} bytes",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            )
        })?;
    let needed = count
        .checked_sub(1)
        .map_or(Some(0), |last| last.checked_mul(stride).and_then(|n| n.checked_add(size)))
        .and_then(|n| n.checked_add(offset));
    match needed {
        // `count` chunks: all but the last `stride` bytes, the last `size`.
        Some(n) if n <= view_bytes.len() => Ok(view_bytes[offset..n].chunks(stride).map(move |c| &c[..size])),
        _ => Err(format!(
            "reads {count} elements of {size} bytes from byte {offset} but buffer view {} has only {} bytes",
            view.index(),
            view_bytes.len()
        )),
    }
}

/// A little-endian unsigned integer of `N` bytes (1, 2 or 4: glTF index
/// types), a function per size so that reading indices inlines it.
fn unsigned<const N: usize>(bytes: &[u8]) -> u32 {
    let mut word = [0; 4];
    word[..N].copy_from_slice(&bytes[..N]);
    u32::from_le_bytes(word)
}

/// Positions: an accessor of float VEC3.
fn read_positions(accessor: &Accessor, buffers: &Buffers) -> Result<Vec<Vec3>, String> {
    expect_f32(accessor, Dimensions::Vec3, "position accessor")?;
    read_accessor(accessor, buffers, Vec3::ZERO, |e| Vec3::new(float(e), float(&e[4..]), float(&e[8..])))
}

/// Fails unless `accessor` holds `F32` elements of `dimensions`; `what`
/// names the accessor's use in the message.
pub(super) fn expect_f32(accessor: &Accessor, dimensions: Dimensions, what: &str) -> Result<(), String> {
    if accessor.data_type() == DataType::F32 && accessor.dimensions() == dimensions {
        return Ok(());
    }
    Err(format!(
        "{what} {} holds {:?} {:?}, not F32 {dimensions:?}",
        accessor.index(),
        accessor.dimensions(),
        accessor.data_type()
    ))
}

/// A little-endian float from the first four of `bytes`.
pub(super) fn float(bytes: &[u8]) -> f32 {
    f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

/// Indices: an accessor of unsigned 8-, 16- or 32-bit scalars.
fn read_indices(accessor: &Accessor, buffers: &Buffers) -> Result<Vec<u32>, String> {
    match (accessor.dimensions(), accessor.data_type()) {
        (Dimensions::Scalar, DataType::U8) => read_accessor(accessor, buffers, 0, unsigned::<1>),
        (Dimensions::Scalar, DataType::U16) => read_accessor(accessor, buffers, 0, unsigned::<2>),
        (Dimensions::Scalar, DataType::U32) => read_accessor(accessor, buffers, 0, unsigned::<4>),
        (dims, kind) => {
            Err(format!("index accessor {} holds {dims:?} {kind:?}, not unsigned scalars", accessor.index()))
        }
    }
}
