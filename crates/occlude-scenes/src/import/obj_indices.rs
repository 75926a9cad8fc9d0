//! Checking an OBJ file's face and line indices before `tobj` reads them.
//! `tobj` (4.0) turns an index into an offset by arithmetic that wraps for
//! indices near the integer limits (`f 1//6148914691236517206 ...` panics
//! inside it), so no index reaches it unless it names an element the file
//! has: a positive index at most the number of such elements in the file, a
//! negative (relative) one at most the number defined before its line, and
//! never 0.

/// The kinds of element a face vertex indexes, in the order of its
/// `v/vt/vn` slots: the keyword that defines one, its name and their name.
const KINDS: [(&str, &str, &str); 3] =
    [("v", "vertex", "vertices"), ("vt", "texture coordinate", "texture coordinates"), ("vn", "normal", "normals")];

/// Checks every index of the `f` and `l` lines of OBJ `text` as the module
/// says; the error names the line, the index and how many elements there
/// are. Lines are split as `tobj` splits them; a token that is not a whole
/// number is left for `tobj` to reject.
pub(super) fn check(text: &str) -> Result<(), String> {
    let mut total = [0u64; 3];
    for line in text.lines() {
        if let Some(kind) = defined_kind(line) {
            total[kind] += 1;
        }
    }
    let mut before = [0u64; 3];
    for (number, line) in text.lines().enumerate() {
        if let Some(kind) = defined_kind(line) {
            before[kind] += 1;
            continue;
        }
        let mut words = line.split_whitespace();
        if !matches!(words.next(), Some("f" | "l")) {
            continue;
        }
        for vertex in words {
            for (slot, index) in vertex.split('/').enumerate().take(KINDS.len()) {
                let Ok(index) = index.parse::<i64>() else { continue };
                let (_, name, names) = KINDS[slot];
                let fits = match index {
                    0 => false,
                    i if i > 0 => i.unsigned_abs() <= total[slot],
                    i => i.unsigned_abs() <= before[slot],
                };
                if !fits {
                    let (count, whence) = if index < 0 { (before[slot], " before it") } else { (total[slot], "") };
                    return Err(format!(
                        "line {}: {name} index {index} is out of range: the file has {count} {names}{whence} \
                         (indices count from 1, or back from -1)",
                        number + 1
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Which kind of element `line` defines (an index into [`KINDS`]), if any.
fn defined_kind(line: &str) -> Option<usize> {
    let keyword = line.split_whitespace().next()?;
    KINDS.iter().position(|&(k, _, _)| k == keyword)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_index_names_an_element_the_file_has() {
        let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n";
        check(&format!("{triangle}f 1//1 2//1 3//1\nf -3//-1 -2//1 -1//1\nl 1 2\n")).unwrap();
        // Forward references are tobj's to judge; they cannot wrap.
        check("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        for (faces, names) in [
            ("f 1//6148914691236517206 2//1 3//1", "line 5: normal index 6148914691236517206"),
            ("f 1//1 2//1 3//-2", "normal index -2 is out of range: the file has 1 normals before it"),
            ("f 0 1 2", "vertex index 0"),
            ("f 1/1/1 2 3", "texture coordinate index 1"),
            ("l 1 -9223372036854775808", "vertex index -9223372036854775808"),
            ("f 1 2 4", "the file has 3 vertices"),
        ] {
            let e = check(&format!("{triangle}{faces}\n")).unwrap_err();
            assert!(e.contains(names), "{e}");
        }
    }
}
