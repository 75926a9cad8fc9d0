//! Checking the files a command will write before it starts, so that a typo
//! in `--json` is reported at once instead of after a long run.

use std::path::{Path, PathBuf};

/// Parses the path of a file to be written (a clap `value_parser`): it must
/// not be a folder, and the folder it goes in must exist. Whether the file
/// can really be created is only known when it is, at the end of the run.
pub fn parse_output_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if s.is_empty() {
        return Err("the path is empty".into());
    }
    if path.is_dir() {
        return Err(format!("{s} is a folder, not a file"));
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(format!("the folder {} does not exist", folder.display()));
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_in_an_existing_folder_is_accepted_and_others_are_refused() {
        let dir = std::env::temp_dir();
        let file = dir.join("occlude-output-path-test.json");
        assert_eq!(parse_output_path(file.to_str().unwrap()), Ok(file.clone()));
        assert_eq!(parse_output_path("report.json"), Ok(PathBuf::from("report.json")));

        let missing = dir.join("occlude-no-such-folder").join("x.json");
        let err = parse_output_path(missing.to_str().unwrap()).unwrap_err();
        assert!(err.contains("occlude-no-such-folder") && err.contains("does not exist"), "{err}");

        let err = parse_output_path(dir.to_str().unwrap()).unwrap_err();
        assert!(err.contains("is a folder"), "{err}");
        assert!(parse_output_path("").is_err());
    }
}
