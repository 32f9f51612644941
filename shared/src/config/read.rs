//! Reading a configuration file: TOML into [`ConfigFile`], and a layer over its `base`.

use super::*;
use std::path::Path;

impl ConfigFile {
    /// Reads and parses a TOML file (no validation yet).
    pub fn read(path: &Path) -> Result<Self, ConfigError> {
        let text = crate::text_file::read_text(path).map_err(|source| ConfigError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses TOML text; `path` names the source in errors and anchors a `base`.
    ///
    /// A top-level `base = "FILE"` (relative to this file's directory) layers this file over
    /// another: the base is read first, and every key this file sets replaces the base's (a
    /// daemon file is the sensor's file plus a `[daemon]` section, without copying it). One
    /// level only: a base may not have a base.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let toml_err = |p: &Path, message: String| ConfigError::Toml {
            path: p.to_owned(),
            message,
        };
        let table: toml::Table = toml::from_str(text).map_err(|e| toml_err(path, e.to_string()))?;
        let Some(base) = table.get("base") else {
            // No layering: parsed from the text itself, so errors keep their line and column.
            return toml::from_str(text).map_err(|e| toml_err(path, e.to_string()));
        };
        let Some(name) = base.as_str() else {
            return Err(with_path(
                invalid("base", base, "must be a file name (a string)"),
                path,
            ));
        };
        let base_path = path.parent().unwrap_or(Path::new(".")).join(name);
        // Named from the file that names it: the base's own path alone did not say where it
        // was asked for.
        let base_text = crate::text_file::read_text(&base_path).map_err(|e| {
            toml_err(
                path,
                format!("base = {name:?}: cannot read {}: {e}", base_path.display()),
            )
        })?;
        let mut merged: toml::Table =
            toml::from_str(&base_text).map_err(|e| toml_err(&base_path, e.to_string()))?;
        if let Some(inner) = merged.get("base") {
            // Said from the file that names it, with the base's own `base` (it showed this
            // file's value under the base's name, a review).
            return Err(toml_err(
                path,
                format!(
                    "base = {name:?}: {} names a base itself (base = {inner}); one level of \
                     layering only: name a file without a base",
                    base_path.display()
                ),
            ));
        }
        // The base alone first, so that its own errors (unknown keys with their line, values out
        // of range) name it rather than the layer.
        let alone: ConfigFile =
            toml::from_str(&base_text).map_err(|e| toml_err(&base_path, e.to_string()))?;
        alone.validate().map_err(|e| with_path(e, &base_path))?;
        // The layer alone too (without its `base`), for its unknown keys and wrong types: parsed
        // from its text with the `base` line blanked, so that the error keeps its line and
        // column (from the table it had neither, a review); from the table when `base` is not
        // on a line of its own.
        let mut layer = table;
        layer.remove("base");
        let blanked: String = text
            .lines()
            .map(|l| {
                if l.trim_start().starts_with("base") && l.contains('=') {
                    ""
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        match toml::from_str::<toml::Table>(&blanked) {
            Ok(t) if t == layer => {
                toml::from_str::<ConfigFile>(&blanked)
                    .map_err(|e| toml_err(path, e.to_string()))?;
            }
            _ => {
                layer
                    .clone()
                    .try_into::<ConfigFile>()
                    .map_err(|e| toml_err(path, e.to_string()))?;
            }
        }
        for (section, value) in layer {
            match (merged.get_mut(&section), value) {
                (Some(toml::Value::Table(into)), toml::Value::Table(keys)) => into.extend(keys),
                (_, value) => {
                    merged.insert(section, value);
                }
            }
        }
        merged.try_into().map_err(|e| toml_err(path, e.to_string()))
    }
}
