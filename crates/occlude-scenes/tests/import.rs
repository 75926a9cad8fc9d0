//! Importing glTF and OBJ models that the tests write themselves: counts,
//! world transforms, instancing, materials, splitting, automatic paths, and a
//! clear error naming the file for every kind of bad input.

use base64::Engine;
use glam::Vec3;
use occlude_core::Aabb;
use occlude_scenes::import::{import, Imported, ModelFormat};
use occlude_scenes::{load, AutoPath, ImportOptions, LoadError, Size};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Builds a glTF document and its one binary buffer.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    roots: Vec<usize>,
    materials: usize,
}

/// Corners of the cube `[-0.5, 0.5]³` and its 12 triangles.
const CUBE_POSITIONS: [[f32; 3]; 8] = [
    [-0.5, -0.5, -0.5],
    [0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, -0.5],
    [-0.5, -0.5, 0.5],
    [0.5, -0.5, 0.5],
    [0.5, 0.5, 0.5],
    [-0.5, 0.5, 0.5],
];
const CUBE_INDICES: [u16; 36] =
    [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5];

impl Gltf {
    /// Appends `bytes` as a buffer view (4-byte aligned) and returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// Adds an accessor and returns its index.
    fn accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A float VEC3 accessor over `positions`.
    fn positions(&mut self, positions: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = positions.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        // glTF requires the bounds of positions; non-finite values (for the
        // bad-input tests) are left out, as JSON cannot hold them.
        let finite = positions.iter().map(|&p| Vec3::from(p)).filter(|p| p.is_finite());
        let (min, max) = finite.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
        self.accessor(json!({"bufferView": view, "componentType": 5126, "count": positions.len(), "type": "VEC3",
                             "min": min.to_array(), "max": max.to_array()}))
    }

    /// An unsigned-short SCALAR accessor over `indices`.
    fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessor(json!({"bufferView": view, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}))
    }

    /// A mesh of `primitives`; returns its index.
    fn mesh(&mut self, primitives: Vec<Value>) -> usize {
        self.meshes.push(json!({ "primitives": primitives }));
        self.meshes.len() - 1
    }

    /// A triangle primitive over new accessors, with an optional material.
    fn primitive(&mut self, positions: &[[f32; 3]], indices: &[u16], material: Option<usize>) -> Value {
        let (p, i) = (self.positions(positions), self.indices(indices));
        self.materials = self.materials.max(material.map_or(0, |m| m + 1));
        let mut primitive = json!({"attributes": {"POSITION": p}, "indices": i});
        if let Some(m) = material {
            primitive["material"] = json!(m);
        }
        primitive
    }

    /// The cube as a one-primitive mesh.
    fn cube(&mut self, material: Option<usize>) -> usize {
        let primitive = self.primitive(&CUBE_POSITIONS, &CUBE_INDICES, material);
        self.mesh(vec![primitive])
    }

    /// Adds a node and returns its index.
    fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Adds a root node of the scene.
    fn root(&mut self, node: Value) -> usize {
        let n = self.node(node);
        self.roots.push(n);
        n
    }

    /// The document, its buffer at `uri` (none: the GLB binary chunk).
    fn document(&self, uri: Option<String>) -> Value {
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        let materials: Vec<Value> = (0..self.materials).map(|m| json!({ "name": format!("m{m}") })).collect();
        json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": self.roots}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [buffer],
        })
    }

    /// Writes `dir/name` with the buffer as a base64 data URI.
    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        write_json(dir, name, &self.document(Some(format!("data:application/octet-stream;base64,{data}"))))
    }

    /// Writes `dir/name` with the buffer in the file `dir/bin`.
    fn write_with_bin(&self, dir: &Path, name: &str, bin: &str) -> PathBuf {
        std::fs::write(dir.join(bin), &self.bin).unwrap();
        write_json(dir, name, &self.document(Some(bin.to_string())))
    }

    /// The model as GLB bytes.
    fn glb(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(&self.document(None)).unwrap();
        json.resize(json.len().next_multiple_of(4), b' ');
        let mut bin = self.bin.clone();
        bin.resize(bin.len().next_multiple_of(4), 0);
        let length = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(length);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(length as u32).to_le_bytes());
        for (kind, chunk) in [(b"JSON", &json), (b"BIN\0", &bin)] {
            out.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
            out.extend_from_slice(kind);
            out.extend_from_slice(chunk);
        }
        out
    }
}

fn write_json(dir: &Path, name: &str, document: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec_pretty(document).unwrap()).unwrap();
    path
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A node placing a mesh scaled to and moved onto `min..max`.
fn placed(mesh: usize, min: [f32; 3], max: [f32; 3]) -> Value {
    let (min, max) = (Vec3::from(min), Vec3::from(max));
    json!({"mesh": mesh, "translation": ((min + max) / 2.0).to_array(), "scale": (max - min).to_array()})
}

/// A 10 x 3 x 10 m room: a floor (no material), four walls (material 0) and
/// three boxes (material 1). Three meshes, eight instances.
fn room() -> Gltf {
    let mut g = Gltf::default();
    let (floor, wall, crate_) = (g.cube(None), g.cube(Some(0)), g.cube(Some(1)));
    g.root(placed(floor, [0.0, -0.1, 0.0], [10.0, 0.0, 10.0]));
    g.root(placed(wall, [0.0, 0.0, 0.0], [0.2, 3.0, 10.0]));
    g.root(placed(wall, [9.8, 0.0, 0.0], [10.0, 3.0, 10.0]));
    g.root(placed(wall, [0.0, 0.0, 0.0], [10.0, 3.0, 0.2]));
    g.root(placed(wall, [0.0, 0.0, 9.8], [10.0, 3.0, 10.0]));
    for x in [2.0, 5.0, 8.0] {
        g.root(placed(crate_, [x - 0.5, 0.0, 4.5], [x + 0.5, 1.0, 5.5]));
    }
    g
}

fn options(split_triangles: usize, auto_path: AutoPath) -> ImportOptions {
    ImportOptions { split_triangles, auto_path }
}

fn import_file(path: &Path, options: ImportOptions) -> Imported {
    let format = match path.extension().unwrap().to_str().unwrap() {
        "gltf" => ModelFormat::Gltf,
        "glb" => ModelFormat::Glb,
        _ => ModelFormat::Obj,
    };
    import(path, format, &options).unwrap_or_else(|e| panic!("{} should import: {e}", path.display()))
}

fn assert_close(a: Aabb, b: Aabb) {
    assert!((a.min - b.min).abs().max_element() < 1e-5 && (a.max - b.max).abs().max_element() < 1e-5, "{a:?} != {b:?}");
}

fn room_bounds() -> Aabb {
    Aabb::new(Vec3::new(0.0, -0.1, 0.0), Vec3::new(10.0, 3.0, 10.0))
}

#[test]
fn room_of_boxes_gives_its_meshes_instances_materials_and_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let path = room().write(dir.path(), "room.gltf");
    let scene = load(path.to_str().unwrap(), Size::Small, 1, &ImportOptions::default()).unwrap();
    assert_eq!(scene.name, "room.gltf");
    assert_eq!(scene.meshes.len(), 3);
    assert_eq!(scene.instances.len(), 8);
    assert_eq!(scene.triangle_count(), 8 * 12);
    assert_eq!(scene.material_count, 3, "two glTF materials and the default one");
    let materials: Vec<u32> = scene.instances.iter().map(|i| i.material).collect();
    assert_eq!(materials, [2, 0, 0, 0, 0, 1, 1, 1]);
    assert_close(scene.bounds(), room_bounds());
    assert!(!scene.path.keyframes.is_empty());
}

#[test]
fn glb_and_external_buffer_give_the_same_scene_as_a_data_uri() {
    let dir = tempfile::tempdir().unwrap();
    let model = room();
    let reference = import_file(&model.write(dir.path(), "a.gltf"), ImportOptions::default()).scene;
    for path in [model.write_with_bin(dir.path(), "b.gltf", "b.bin"), write(dir.path(), "c.glb", model.glb())] {
        let scene = import_file(&path, ImportOptions::default()).scene;
        assert_eq!(scene.instances.len(), reference.instances.len());
        assert_eq!(scene.triangle_count(), reference.triangle_count());
        assert_eq!(scene.bounds(), reference.bounds());
        assert_eq!(scene.path, reference.path);
    }
}

#[test]
fn nested_nodes_compose_their_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    // Grandchild: a matrix moving by (0, 0, 3); child: up 1 with the cube;
    // parent: at x = 10, scaled 2.
    let grandchild = g.node(json!({"mesh": cube, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,3,1]}));
    let child = g.node(json!({"mesh": cube, "translation": [0, 1, 0], "children": [grandchild]}));
    g.root(json!({"translation": [10, 0, 0], "scale": [2, 2, 2], "children": [child]}));
    let scene = import_file(&g.write(dir.path(), "nested.gltf"), ImportOptions::default()).scene;
    assert_eq!(scene.instances.len(), 2);
    assert_close(scene.instances[0].bounds, Aabb::new(Vec3::new(9.0, 1.0, -1.0), Vec3::new(11.0, 3.0, 1.0)));
    assert_close(scene.instances[1].bounds, Aabb::new(Vec3::new(9.0, 1.0, 5.0), Vec3::new(11.0, 3.0, 7.0)));
}

#[test]
fn a_mesh_used_by_several_nodes_is_instanced() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(Some(0));
    for x in 0..5 {
        g.root(json!({"mesh": cube, "translation": [x as f32 * 2.0, 0, 0]}));
    }
    let scene = import_file(&g.write(dir.path(), "row.gltf"), ImportOptions::default()).scene;
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.instances.len(), 5);
    assert_eq!(scene.unique_triangle_count(), 12);
    assert_eq!(scene.triangle_count(), 60);
    assert_close(scene.bounds(), Aabb::new(Vec3::splat(-0.5), Vec3::new(8.5, 0.5, 0.5)));
}

#[test]
fn strips_become_triangles_and_lines_are_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let mut strip = g.primitive(&quad, &[0, 1, 2, 3], None);
    strip["mode"] = json!(5);
    let mut lines = g.primitive(&quad, &[0, 1, 2, 3], None);
    lines["mode"] = json!(1);
    let mesh = g.mesh(vec![strip, lines]);
    g.root(json!({ "mesh": mesh }));
    let imported = import_file(&g.write(dir.path(), "modes.gltf"), ImportOptions::default());
    assert_eq!(imported.scene.triangle_count(), 2);
    assert_eq!(imported.scene.meshes[0].indices, [0, 1, 2, 2, 1, 3]);
    assert_eq!(imported.warnings.len(), 1);
    assert!(imported.warnings[0].contains("modes.gltf") && imported.warnings[0].contains("primitive 1"));
}

#[test]
fn large_meshes_are_split_into_several_instanced_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({ "mesh": cube }));
    g.root(json!({"mesh": cube, "translation": [3, 0, 0]}));
    let path = g.write(dir.path(), "split.gltf");
    let whole = import_file(&path, options(0, AutoPath::Orbit)).scene;
    assert_eq!((whole.meshes.len(), whole.instances.len()), (1, 2));
    let split = import_file(&path, options(4, AutoPath::Orbit)).scene;
    assert_eq!(split.meshes.len(), 4, "12 triangles split down to at most 4");
    assert_eq!(split.instances.len(), 8, "every placement of the mesh places every part");
    assert!(split.meshes.iter().all(|m| m.triangle_count() <= 4));
    assert_eq!(split.triangle_count(), whole.triangle_count());
    assert_eq!(split.bounds(), whole.bounds());
}

#[test]
fn walk_path_stays_at_eye_height_clear_of_the_room() {
    let dir = tempfile::tempdir().unwrap();
    let imported = import_file(&room().write(dir.path(), "room.gltf"), options(0, AutoPath::Walk));
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let scene = &imported.scene;
    for k in &scene.path.keyframes {
        assert!((k.position.y - (-0.1 + 1.7)).abs() < 1e-4);
        let eye = Aabb::new(k.position - Vec3::splat(0.24), k.position + Vec3::splat(0.24));
        assert!(scene.instances.iter().all(|i| !i.bounds.overlaps(&eye)), "{:?} touches an object", k.position);
        assert!(room_bounds().contains_point(k.position), "the walk stays inside the room");
    }
}

#[test]
fn walk_falls_back_to_orbit_with_a_warning_when_there_is_no_free_space() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({"mesh": cube, "scale": [10, 10, 10]}));
    let path = g.write(dir.path(), "block.gltf");
    let walked = import_file(&path, options(0, AutoPath::Walk));
    assert_eq!(walked.warnings.len(), 1);
    assert!(walked.warnings[0].contains("block.gltf") && walked.warnings[0].contains("orbit"));
    assert_eq!(walked.scene.path, import_file(&path, options(0, AutoPath::Orbit)).scene.path);
    for k in &walked.scene.path.keyframes {
        assert!(!walked.scene.bounds().contains_point(k.position));
    }
}

#[test]
fn obj_objects_materials_and_relative_indices() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "two.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
    let obj = "mtllib two.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
        o red_quad\nusemtl red\nf 1 2 3 4\n\
        v 0 0 2\nv 1 0 2\nv 1 1 2\n\
        o blue_tri\nusemtl blue\nf -3 -2 -1\n\
        o plain\nusemtl none\nf 1 2 5\n";
    let imported = import_file(&write(dir.path(), "shapes.obj", obj), ImportOptions::default());
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let scene = imported.scene;
    assert_eq!(scene.instances.len(), 3);
    assert_eq!(scene.triangle_count(), 4, "the quad is triangulated");
    let materials: Vec<u32> = scene.instances.iter().map(|i| i.material).collect();
    assert_eq!(materials, [0, 1, 2]);
    assert_eq!(scene.material_count, 3);
    assert_close(scene.instances[1].bounds, Aabb::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0)));
}

#[test]
fn obj_without_its_mtl_warns_and_uses_one_material() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "lost.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    let imported = import_file(&path, ImportOptions::default());
    assert_eq!(imported.warnings.len(), 1);
    assert!(imported.warnings[0].contains("lost.obj"));
    assert_eq!(imported.scene.material_count, 1);
}

#[test]
fn procedural_names_still_generate() {
    let scene = load("city", Size::Small, 1, &ImportOptions::default()).unwrap();
    assert_eq!(scene.name, "city");
}

/// The error of loading `path`, checked to name the file.
fn error(path: &Path) -> (LoadError, String) {
    let e = load(path.to_str().unwrap(), Size::Small, 1, &ImportOptions::default()).expect_err("bad input");
    let message = e.to_string();
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(message.contains(name), "the error should name {name}: {message}");
    (e, message)
}

#[test]
fn truncated_glb_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let glb = room().glb();
    let (e, message) = error(&write(dir.path(), "cut.glb", &glb[..glb.len() / 2]));
    assert!(matches!(e, LoadError::Malformed { format: "GLB", .. }), "{e:?}");
    assert!(message.contains("truncated"), "{message}");
    let (_, message) = error(&write(dir.path(), "stub.glb", &glb[..7]));
    assert!(message.contains("12-byte GLB header"), "{message}");
}

#[test]
fn glb_header_claiming_2_gb_is_an_error_without_allocating_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut glb = room().glb();
    glb[8..12].copy_from_slice(&2_000_000_000u32.to_le_bytes());
    let (_, message) = error(&write(dir.path(), "huge.glb", &glb));
    assert!(message.contains("2000000000"), "{message}");
    // The same claim on a chunk: the file length is right, the chunk's is not.
    let mut glb = room().glb();
    glb[12..16].copy_from_slice(&2_000_000_000u32.to_le_bytes());
    let (_, message) = error(&write(dir.path(), "huge_chunk.glb", &glb));
    assert!(message.contains("claims 2000000000 bytes"), "{message}");
}

#[test]
fn gltf_with_a_missing_buffer_file_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = room().write_with_bin(dir.path(), "room.gltf", "room.bin");
    std::fs::remove_file(dir.path().join("room.bin")).unwrap();
    let (e, message) = error(&path);
    assert!(matches!(e, LoadError::MissingFile { .. }), "{e:?}");
    assert!(message.contains("room.bin"), "{message}");
}

#[test]
fn index_out_of_range_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let primitive = g.primitive(&CUBE_POSITIONS, &[0, 1, 8], None);
    let mesh = g.mesh(vec![primitive]);
    g.root(json!({ "mesh": mesh }));
    let (e, message) = error(&g.write(dir.path(), "index.gltf"));
    assert!(matches!(e, LoadError::Invalid { .. }), "{e:?}");
    assert!(message.contains("index 8 is out of range"), "{message}");
}

#[test]
fn accessor_past_its_buffer_view_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = room();
    g.accessors[0]["count"] = json!(1_000_000);
    let (_, message) = error(&g.write(dir.path(), "overrun.gltf"));
    assert!(message.contains("accessor 0 reads 1000000 elements"), "{message}");
}

#[test]
fn nan_or_infinite_positions_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bad) in [("nan.gltf", f32::NAN), ("inf.gltf", f32::INFINITY)] {
        let mut g = Gltf::default();
        let primitive = g.primitive(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, bad, 0.0]], &[0, 1, 2], None);
        let mesh = g.mesh(vec![primitive]);
        g.root(json!({ "mesh": mesh }));
        let (_, message) = error(&g.write(dir.path(), name));
        assert!(message.contains("vertex 2 has a non-finite position"), "{message}");
    }
    let (_, message) = error(&write(dir.path(), "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n"));
    assert!(message.contains("non-finite"), "{message}");
}

#[test]
fn empty_scene_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (e, _) = error(&Gltf::default().write(dir.path(), "empty.gltf"));
    assert!(matches!(e, LoadError::Empty { .. }), "{e:?}");
    let (e, _) = error(&write(dir.path(), "empty.obj", "# nothing\nv 0 0 0\n"));
    assert!(matches!(e, LoadError::Empty { .. }), "{e:?}");
}

#[test]
fn node_cycle_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({"mesh": cube, "children": [1]}));
    g.node(json!({"mesh": cube, "children": [0]}));
    let (_, message) = error(&g.write(dir.path(), "cycle.gltf"));
    assert!(message.contains("not a tree"), "{message}");
}

#[test]
fn invalid_json_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (e, _) = error(&write(dir.path(), "broken.gltf", "{\"asset\": "));
    assert!(matches!(e, LoadError::Malformed { format: "glTF", .. }), "{e:?}");
}

#[test]
fn obj_indices_out_of_range_are_an_error_but_relative_ones_are_legal() {
    let dir = tempfile::tempdir().unwrap();
    let vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let ok = import_file(&write(dir.path(), "relative.obj", format!("{vertices}f -3 -2 -1\n")), Default::default());
    assert_eq!(ok.scene.triangle_count(), 1);
    for (name, face) in [("minus.obj", "f -1 -2 -9\n"), ("past.obj", "f 1 2 7\n"), ("zero.obj", "f 0 1 2\n")] {
        let (e, message) = error(&write(dir.path(), name, format!("{vertices}{face}")));
        assert!(matches!(e, LoadError::Malformed { format: "OBJ", .. }), "{e:?}");
        assert!(message.contains("out of bounds"), "{message}");
    }
}

#[test]
fn unknown_names_and_missing_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (e, message) = error(&write(dir.path(), "model.fbx", "x"));
    assert!(matches!(e, LoadError::UnknownScene { .. }), "{e:?}");
    assert!(message.contains("teapots") && message.contains(".glb") && message.contains(".obj"), "{message}");
    let (e, _) = error(&dir.path().join("absent.glb"));
    assert!(matches!(e, LoadError::Io { .. }), "{e:?}");
}
