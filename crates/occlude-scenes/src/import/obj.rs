//! Wavefront OBJ import with `tobj`: one mesh and one instance per object or
//! group, polygons triangulated; points and lines are ignored.

use super::{obj_indices, referenced, Builder, LoadError, MAX_MATERIAL_BYTES};
use glam::{Mat4, Vec3};
use std::path::Path;

/// Imports OBJ `bytes`, the file of `builder`, into it. Material ids are the
/// indices of the materials of its `.mtl` files (looked for inside the
/// model's folder, see `referenced`, at most [`MAX_MATERIAL_BYTES`] each);
/// objects without a known material share the id after the last. A `.mtl`
/// that cannot be read is a warning (every object then gets that default id),
/// not an error. Negative (relative) face indices are legal; indices outside
/// the elements of the file are an error, found before `tobj` reads them
/// (see `obj_indices`).
pub(super) fn import(builder: &mut Builder, bytes: &[u8]) -> Result<(), LoadError> {
    let text =
        std::str::from_utf8(bytes).map_err(|e| builder.malformed("OBJ", format!("it is not UTF-8 text: {e}")))?;
    obj_indices::check(text).map_err(|e| builder.malformed("OBJ", e))?;
    let options = tobj::LoadOptions { triangulate: true, ignore_points: true, ignore_lines: true, single_index: false };
    let model = builder.path.clone();
    let refused = std::cell::RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |mtl| {
        load_materials(&model, mtl, &mut refused.borrow_mut())
    })
    .map_err(|e| builder.malformed("OBJ", e.to_string()))?;
    let refused = refused.into_inner();
    let materials = materials.unwrap_or_else(|e| {
        let why = if refused.is_empty() { e.to_string() } else { refused.join("; ") };
        builder.warn(format_args!("its materials cannot be loaded ({why}); every object gets one default material"));
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

/// The materials of the library `mtl` an OBJ file `model` names, read inside
/// the model's folder. Why a library is refused or cannot be read is added
/// to `refused` (`tobj` keeps only its own error kind).
fn load_materials(model: &Path, mtl: &Path, refused: &mut Vec<String>) -> tobj::MTLLoadResult {
    let reference = mtl.to_string_lossy();
    let why = match referenced::read_up_to(model, &reference, MAX_MATERIAL_BYTES) {
        Ok((bytes, false)) => return tobj::load_mtl_buf(&mut bytes.as_slice()),
        Ok((_, true)) => {
            format!("{reference} is larger than the {MAX_MATERIAL_BYTES} bytes read of a material library")
        }
        Err(referenced::Refused::Reference(why)) => why,
        Err(referenced::Refused::Unreadable(file, e)) => format!("cannot read {}: {e}", file.display()),
    };
    refused.push(why);
    Err(tobj::LoadError::OpenFileFailed)
}
