//! Helpers shared by the integration tests of `corridor-service`.
#![allow(dead_code)]

pub mod cli;

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

/// Writes a log of `rows` rows to `out`: the rows of the IMU log `src` over and over, each
/// repetition shifted in time to follow the last one by one sample period (a long walk made of
/// one recording, for memory and throughput figures).
pub fn repeat_log(src: &Path, rows: u64, out: &Path) {
    use std::io::Write;
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let body: Vec<(f64, &str)> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let (t, rest) = l.split_once(',').unwrap();
            (t.parse::<f64>().unwrap(), rest)
        })
        .collect();
    let n = body.len();
    let period_s = body[n - 1].0 - body[0].0 + (body[n - 1].0 - body[n - 2].0);
    let mut w = std::io::BufWriter::new(std::fs::File::create(out).unwrap());
    writeln!(w, "{header}").unwrap();
    for k in 0..rows {
        let rep = k / n as u64;
        let (t, rest) = body[(k % n as u64) as usize];
        writeln!(w, "{},{rest}", t + rep as f64 * period_s).unwrap();
    }
    w.flush().unwrap();
}
