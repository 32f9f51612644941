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
        let table: toml::Table =
            toml::from_str(text).map_err(|e| toml_err(path, toml_message(&e)))?;
        let Some(base) = table.get("base") else {
            // No layering: parsed from the text itself, so errors keep their line and column.
            return toml::from_str(text).map_err(|e| toml_err(path, toml_message(&e)));
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
            toml::from_str(&base_text).map_err(|e| toml_err(&base_path, toml_message(&e)))?;
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
            toml::from_str(&base_text).map_err(|e| toml_err(&base_path, toml_message(&e)))?;
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
                    .map_err(|e| toml_err(path, toml_message(&e)))?;
            }
            _ => {
                layer
                    .clone()
                    .try_into::<ConfigFile>()
                    .map_err(|e| toml_err(path, toml_message(&e)))?;
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
        merged
            .try_into()
            .map_err(|e| toml_err(path, toml_message(&e)))
    }
}

/// The toml crate's message for `e`, with the dotted key the error is about when it knows it:
/// ``key `eskf.gyro_noise_rad_s`: invalid type: string "abc", expected f64`` (a value of the wrong
/// type) or ``in [eskf]: unknown field `x` `` (a field of a table) under the quoted line. The
/// crate keeps the key path private and prints it (as "in `a.b`") only when it has no text to
/// quote, so it is read from the error's message without its text; a type error of a file's
/// value named its line and column but not its key (a review).
fn toml_message(e: &toml::de::Error) -> String {
    let full = e.to_string();
    let mut bare = e.clone();
    bare.set_input(None);
    let bare = bare.to_string();
    let key = bare
        .trim_end()
        .rsplit_once('\n')
        .and_then(|(_, last)| last.strip_prefix("in `")?.strip_suffix('`'));
    match key {
        // Quoted: the key is said in place of the crate's own "in" line.
        Some(key) if full != bare => match full.trim_end().strip_suffix(e.message()) {
            Some(quoted) => {
                // The path of a field's error is the table's: `in [eskf]: unknown field`.
                let message = e.message();
                if message.starts_with("unknown field") || message.starts_with("missing field") {
                    format!("{quoted}in [{key}]: {message}")
                } else {
                    format!("{quoted}key `{key}`: {message}")
                }
            }
            None => full,
        },
        _ => full,
    }
}
