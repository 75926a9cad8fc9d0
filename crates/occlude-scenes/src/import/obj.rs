//! Wavefront OBJ import with `tobj`: one mesh and one instance per object or
//! group, polygons triangulated; points and lines are ignored.

use super::{Builder, LoadError};
use glam::{Mat4, Vec3};

/// Imports OBJ `bytes`, the file of `builder`, into it. Material ids are the
/// indices of the materials of its `.mtl` files (looked for beside the file);
/// objects without a known material share the id after the last. A `.mtl`
/// that cannot be read is a warning (every object then gets that default id),
/// not an error. Negative (relative) face indices are legal; indices outside
/// the vertices are an error.
pub(super) fn import(builder: &mut Builder, mut bytes: &[u8]) -> Result<(), LoadError> {
    let dir = builder.path.parent().map(std::path::Path::to_path_buf).unwrap_or_default();
    let options = tobj::LoadOptions { triangulate: true, ignore_points: true, ignore_lines: true, single_index: false };
    let (models, materials) = tobj::load_obj_buf(&mut bytes, &options, |mtl| tobj::load_mtl(dir.join(mtl)))
        .map_err(|e| builder.malformed("OBJ", e.to_string()))?;
    let materials = materials.unwrap_or_else(|e| {
        builder.warn(format_args!("its materials cannot be loaded ({e}); every object gets one default material"));
        Vec::new()
    });
    let default_material = materials.len();
    for model in models {
        let what = format!("object '{}'", model.name);
        let positions = model.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let meshes = builder.add_geometry(&what, positions, model.mesh.indices)?;
        let material = model.mesh.material_id.filter(|&m| m < default_material).unwrap_or(default_material);
        builder.place(&what, &meshes, Mat4::IDENTITY, material as u32)?;
    }
    Ok(())
}
