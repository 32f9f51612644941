//! Corridor map files: TOML with `[[corridor]]` tables, read and checked here so that the core
//! ([`crate::core::heading`]) only ever sees a checked [`CorridorMap`] and does no IO.

use crate::core::heading::{CorridorMap, GeometryError};
use std::path::{Path, PathBuf};

/// A map that could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// IO error.
    #[error("{path}: cannot read map: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML error (names the key).
    #[error("{path}: {message}")]
    Toml {
        /// File.
        path: PathBuf,
        /// Parser message.
        message: String,
    },
    /// A corridor with a bad geometry.
    #[error("{path}: {source}")]
    Geometry {
        /// File.
        path: PathBuf,
        /// What is wrong, and where.
        source: GeometryError,
    },
}

/// Reads and checks a map file.
pub fn read_corridor_map(path: &Path) -> Result<CorridorMap, MapError> {
    let text = std::fs::read_to_string(path).map_err(|source| MapError::Io {
        path: path.to_owned(),
        source,
    })?;
    let map: CorridorMap = toml::from_str(&text).map_err(|e| MapError::Toml {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    map.check().map_err(|source| MapError::Geometry {
        path: path.to_owned(),
        source,
    })?;
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_corridor_is_named_with_the_file() {
        let dir = std::env::temp_dir().join(format!("corridor-map-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("map.toml");
        std::fs::write(
            &file,
            "[[corridor]]\nname = \"a\"\nfrom_m = [0.0, 0.0]\nto_m = [10.0, 0.0]\nwidth_m = 2.0\n\
             [[corridor]]\nname = \"b\"\nfrom_m = [0.0, 0.0]\nto_m = [0.0, 5.0]\nwidth_m = -1.0\n",
        )
        .unwrap();
        let err = read_corridor_map(&file).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            err.contains("map.toml") && err.contains("corridor 1 (\"b\")"),
            "{err}"
        );
        assert!(err.contains("width_m = -1 must be > 0"), "{err}");
        assert!(matches!(
            read_corridor_map(&dir.join("missing.toml")),
            Err(MapError::Io { .. })
        ));
    }
}
