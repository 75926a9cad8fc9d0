//! The files a model refers to (glTF buffers, OBJ material libraries),
//! resolved inside the model's folder: a reference is a relative path with
//! no `..`, no root and no URI scheme, and it must name a regular file that
//! stays inside the folder once links are followed. A model therefore reads
//! only files beside it or below, never `/dev/zero`, `../../etc/passwd` or a
//! URL, and never more bytes than the caller allows.

use std::io;
use std::path::{Component, Path, PathBuf};

/// Why a reference was refused or could not be read.
pub(super) enum Refused {
    /// The reference itself is not allowed (the reason, naming it).
    Reference(String),
    /// The file it names cannot be read.
    Unreadable(PathBuf, io::Error),
}

/// The file `reference` names beside the model file `model`, refused unless
/// it stays inside the model's folder (see the module's rules).
pub(super) fn resolve(model: &Path, reference: &str) -> Result<PathBuf, Refused> {
    let refuse = |why: &str| Err(Refused::Reference(format!("'{reference}' {why}")));
    if has_scheme(reference) {
        return refuse("is a URL: only relative file paths beside the model (and glTF data: URIs) are read");
    }
    let relative = Path::new(reference);
    if reference.is_empty() || relative.as_os_str().is_empty() {
        return refuse("is empty");
    }
    if relative.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
        return refuse("leaves the model's folder: only relative paths without '..' are read");
    }
    let folder = match model.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let file = folder.join(relative);
    let unreadable = |e| Refused::Unreadable(file.clone(), e);
    let (real_folder, real_file) =
        (folder.canonicalize().map_err(unreadable)?, file.canonicalize().map_err(unreadable)?);
    if !real_file.starts_with(&real_folder) {
        return refuse("is a link that leaves the model's folder");
    }
    Ok(file)
}

/// Reads at most `limit` bytes of the file `reference` names beside
/// `model` ([`resolve`]), and whether it holds more.
pub(super) fn read_up_to(model: &Path, reference: &str, limit: u64) -> Result<(Vec<u8>, bool), Refused> {
    let file = resolve(model, reference)?;
    occlude_core::input_file::read_up_to(&file, limit).map_err(|e| Refused::Unreadable(file, e))
}

/// Whether `reference` starts with a URI scheme (`http:`, `file:`, `C:`):
/// letters, digits, `+`, `-` and `.` after a letter, then a colon.
fn has_scheme(reference: &str) -> bool {
    match reference.split_once(':') {
        Some((scheme, _)) => {
            let mut chars = scheme.chars();
            chars.next().is_some_and(|c| c.is_ascii_alphabetic())
                && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_inside_the_models_folder_are_resolved() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("sub").join("m.gltf");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        std::fs::create_dir(dir.path().join("sub").join("bin")).unwrap();
        std::fs::write(dir.path().join("sub").join("bin").join("b.bin"), [1, 2, 3]).unwrap();
        std::fs::write(dir.path().join("outside.bin"), [1]).unwrap();
        std::os::unix::fs::symlink(dir.path().join("outside.bin"), dir.path().join("sub").join("link.bin")).unwrap();
        assert!(resolve(&model, "bin/b.bin").is_ok());
        assert!(resolve(&model, "./bin/b.bin").is_ok());
        assert!(matches!(read_up_to(&model, "bin/b.bin", 2), Ok((b, true)) if b == [1, 2]));
        for (reference, why) in [
            ("/dev/zero", "leaves"),
            ("../outside.bin", "leaves"),
            ("bin/../../outside.bin", "leaves"),
            ("link.bin", "link"),
            ("http://example.com/b.bin", "URL"),
            ("file:///dev/zero", "URL"),
            ("", "empty"),
        ] {
            match resolve(&model, reference) {
                Err(Refused::Reference(e)) => assert!(e.contains(why) && e.contains(reference), "{e}"),
                _ => panic!("{reference} was not refused"),
            }
        }
        assert!(matches!(read_up_to(&model, "bin", 10), Err(Refused::Unreadable(..))), "a folder is not read");
        assert!(matches!(resolve(&model, "absent.bin"), Err(Refused::Unreadable(..))));
    }
}
