//! glTF 2.0 import. The `gltf` crate parses and validates the JSON document;
//! GLB chunks, buffers and accessors are read here, with every byte range
//! checked against the bytes really present.

use super::{Builder, LoadError};
use base64::Engine;
use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::{Accessor, Document, Semantic};
use std::collections::hash_map::{Entry, HashMap};

/// GLB chunk type of the JSON chunk (`JSON`, little endian).
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// GLB chunk type of the binary chunk (`BIN\0`, little endian).
const CHUNK_BIN: u32 = 0x004E_4942;

/// Imports the glTF (`binary`: GLB) file of `builder` into it: the default
/// scene (else the first, else every root node), its node tree flattened into
/// instances with world transforms. A glTF mesh used by several nodes is read
/// once and instanced. Material ids are glTF material indices; primitives
/// without a material share the id after the last. Triangle strips and fans
/// become triangle lists; points and lines are skipped with a warning.
pub(super) fn import(builder: &mut Builder, binary: bool) -> Result<(), LoadError> {
    let bytes = std::fs::read(&builder.path).map_err(|reason| LoadError::Io { path: builder.path.clone(), reason })?;
    let (json, blob) = if binary { glb_chunks(builder, &bytes)? } else { (&bytes[..], None) };
    let format = if binary { "GLB" } else { "glTF" };
    let root = gltf::json::Root::from_slice(json).map_err(|e| builder.malformed(format, e.to_string()))?;
    let document = Document::from_json(root).map_err(|e| builder.malformed(format, e.to_string()))?;
    let buffers = load_buffers(builder, &document, blob)?;
    let default_material = document.materials().len() as u32;

    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            document.nodes().flat_map(|n| n.children()).for_each(|c| is_child[c.index()] = true);
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut visited = vec![false; document.nodes().len()];
    let mut meshes: HashMap<usize, Vec<(Vec<u32>, u32)>> = HashMap::new();
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(
                builder.invalid(format!("node {} is reached twice: the node hierarchy is not a tree", node.index()))
            );
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(builder.invalid(format!("node {} has a non-finite transform", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            let parts = match meshes.entry(mesh.index()) {
                Entry::Occupied(entry) => entry.into_mut(),
                Entry::Vacant(entry) => entry.insert(read_mesh(builder, &mesh, &buffers, default_material)?),
            };
            for (parts, material) in parts.iter() {
                builder.place(parts, world, *material);
            }
        }
        stack.extend(node.children().collect::<Vec<_>>().into_iter().rev().map(|c| (c, world)));
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

/// The bytes of every buffer of `document`: the GLB binary chunk, a base64
/// data URI, or a file beside the model; each at least its declared length.
fn load_buffers(builder: &Builder, document: &Document, blob: Option<&[u8]>) -> Result<Vec<Vec<u8>>, LoadError> {
    document
        .buffers()
        .map(|buffer| {
            let i = buffer.index();
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .ok_or_else(|| {
                        builder.invalid(format!("buffer {i} refers to the GLB binary chunk, which is missing"))
                    })?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| builder.invalid(format!("buffer {i}: only base64 data URIs are supported")))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| builder.invalid(format!("buffer {i}: bad base64 data URI: {e}")))?
                }
                gltf::buffer::Source::Uri(uri) => {
                    let file = builder.path.parent().unwrap_or(std::path::Path::new("")).join(uri);
                    std::fs::read(&file).map_err(|reason| LoadError::MissingFile {
                        path: builder.path.clone(),
                        file,
                        reason,
                    })?
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
        .collect()
}

/// Reads every triangle primitive of `mesh` as meshes of `builder`, with its
/// material id.
fn read_mesh(
    builder: &mut Builder,
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
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

/// The elements of `accessor`: one byte slice per element, bounds checked.
fn elements<'b>(accessor: &Accessor, buffers: &'b [Vec<u8>]) -> Result<Vec<&'b [u8]>, String> {
    let a = accessor.index();
    if accessor.sparse().is_some() {
        return Err(format!("accessor {a} is sparse, which is not supported"));
    }
    let view = accessor.view().ok_or_else(|| format!("accessor {a} has no buffer view"))?;
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "buffer view {} has a stride of {stride} bytes, less than its {size}-byte elements",
            view.index()
        ));
    }
    let buffer = &buffers[view.buffer().index()];
    let view_bytes =
        view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end)).ok_or_else(|| {
            format!(
                "buffer view {} (bytes {} + {}) lies outside buffer {} of {} bytes",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            )
        })?;
    let count = accessor.count();
    let needed = count
        .checked_sub(1)
        .map_or(Some(0), |last| last.checked_mul(stride).and_then(|n| n.checked_add(size)))
        .and_then(|n| n.checked_add(accessor.offset()));
    match needed {
        Some(n) if n <= view_bytes.len() => {
            Ok((0..count).map(|i| &view_bytes[accessor.offset() + i * stride..][..size]).collect())
        }
        _ => Err(format!(
            "accessor {a} reads {count} elements of {size} bytes from byte {} but buffer view {} has only {} bytes",
            accessor.offset(),
            view.index(),
            view_bytes.len()
        )),
    }
}

/// Positions: an accessor of float VEC3.
fn read_positions(accessor: &Accessor, buffers: &[Vec<u8>]) -> Result<Vec<Vec3>, String> {
    if accessor.data_type() != DataType::F32 || accessor.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "position accessor {} holds {:?} {:?}, not F32 Vec3",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    let float = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    Ok(elements(accessor, buffers)?.into_iter().map(|e| Vec3::new(float(e), float(&e[4..]), float(&e[8..]))).collect())
}

/// Indices: an accessor of unsigned 8-, 16- or 32-bit scalars.
fn read_indices(accessor: &Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let read: fn(&[u8]) -> u32 = match (accessor.dimensions(), accessor.data_type()) {
        (Dimensions::Scalar, DataType::U8) => |b| b[0] as u32,
        (Dimensions::Scalar, DataType::U16) => |b| u16::from_le_bytes([b[0], b[1]]) as u32,
        (Dimensions::Scalar, DataType::U32) => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (dims, kind) => {
            return Err(format!("index accessor {} holds {dims:?} {kind:?}, not unsigned scalars", accessor.index()))
        }
    };
    Ok(elements(accessor, buffers)?.into_iter().map(read).collect())
}
