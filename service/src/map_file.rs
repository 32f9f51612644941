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
    /// No corridor at all: `--map` would then take every heading observation away, silently.
    #[error("{path}: no [[corridor]]: a map needs at least one")]
    Empty {
        /// File.
        path: PathBuf,
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
    let text = corridor_shared::text_file::read_text(path).map_err(|source| MapError::Io {
        path: path.to_owned(),
        source,
    })?;
    let toml_err = |message: String| MapError::Toml {
        path: path.to_owned(),
        message,
    };
    let table: toml::Table = toml::from_str(&text).map_err(|e| toml_err(e.to_string()))?;
    // A point of three or more numbers was read as its first two (serde's fixed-size arrays
    // stop at their length; a review): said, with the corridor and the key.
    if let Some(toml::Value::Array(corridors)) = table.get("corridor") {
        for (index, c) in corridors.iter().enumerate() {
            for key in ["from_m", "to_m"] {
                if let Some(toml::Value::Array(p)) = c.get(key)
                    && p.len() != 2
                {
                    return Err(toml_err(format!(
                        "corridor {index}: {key} = {}: must be two numbers [x, y], metres",
                        toml::Value::Array(p.clone())
                    )));
                }
            }
        }
    }
    let map: CorridorMap = toml::from_str(&text).map_err(|e| toml_err(e.to_string()))?;
    if map.corridors.is_empty() {
        return Err(MapError::Empty {
            path: path.to_owned(),
        });
    }
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

    /// A corridor too narrow or too short to hold a footprint (1e-300 m), or one whose ends lie
    /// so far out (±1e308 m) that the test of a footprint inside it overflows, took every
    /// heading observation along it away without a word (a review); a width of 1e300 m made
    /// the whole plane one corridor.
    #[test]
    fn a_corridor_no_footprint_can_be_inside_or_beyond_any_survey_is_refused() {
        let dir = std::env::temp_dir().join(format!("corridor-map-g-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("map.toml");
        let read = |from: &str, to: &str, width: &str| {
            std::fs::write(
                &file,
                format!("[[corridor]]\nfrom_m = {from}\nto_m = {to}\nwidth_m = {width}\n"),
            )
            .unwrap();
            read_corridor_map(&file)
                .map(|_| ())
                .map_err(|e| e.to_string())
        };
        for (from, to, width, said) in [
            (
                "[0.0, 0.0]",
                "[10.0, 0.0]",
                "1e-300",
                "width_m = 1e-300 must be in [0.1, 1e6] m",
            ),
            (
                "[0.0, 0.0]",
                "[10.0, 0.0]",
                "1e300",
                "width_m = 1e300 must be in [0.1, 1e6] m",
            ),
            (
                "[0.0, 0.0]",
                "[1e-200, 0.0]",
                "2.0",
                "ends are 1e-200 m apart",
            ),
            ("[0.0, 0.0]", "[0.0, 0.05]", "2.0", "ends are 0.05 m apart"),
            (
                "[-1e308, 0.0]",
                "[1e308, 0.0]",
                "2.0",
                "from_m = [-1e308, 0.0], to_m = [1e308, 0.0]",
            ),
            ("[0.0, 0.0]", "[2e6, 0.0]", "2.0", "within ±1e6 m"),
        ] {
            let err = read(from, to, width).unwrap_err();
            assert!(
                err.contains("map.toml") && err.contains("corridor 0") && err.contains(said),
                "{from} {to} {width}: {err}"
            );
        }
        assert!(read("[0.0, 0.0]", "[0.0, 0.1]", "0.1").is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// An empty map, or a point with a third number, was taken without a word (a review): the
    /// one took every heading observation away, the other dropped the number.
    #[test]
    fn an_empty_map_and_a_point_of_three_numbers_are_refused() {
        let dir = std::env::temp_dir().join(format!("corridor-map-e-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("map.toml");
        let read = |text: &str| {
            std::fs::write(&file, text).unwrap();
            read_corridor_map(&file)
                .map(|_| ())
                .map_err(|e| e.to_string())
        };
        for empty in ["", "# no corridors yet\n"] {
            let err = read(empty).unwrap_err();
            assert!(
                err.contains("map.toml") && err.contains("no [[corridor]]"),
                "{err}"
            );
        }
        let err = read(
            "[[corridor]]\nfrom_m = [0.0, 0.0]\nto_m = [10.0, 0.0]\nwidth_m = 2.0\n\
             [[corridor]]\nfrom_m = [0.0, 0.0, 0.0]\nto_m = [0.0, 5.0]\nwidth_m = 2.0\n",
        )
        .unwrap_err();
        assert!(
            err.contains("corridor 1: from_m = [0.0, 0.0, 0.0]"),
            "{err}"
        );
        assert!(
            read("[[corridor]]\nfrom_m = [0.0, 0.0]\nto_m = [10.0, 0.0]\nwidth_m = 2.0\n").is_ok()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
