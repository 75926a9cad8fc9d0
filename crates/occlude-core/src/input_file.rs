//! Reading the files a user names (models, their buffers and materials,
//! camera paths, GPU models, reports) so that what is read is bounded by the
//! file: only regular files are read (a device such as `/dev/zero`, a pipe
//! or a folder is refused before anything is read), and never more than a
//! limit the caller states, so no file can make a reader allocate without
//! bound.

use std::io::{self, Read};
use std::path::Path;

/// The bytes of the regular file `path`, which may hold at most `limit`
/// bytes: a larger file, or one that is not a regular file, is an error
/// saying so (the caller names the file).
pub fn read(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let (bytes, more) = read_up_to(path, limit)?;
    if more {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("it is larger than the {limit} bytes allowed for this file"),
        ));
    }
    Ok(bytes)
}

/// The first `limit` bytes of the regular file `path` (all of it when it is
/// shorter), and whether it holds more.
pub fn read_up_to(path: &Path, limit: u64) -> io::Result<(Vec<u8>, bool)> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "it is not a regular file (a folder, device or pipe is not read)",
        ));
    }
    let file = std::fs::File::open(path)?;
    // The file's size bounds the allocation; a file growing meanwhile is
    // still cut at `limit` plus the one byte that tells there is more.
    let mut bytes = Vec::with_capacity(metadata.len().min(limit) as usize);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    let more = bytes.len() as u64 > limit;
    bytes.truncate(limit.min(bytes.len() as u64) as usize);
    Ok((bytes, more))
}

/// The UTF-8 text of the regular file `path` of at most `limit` bytes,
/// without a leading byte-order mark (which some editors write and every
/// text reader here accepts alike).
pub fn read_text(path: &Path, limit: u64) -> io::Result<String> {
    let text = String::from_utf8(read(path, limit)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("it is not UTF-8 text ({e})")))?;
    Ok(strip_bom(&text).to_string())
}

/// `text` without a leading UTF-8 byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_are_read_and_never_past_the_limit() {
        let dir = std::env::temp_dir().join(format!("occlude-input-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("ten.txt");
        std::fs::write(&file, "\u{feff}123456789").unwrap();
        assert_eq!(read(&file, 12).unwrap().len(), 12);
        let e = read(&file, 11).unwrap_err();
        assert!(e.to_string().contains("larger than the 11 bytes"), "{e}");
        assert_eq!(read_up_to(&file, 4).unwrap(), (b"\xef\xbb\xbf1".to_vec(), true));
        assert_eq!(read_text(&file, 100).unwrap(), "123456789");
        for not_a_file in [dir.as_path(), Path::new("/dev/zero")] {
            let e = read(not_a_file, 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
