//! Checking the files a command will write before it starts, so that a typo
//! in `--json` is reported at once instead of after a long run, and so that
//! no output overwrites one of the command's inputs or another output.

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

/// A file a command reads or writes, named by its option for errors
/// (`"--json"`, `"--scene"`); `None` when the option is not given.
pub type NamedPath<'a> = (&'a str, Option<&'a Path>);

/// Checks that no two `outputs` name the same file and that no output names
/// one of the `inputs` (paths compared once resolved: `./a.json` and
/// `a.json` are the same file, and so are two links to it); the error names
/// both options.
pub fn check_distinct(outputs: &[NamedPath], inputs: &[NamedPath]) -> Result<(), String> {
    let resolved = |list: &[NamedPath<'_>]| -> Vec<(String, PathBuf)> {
        list.iter().filter_map(|(option, path)| path.map(|p| (option.to_string(), resolve(p)))).collect()
    };
    let (outputs, inputs) = (resolved(outputs), resolved(inputs));
    for (i, (option, path)) in outputs.iter().enumerate() {
        if let Some((other, _)) = outputs[..i].iter().find(|(_, p)| p == path) {
            return Err(format!("{other} and {option} name the same file {}: name two files", path.display()));
        }
        if let Some((input, _)) = inputs.iter().find(|(_, p)| p == path) {
            return Err(format!(
                "{option} {} is the file {input} reads: writing it would overwrite the input; name another file",
                path.display()
            ));
        }
    }
    Ok(())
}

/// `path` with its links and `.` and `..` resolved, as far as it exists:
/// a file not yet written resolves through its folder.
fn resolve(path: &Path) -> PathBuf {
    if let Ok(resolved) = path.canonicalize() {
        return resolved;
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (folder.canonicalize(), path.file_name()) {
        (Ok(folder), Some(name)) => folder.join(name),
        _ => path.to_path_buf(),
    }
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

    /// An output naming an input, or two outputs naming one file, however
    /// each is spelled, is refused naming both options.
    #[test]
    fn outputs_are_distinct_from_each_other_and_from_the_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("a.json");
        std::fs::write(&input, "{}").unwrap();
        let spelled_otherwise = dir.path().join(".").join("a.json");
        let out = dir.path().join("out.html");
        let md = dir.path().join("out.md");
        check_distinct(&[("--out", Some(&out)), ("--markdown", Some(&md))], &[("FILE", Some(&input))]).unwrap();
        check_distinct(&[("--out", Some(&out)), ("--markdown", None)], &[("FILE", None)]).unwrap();
        let e = check_distinct(&[("--out", Some(&spelled_otherwise))], &[("FILE", Some(&input))]).unwrap_err();
        assert!(e.contains("--out") && e.contains("FILE") && e.contains("overwrite"), "{e}");
        let twice = dir.path().join("sub").join("..").join("out.html");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let e = check_distinct(&[("--json", Some(&out)), ("--csv", Some(&twice))], &[]).unwrap_err();
        assert!(e.contains("--json and --csv name the same file"), "{e}");
    }
}
