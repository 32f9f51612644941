//! Reading the small text files a command is given (a configuration, a map, a suite, a ground
//! truth), no further than such a file can be long.

use std::io::Read as _;
use std::path::Path;

/// Longest text file [`read_text`] reads, bytes (16 MiB: the shipped configuration is 39 KB, a
/// ground truth 5 KB).
pub const MAX_TEXT_FILE_BYTES: u64 = 16 << 20;

/// Reads the UTF-8 text file at `path`, as [`std::fs::read_to_string`] but for one longer than
/// [`MAX_TEXT_FILE_BYTES`]: an [`std::io::ErrorKind::InvalidData`] error that says so. A path to
/// something else than the file meant was read whole into memory: `--config /dev/zero` (or
/// `--map`, `--truth`, a suite, a `base`) aborted with "memory allocation failed".
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_TEXT_FILE_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_TEXT_FILE_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("longer than {MAX_TEXT_FILE_BYTES} bytes: not a text file this reads"),
        ));
    }
    String::from_utf8(bytes).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// Why `path` (followed through links) is not a file a command can read, or `None` when it is
/// one: "no such file", "is a directory, not a file", "is not a regular file" (a FIFO, a
/// device), or the OS error (no permission to look). An existing directory was reported as
/// "no such file".
pub fn not_a_file(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => None,
        Ok(m) if m.is_dir() => Some("is a directory, not a file".to_owned()),
        Ok(_) => Some("is not a regular file".to_owned()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some("no such file".to_owned()),
        Err(e) => Some(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_not_a_file_says_what_it_is() {
        let dir = std::env::temp_dir().join(format!("corridor-not-a-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("f.txt");
        std::fs::write(&file, "x").unwrap();
        assert_eq!(not_a_file(&file), None);
        assert_eq!(
            not_a_file(&dir).as_deref(),
            Some("is a directory, not a file")
        );
        assert_eq!(
            not_a_file(&dir.join("nope")).as_deref(),
            Some("no such file")
        );
        assert_eq!(
            not_a_file(Path::new("/dev/null")).as_deref(),
            Some("is not a regular file")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_without_an_end_is_refused_after_its_bound() {
        let err = read_text(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidData);
        assert!(
            err.to_string().contains("longer than 16777216 bytes"),
            "{err}"
        );
        let err = crate::config::Config::from_file(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("/dev/zero: cannot read config: longer than"),
            "{err}"
        );
        let err = crate::truth_csv::read_truth_csv(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("/dev/zero") && err.contains("longer than"),
            "{err}"
        );
    }
}
