//! Writing a [`Scene`] as binary glTF 2.0 (GLB), so that generated scenes can
//! go through the importer: the building of the import tests and benchmarks
//! ([`crate::building`]), the large model of the import-speed benchmark and
//! the seeds of the importer fuzzers, or any procedural scene opened in
//! another tool.
//!
//! Each mesh becomes one position and one index accessor; each (mesh,
//! material) pair that instances use becomes one glTF mesh sharing them; each
//! instance becomes one root node with its transform as a matrix. Importing
//! the file again gives the same meshes, instances, transforms and materials
//! in the same order (only the walkthrough is not stored).

use occlude_core::Scene;
use serde_json::{json, Value};
use std::collections::HashMap;

/// GLB chunk type of the JSON chunk (`JSON`, little endian).
const CHUNK_JSON: &[u8; 4] = b"JSON";
/// GLB chunk type of the binary chunk.
const CHUNK_BIN: &[u8; 4] = b"BIN\0";
/// glTF component type of 32-bit floats.
const FLOAT: u32 = 5126;
/// glTF component type of 32-bit unsigned integers.
const UNSIGNED_INT: u32 = 5125;
/// glTF buffer-view target of vertex attributes.
const ARRAY_BUFFER: u32 = 34962;
/// glTF buffer-view target of indices.
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// `scene` as the bytes of a GLB file (see the module documentation).
pub fn glb(scene: &Scene) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    for mesh in &scene.meshes {
        let mut view = |bytes: Vec<u8>, target: u32| {
            views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target}));
            bin.extend_from_slice(&bytes);
            views.len() - 1
        };
        let positions =
            view(mesh.positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect(), ARRAY_BUFFER);
        let indices = view(mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect(), ELEMENT_ARRAY_BUFFER);
        accessors.push(json!({
            "bufferView": positions, "componentType": FLOAT, "count": mesh.positions.len(), "type": "VEC3",
            "min": mesh.bounds.min.to_array(), "max": mesh.bounds.max.to_array(),
        }));
        accessors.push(json!({
            "bufferView": indices, "componentType": UNSIGNED_INT, "count": mesh.indices.len(), "type": "SCALAR",
        }));
    }
    let mut meshes = Vec::new();
    let mut mesh_of: HashMap<(u32, u32), usize> = HashMap::new();
    let nodes: Vec<Value> = scene
        .instances
        .iter()
        .map(|instance| {
            let key = (instance.mesh, instance.material);
            let mesh = *mesh_of.entry(key).or_insert_with(|| {
                let (m, material) = (instance.mesh as usize, instance.material);
                meshes.push(json!({"primitives": [{
                    "attributes": {"POSITION": 2 * m}, "indices": 2 * m + 1, "material": material,
                }]}));
                meshes.len() - 1
            });
            json!({"mesh": mesh, "matrix": instance.transform.to_cols_array()})
        })
        .collect();
    let material_count = scene.instances.iter().map(|i| i.material + 1).max().unwrap_or(0).max(scene.material_count);
    let materials: Vec<Value> = (0..material_count).map(|m| json!({"name": format!("material {m}")})).collect();
    let document = json!({
        "asset": {"version": "2.0", "generator": "occlude-scenes export"},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    container(&serde_json::to_vec(&document).expect("a JSON value serializes"), &bin)
}

/// The GLB file of the glTF JSON document `json` and its binary buffer `bin`
/// (GLB header, JSON chunk padded with spaces, binary chunk padded with
/// zeros). Also for tests that write documents [`glb`] would not (broken ones).
///
/// # Panics
///
/// If the file would exceed the 4 GiB that GLB lengths can hold.
pub fn container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let padded = |chunk: &[u8], pad: u8| {
        let mut chunk = chunk.to_vec();
        chunk.resize(chunk.len().next_multiple_of(4), pad);
        chunk
    };
    let (json, bin) = (padded(json, b' '), padded(bin, 0));
    let length = 12 + 8 + json.len() + 8 + bin.len();
    let word = |n: usize| u32::try_from(n).expect("GLB files are at most 4 GiB").to_le_bytes();
    let mut out = Vec::with_capacity(length);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&word(length));
    for (kind, chunk) in [(CHUNK_JSON, &json), (CHUNK_BIN, &bin)] {
        out.extend_from_slice(&word(chunk.len()));
        out.extend_from_slice(kind);
        out.extend_from_slice(chunk);
    }
    out
}
