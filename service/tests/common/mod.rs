//! Helpers shared by the integration tests of `corridor-service`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A fresh, empty temporary directory, removed when dropped (also when the test fails).
pub struct TempDir(PathBuf);

impl TempDir {
    /// `corridor-{tag}` under the system's temporary directory, emptied first.
    pub fn new(tag: &str) -> Self {
        let d = std::env::temp_dir().join(format!("corridor-{tag}"));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        TempDir(d)
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
